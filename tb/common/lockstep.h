// SPDX-License-Identifier: MIT
// Lockstep: one Verilated module and its golden model get the same inputs every
// cycle; every output is compared on every cycle. On the first mismatch it
// replays the recorded stimulus into a fresh, traced RTL instance to leave an FST
// waveform, and throws LockstepMismatch naming the cycle, the signal, the model's
// (expected) and the RTL's (actual) value, and the waveform's path.
//
// Waveforms go to $CPSTEP_WAVE_DIR (default: the working directory), named after
// the running GoogleTest test when there is one. The replay needs every input
// since construction; past `max_history` cycles the fixture stops recording and a
// mismatch is reported without a waveform, so long sweeps use a fixture per batch.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/dut.h"

namespace cpstep::tb {

struct LockstepMismatch : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline std::string wave_path(const std::string& stem) {
  const char* dir = std::getenv("CPSTEP_WAVE_DIR");
  std::filesystem::path p = dir ? dir : ".";
  std::filesystem::create_directories(p);
  std::string name = stem;
  if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
    name = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : name)
    if (c == '/' || c == ' ') c = '_';
  return (p / (name + ".fst")).string();
}

template <class P>
class Lockstep {
 public:
  using In = typename P::In;
  using Out = typename P::Out;

  explicit Lockstep(std::string name = "lockstep", size_t max_history = 4'000'000)
      : name_(std::move(name)), max_history_(max_history) {}

  // One clock: same inputs to both, compare, rising edge. Returns the outputs.
  Out step(const In& in) {
    if (stimulus_.size() < max_history_) stimulus_.push_back(in);
    else recording_ = false;
    const Out want = model_.step(in);
    const Out got = rtl_.step(in);
    for (const auto& f : P::fields()) {
      const uint64_t e = f.get(want), a = f.get(got);
      if (e != a) fail(f.name, e, a);
    }
    return got;
  }

  // `cycles` clocks with the inputs `in`, for a model stepper that advances many
  // at once (the fast engine: sim::FastCardDut::advance): the RTL steps through
  // every cycle of each span the model takes at once and is compared in each. In
  // a span of several cycles the model's outputs are those of its first cycle for
  // every output the span holds (P::span_holds(name): all but MISO inside a frame).
  template <class OnSpan>
    requires requires(typename sim::ModelStepperOf<P>::type& m, const In& i) {
      m.advance(i, uint64_t(1), [](uint64_t, uint64_t, const Out&) {});
    }
  void advance(const In& in, uint64_t cycles, OnSpan&& on_span) {
    model_.advance(in, cycles, [&](uint64_t c, uint64_t n, const Out& want) {
      for (uint64_t i = 0; i < n; ++i) {
        if (stimulus_.size() < max_history_) stimulus_.push_back(in);
        else recording_ = false;
        const Out got = rtl_.step(in);
        for (const auto& f : P::fields()) {
          if (i > 0 && !P::span_holds(f.name)) continue;
          const uint64_t e = f.get(want), a = f.get(got);
          if (e != a) fail(f.name, e, a);
        }
      }
      on_span(c, n, want);
    });
  }

  // A whole SPI transfer's pin schedule (sim::SpiPhase: pins, cycles, sample),
  // for a model stepper that takes one at once (sim::FastCardDut::run_phases: the
  // front end alone, several phases to a span): the RTL steps through every cycle
  // with each phase's pins and is compared in each as advance() does, and the
  // MISO the model gives for each phase's first cycle (`sampled`, 1 when
  // undriven: what the master samples) is compared with the RTL's there.
  template <class Phase, class OnSpan>
    requires requires(typename sim::ModelStepperOf<P>::type& m, const std::vector<Phase>& ph,
                      std::vector<uint8_t>& s) {
      m.run_phases(ph, s, [](uint64_t, uint64_t, const In&, const Out&) {});
    }
  void run_phases(const std::vector<Phase>& phases, std::vector<uint8_t>& sampled, OnSpan&& on_span) {
    size_t p = 0;
    uint64_t into = 0;  // cycles of phase p done
    model_.run_phases(phases, sampled, [&](uint64_t c, uint64_t n, const In& pins, const Out& want) {
      for (uint64_t i = 0; i < n; ++i) {
        while (into == phases[p].cycles) {
          ++p;
          into = 0;
        }
        const In& in = phases[p].pins;
        if (stimulus_.size() < max_history_) stimulus_.push_back(in);
        else recording_ = false;
        const Out got = rtl_.step(in);
        if (into++ == 0) {
          const bool rtl_miso = !got.miso_oe || got.miso;
          if (sampled[p] != uint8_t(rtl_miso)) fail("spi_miso_o (as sampled)", sampled[p], rtl_miso);
        }
        for (const auto& f : P::fields()) {
          if (i > 0 && !P::span_holds(f.name)) continue;
          const uint64_t e = f.get(want), a = f.get(got);
          if (e != a) fail(f.name, e, a);
        }
      }
      on_span(c, n, pins, want);
    });
  }

  // Synchronous reset for `cycles` clocks (compared like any other cycle).
  void reset(unsigned cycles = 2) {
    In in{};
    in.rst = true;
    for (unsigned i = 0; i < cycles; ++i) step(in);
  }

  uint64_t cycle() const { return rtl_.cycle(); }
  typename P::Model& model() { return model_.model(); }
  // The model's stepper (ModelDut, or SkippingModelDut: sim::ModelStepperOf).
  const auto& model_stepper() const { return model_; }

 private:
  [[noreturn]] void fail(const char* signal, uint64_t expected, uint64_t actual) {
    const uint64_t cycle = rtl_.cycle();
    std::ostringstream m;
    m << "lockstep mismatch at cycle " << cycle << ": signal " << signal << " expected (model) "
      << expected << ", actual (rtl) " << actual;
    if (!recording_) {
      m << "; no waveform: more than " << max_history_ << " cycles since the fixture was made";
      throw LockstepMismatch(m.str());
    }
    const std::string path = wave_path(name_);
    {
      sim::RtlDut<P> traced(path);
      for (const In& in : stimulus_) traced.step(in);
      In idle = stimulus_.back();
      for (int i = 0; i < 4; ++i) traced.step(idle);  // a little context after
    }
    m << "; waveform: " << path << " (cycle n spans time 2n..2n+1)";
    throw LockstepMismatch(m.str());
  }

  std::string name_;
  typename sim::ModelStepperOf<P>::type model_;
  sim::RtlDut<P> rtl_;
  size_t max_history_;
  bool recording_ = true;
  std::vector<In> stimulus_;
};

// Checks the valid/ready contract of one stream, cycle by cycle: valid never
// drops and data never changes while a transfer is pending (valid && !ready).
class StreamContract {
 public:
  explicit StreamContract(std::string name) : name_(std::move(name)) {}
  void check(uint64_t cycle, bool valid, bool ready, uint64_t data) {
    if (pending_) {
      if (!valid)
        ADD_FAILURE() << name_ << ": valid dropped without a transfer at cycle " << cycle;
      else if (data != data_)
        ADD_FAILURE() << name_ << ": data changed while stalled at cycle " << cycle << " ("
                      << data_ << " -> " << data << ")";
    }
    pending_ = valid && !ready;
    data_ = data;
  }

 private:
  std::string name_;
  bool pending_ = false;
  uint64_t data_ = 0;
};

}  // namespace cpstep::tb
