// SPDX-License-Identifier: MIT
#include "sim/vcd_writer.h"

#include <stdexcept>

namespace cpstep::sim {

namespace {

// Identifier codes: base-94 numbers in the printable characters '!'..'~'.
std::string id_code(size_t n) {
  std::string s;
  do {
    s.push_back(char('!' + n % 94));
    n /= 94;
  } while (n != 0);
  return s;
}

}  // namespace

VcdWriter::VcdWriter(std::ostream& out, std::string timescale, std::string scope)
    : out_(out), timescale_(std::move(timescale)), scope_(std::move(scope)) {}

int VcdWriter::add_signal(const std::string& name, unsigned width) {
  if (started_) throw std::logic_error("VcdWriter: signal added after the first sample");
  if (width < 1 || width > 64) throw std::invalid_argument("VcdWriter: width must be 1..64");
  signals_.push_back({name, id_code(signals_.size()), width});
  return int(signals_.size() - 1);
}

void VcdWriter::set(int signal, uint64_t value) {
  Signal& s = signals_.at(size_t(signal));
  s.value = s.width == 64 ? value : value & ((uint64_t(1) << s.width) - 1);
}

void VcdWriter::write_value(const Signal& s) {
  if (s.width == 1) {
    out_ << (s.value ? '1' : '0') << s.code << '\n';
    return;
  }
  out_ << 'b';
  for (unsigned b = s.width; b-- > 0;) out_ << ((s.value >> b & 1) ? '1' : '0');
  out_ << ' ' << s.code << '\n';
}

void VcdWriter::sample(uint64_t time) {
  if (!started_) {
    out_ << "$timescale " << timescale_ << " $end\n";
    out_ << "$scope module " << scope_ << " $end\n";
    for (const Signal& s : signals_)
      out_ << "$var wire " << s.width << ' ' << s.code << ' ' << s.name << " $end\n";
    out_ << "$upscope $end\n$enddefinitions $end\n";
    out_ << '#' << time << "\n$dumpvars\n";
    for (Signal& s : signals_) {
      write_value(s);
      s.written = s.value;
    }
    out_ << "$end\n";
    started_ = true;
    last_time_ = time;
    return;
  }
  if (time < last_time_) throw std::logic_error("VcdWriter: time went backwards");
  bool stamped = false;
  for (Signal& s : signals_) {
    if (s.value == s.written) continue;
    if (!stamped) {
      out_ << '#' << time << '\n';
      stamped = true;
    }
    write_value(s);
    s.written = s.value;
  }
  last_time_ = time;
}

uint64_t cycle_start_ps(uint64_t cycle, uint64_t clock_hz) {
  __extension__ using u128 = unsigned __int128;
  return uint64_t((u128(cycle) * 1'000'000'000'000u + clock_hz / 2) / clock_hz);
}

}  // namespace cpstep::sim
