// SPDX-License-Identifier: MIT
// docs/PROTOCOL.md's worked example: frames from the host codec, sent through the
// pin-level SPI master to the Verilated card (4 axes), printed with the replies.
//   build/tb/spi/spi_example
#include <cstdio>
#include <string>
#include <vector>

#include "card/frame.h"
#include "card/protocol.h"
#include "sim/card_configs.h"
#include "sim/spi_master.h"

namespace {

using namespace cpstep;

std::string hex(const std::vector<uint8_t>& b, size_t from, size_t to) {
  std::string s;
  char buf[4];
  for (size_t i = from; i < to && i < b.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%02X", b[i]);
    s += (i > from ? (((i - from) % 16 == 0) ? "\n      " : " ") : "") + std::string(buf);
  }
  return s;
}

void show(const char* what, const std::vector<uint8_t>& mosi, size_t frame_len, const std::vector<uint8_t>& miso) {
  const card::Reply r = card::decode_reply(miso, 4);
  std::printf("%s: %zu frame bytes, %zu clocked\n", what, frame_len, mosi.size());
  std::printf("MOSI  %s\n", hex(mosi, 0, frame_len).c_str());
  std::printf("MISO  %s\n", hex(miso, 0, card::reply_bytes(4)).c_str());
  std::printf("reply: last_seq %u, last_result %u (%s), flags 0x%02X, free %u, reads %u, status 0x%08X, "
              "last_read 0x%08X, CRC %s\n\n",
              r.last_seq, r.last_result, card::frame_result_name(r.last_result).name, r.flags, r.free_words,
              r.reads, r.status, r.last_read, r.crc_ok ? "ok" : "BAD");
}

}  // namespace

int main() {
  sim::RtlDut<sim::CardDefault> dut;
  sim::SpiMaster<sim::RtlDut<sim::CardDefault>> spi(dut);
  spi.reset();
  const size_t reply = card::reply_bytes(4);

  const auto poll = card::encode_poll(0x01, 4);
  show("POLL, seq 0x01", poll, card::frame_bytes(0), spi.transfer(poll));

  std::vector<uint32_t> words;
  card::encode_drivers(true, words);
  card::encode_read(card::Register::id, 0, words);
  const auto cmds = card::encode_frame(card::FrameType::commands, 0x02, words, reply);
  show("COMMANDS, seq 0x02: CONTROL drivers on, READ 0x1F", cmds, card::frame_bytes(words.size()),
       spi.transfer(cmds));

  const auto poll3 = card::encode_poll(0x03, 4);
  show("POLL, seq 0x03", poll3, card::frame_bytes(0), spi.transfer(poll3));
  return 0;
}
