// SPDX-License-Identifier: MIT
// cp_conic_serial — cycle-accurate, bit-exact model of rtl/cp_conic_serial.v: the
// motion core's bit-serial conic walker (docs/CONIC.md "The walk, bit-serial").
//
// Written from docs/CONIC.md, not from the RTL. The RTL turns G and its gradient
// through shift registers one bit a clock; nothing of a pass is visible at the
// ports until its last bit, so this model keeps the values whole and does a pass's
// arithmetic at its last bit, modulo 2^IW as the serial adders do.
#pragma once

#include <array>
#include <cstdint>

#include "model/cp_conic.h"
#include "model/cp_div.h"

namespace cpstep::model {

struct CpConicSerialParams {
  unsigned qw = 16;  // signed width of A, B, C (at most 16: a word carries two)
  unsigned iw = 40;  // width of G, its gradient and the evaluations (modulo 2^IW)
  unsigned xw = 24;  // signed width of the end node's offset from the start node (at most 24)
  // Each move's length by the conic length rule (len_k, len): rtl/cp_conic_serial.v's LEN.
  bool len = false;
};

struct CpConicSerialIn {
  bool rst = false;
  bool clear = false;
  // One word of the conic (rtl/cp_conic_serial.v, docs/CORE.md "CONIC"): 0: B, A;
  // 1: clockwise [31], C; 2, 3, 4: G, Gx, Gy (32 bits); 5, 6: du, dv ([23:0]).
  bool wr = false;
  unsigned wr_sel = 0;
  uint32_t wr_data = 0;
  bool start = false;
  // With start: go on from where the last walk ended (its last move, kept since, is
  // applied by the first pass): only words 5, 6 need be written.
  bool cont = false;
  bool move_ready = false;
  // len: the walk's length rule {S [31:27], K [26:0]}, held while len_go says its
  // segment is loaded (a division starts only then).
  uint32_t len_k = 0;
  bool len_go = false;
};

struct CpConicSerialOut {
  bool busy = false;
  bool move_valid = false;
  int move_dx = 0, move_dy = 0;  // in {-1, 0, 1}; 0 while not valid
  bool move_end = false;
  // len: the presented move's length (Q2.30).
  uint32_t len = 0;
};

class CpConicSerial {
 public:
  using Params = CpConicSerialParams;
  using In = CpConicSerialIn;
  using Out = CpConicSerialOut;

  explicit CpConicSerial(CpConicSerialParams params = {});

  CpConicSerialIn in;

  CpConicSerialOut outputs() const;
  void tick();

  const CpConicSerialParams& params() const { return p_; }
  // No pass is running and none will start by itself: idle, or a decided move
  // waiting behind the one presented. Until an input changes (a word, start,
  // clear, reset, or the presented move taken) the walker's state stays as it is.
  // (len: a division runs only while a decided move waits with nothing presented;
  // such a move also holds still while its segment is not loaded, len_go false.)
  bool quiet(bool len_go = true) const {
    const CpDivOut dv = div_.outputs();
    return !r_.pass && (!r_.pend || r_.ov || (p_.len && !len_go && !dv.busy && !dv.done));
  }

  // The move from a node, docs/CONIC.md "The rule", with every value taken modulo
  // 2^iw as the walker's adders take them: CpConic::rule for any walk whose values
  // fit (the host checks that they do: `fits`).
  static void rule(const CpConic::Coeffs& k, const CpConic::Node& n, bool cw, unsigned iw, int& dx,
                   int& dy);
  // Do a node's G, gradient and both evaluations of every quadrant fit iw bits?
  static bool fits(const CpConic::Coeffs& k, const CpConic::Node& n, unsigned iw);
  // The seven words that load a walk (the wr_sel order above): the conic's A, B, C
  // (16 bits each), the start node's G and gradient (32 bits each), the end minus the
  // start (24 bits each). The caller checks that the values fit.
  static std::array<uint32_t, 7> words(const CpConic::Coeffs& k, const CpConic::Node& start, bool cw,
                                       int64_t du, int64_t dv);
  // The length rule's divisor at a node as the walker takes it: the larger of |Gx|
  // and |Gy| (modulo 2^iw, as its serial comparisons see them; Gx on a tie), given
  // to the divider as v ^ sign and the sign (the magnitude is their sum).
  static void rule_divisor(const CpConic::Node& n, unsigned iw, uint64_t& d, bool& inc);

 private:
  struct Regs {
    // Control (reset).
    bool pass = false, pend = false, ov = false;
    // Datapath.
    unsigned i = 0;
    CpConic::Coeffs k;       // a, b, c used
    CpConic::Node n;         // the current node (at a pass's end: the new one)
    bool cw = false;
    int64_t du = 0, dv = 0;  // the end node minus the current node (modulo 2^XW)
    int mdx = 0, mdy = 0;    // the move the next pass applies
    int odx = 0, ody = 0;
    bool oend = false;
    // len: the divisor of the node the last pass computed (v ^ sign, sign).
    uint64_t ld = 0;
    bool linc = false;
  };

  CpConicSerialParams p_;
  Regs r_;
  CpDiv div_;
};

}  // namespace cpstep::model
