// SPDX-License-Identifier: MIT
// cp_engine — Castle–Pitteway move-string engine for one (major, minor) axis pair.
//
// Accepts (u, v, k, rep) on a valid/ready handshake, grows the register pair
// M1/M2 with Euclid's subtractive loop and swap-and-reverse, then streams the
// pattern M2·reverse(M1) replayed x·2^k·rep times (x = gcd(u, v) when the loop
// ends) as a valid/ready stream of moves: 1 = diagonal (major and minor step),
// 0 = axial (major only). Exactly u·2^k·rep moves are emitted.
//
// Storage (docs/ENGINE.md): each register is a 1-bit-wide memory of 2^AW bits
// holding a circular window [lo, lo+len) and a direction flag rev; the logical
// string is the window read forward (rev=0) or backward (rev=1). Reversal flips
// the flag; "M = S + reverse(M)" flips M's flag, then prepends S's bits, last bit
// first, one bit per clock (the seed paper's serial transfer, Figure 6). The read
// of the source is synchronous (block RAM), its write lands one clock later, and
// consecutive iterations overlap, so a build costs one clock per copied bit:
// u/gcd(u,v) - 2 clocks in all.
//
// Valid/ready contract (docs/ENGINE.md): a transfer happens on a rising edge
// where valid && ready; valid never waits for ready; while valid && !ready the
// data holds.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_engine #(
    // Pattern capacity: the longest pattern u/gcd(u, v) the registers hold.
    parameter integer W = 1024,
    // Largest u accepted. With UMAX > W, u/gcd(u, v) > W is found during the
    // build and refused then (ERR_PATTERN_GT_W), before any move.
    parameter integer UMAX = W,
    // Largest step-doubling exponent k accepted.
    parameter integer KMAX = 8,
    // Width of the replay multiplier rep (rep >= 1).
    parameter integer RW = 16,
    // 1: the motion core's mode. The caller has validated the request (u, v, k
    // and rep are not checked; only a pattern longer than W is refused), and one
    // period of the pattern is all it takes: the stream ends with the first
    // M2·reverse(M1) (move_last_o with move_pend_o), whatever x, k and rep.
    parameter integer ONE_PERIOD = 0
) (
    input  wire          clk,
    input  wire          rst,

    // Request: the pattern (u, v) and its replay count.
    input  wire          in_valid_i,
    output wire          in_ready_o,
    input  wire [UW-1:0] in_u_i,
    input  wire [UW-1:0] in_v_i,
    input  wire [KW-1:0] in_k_i,
    input  wire [RW-1:0] in_rep_i,

    // A refused request: one-clock pulse with the reason (ERR_* below).
    output wire          err_o,
    output wire [2:0]    err_code_o,

    // Move stream.
    output wire          move_valid_o,
    input  wire          move_ready_i,
    output wire          move_o,
    output wire          move_last_o,
    // The move ends a period of the pattern M2·reverse(M1) (every move of a
    // constant pattern does); the first such move ends the pattern's first copy.
    output wire          move_pend_o,

    // Debug port: memory write ports and a snapshot after each loop iteration.
    // All are zero when their strobe is low. Unconnected, they synthesize away.
    output wire          dbg_we1_o,
    output wire [AW-1:0] dbg_waddr1_o,
    output wire          dbg_wbit1_o,
    output wire          dbg_we2_o,
    output wire [AW-1:0] dbg_waddr2_o,
    output wire          dbg_wbit2_o,
    output wire          dbg_iter_o,
    output wire [UW-1:0] dbg_x_o,
    output wire [UW-1:0] dbg_y_o,
    output wire [AW-1:0] dbg_m1_lo_o,
    output wire [AW-1:0] dbg_m1_len_o,
    output wire          dbg_m1_rev_o,
    output wire [AW-1:0] dbg_m2_lo_o,
    output wire [AW-1:0] dbg_m2_len_o,
    output wire          dbg_m2_rev_o
);

// Memory address width: each register holds at most u/gcd - 1 <= W - 1 bits.
localparam integer AW = (W > 2) ? $clog2(W) : 1;
// Width of u, v, x, y: wide enough to express UMAX + 1, so u > UMAX can be refused.
localparam integer UW = $clog2(UMAX + 2);
// Width of k: wide enough to express KMAX + 1.
localparam integer KW = (KMAX > 0) ? $clog2(KMAX + 2) : 1;
// Width of the inner replay counter x << k (x <= UMAX).
localparam integer NW = UW + KMAX;

localparam [UW-1:0] UMAX_U = UMAX[UW-1:0];
localparam [AW:0]   W_L = W[AW:0];
localparam [KW-1:0] KMAX_K = KMAX[KW-1:0];

// Refusal reasons, checked in this order.
localparam [2:0] ERR_NONE      = 3'd0;
localparam [2:0] ERR_U_ZERO    = 3'd1;
localparam [2:0] ERR_V_GT_U    = 3'd2;
localparam [2:0] ERR_U_GT_UMAX = 3'd3;
localparam [2:0] ERR_K_GT_KMAX = 3'd4;
localparam [2:0] ERR_REP_ZERO  = 3'd5;
localparam [2:0] ERR_PATTERN_GT_W = 3'd6;

localparam [1:0] S_IDLE   = 2'd0;
localparam [1:0] S_BUILD  = 2'd1;
localparam [1:0] S_REPLAY = 2'd2;

// Elaboration-time parameter checks: an illegal value instantiates a module
// that does not exist, which both Verilator and yosys report by name.
generate
    if (W < 2) begin : g_check_w
        cp_engine_parameter_W_must_be_at_least_2 u_bad ();
    end
    if (UMAX < W) begin : g_check_umax
        cp_engine_parameter_UMAX_must_be_at_least_W u_bad ();
    end
    if (KMAX < 0 || KMAX > 24) begin : g_check_kmax
        cp_engine_parameter_KMAX_must_be_0_to_24 u_bad ();
    end
    if (RW < 1 || RW > 32) begin : g_check_rw
        cp_engine_parameter_RW_must_be_1_to_32 u_bad ();
    end
    if (ONE_PERIOD < 0 || ONE_PERIOD > 1) begin : g_check_one_period
        cp_engine_parameter_ONE_PERIOD_must_be_0_or_1 u_bad ();
    end
endgenerate

// ---------------------------------------------------------------- storage
reg mem1 [0:(1<<AW)-1];
reg mem2 [0:(1<<AW)-1];
reg rdata1_q;
reg rdata2_q;

reg          re1, re2;
reg [AW-1:0] raddr1, raddr2;
reg          we1, we2;
reg [AW-1:0] waddr1, waddr2;
reg          wbit1, wbit2;

always @(posedge clk) begin
    if (we1) mem1[waddr1] <= wbit1;
    if (we2) mem2[waddr2] <= wbit2;
    if (re1) rdata1_q <= mem1[raddr1];
    if (re2) rdata2_q <= mem2[raddr2];
end

// ---------------------------------------------------------------- state
// Control state (reset).
reg [1:0]    state_q, state_d;
reg          wp_q, wp_d;            // a build write lands this clock
reg          move_valid_q, move_valid_d;
reg          err_q, err_d;
reg          dbg_iter_q, dbg_iter_d;

// Datapath (loaded on acceptance, no reset).
reg [UW-1:0] x_q, x_d, y_q, y_d;
reg [KW-1:0] k_q, k_d;
reg [RW-1:0] rep_q, rep_d;          // replay multiplier, kept for reloads
reg          const_q, const_d;      // v == 0 or v == u: a 1-move pattern
reg          cbit_q, cbit_d;        // its move
reg [AW-1:0] m1_lo_q, m1_lo_d, m1_len_q, m1_len_d;
reg [AW-1:0] m2_lo_q, m2_lo_d, m2_len_q, m2_len_d;
reg          m1_rev_q, m1_rev_d, m2_rev_q, m2_rev_d;
reg [AW-1:0] rd_cnt_q, rd_cnt_d;    // build: source reads left in this iteration
reg [AW-1:0] rd_ptr_q, rd_ptr_d;    // build: physical address of the next read
reg          wp_to2_q, wp_to2_d;    // build: the pending write goes to M2
reg [AW-1:0] wp_addr_q, wp_addr_d;
reg          ph_q, ph_d;            // replay: 0 = M2 forward, 1 = M1 backward
reg [AW-1:0] rp_cnt_q, rp_cnt_d;    // replay: reads left in this phase
reg [AW-1:0] rp_ptr_q, rp_ptr_d;
reg [NW-1:0] inner_q, inner_d;      // replays left of x << k
reg [RW-1:0] outer_q, outer_d;      // rounds of x << k left
reg          out_ph_q, out_ph_d;    // phase of the move in the output register
reg          out_last_q, out_last_d;
reg          out_pend_q, out_pend_d;
reg [2:0]    err_code_q, err_code_d;
reg [UW-1:0] dbg_x_q, dbg_x_d, dbg_y_q, dbg_y_d;
reg [AW-1:0] dbg_m1_lo_q, dbg_m1_lo_d, dbg_m1_len_q, dbg_m1_len_d;
reg [AW-1:0] dbg_m2_lo_q, dbg_m2_lo_d, dbg_m2_len_q, dbg_m2_len_d;
reg          dbg_m1_rev_q, dbg_m1_rev_d, dbg_m2_rev_q, dbg_m2_rev_d;

// ---------------------------------------------------------------- helpers
// Physical address of a register's last logical bit, and of its first.
function [AW-1:0] log_last;
    input [AW-1:0] lo;
    input [AW-1:0] len;
    input          rev;
    log_last = rev ? lo : lo + len - 1'b1;
endfunction

function [AW-1:0] log_first;
    input [AW-1:0] lo;
    input [AW-1:0] len;
    input          rev;
    log_first = rev ? lo + len - 1'b1 : lo;
endfunction

function [NW-1:0] shifted;
    input [UW-1:0] x;
    input [KW-1:0] k;
    shifted = {{(NW-UW){1'b0}}, x} << k;
endfunction

wire accept = in_valid_i && in_ready_o;
wire issue  = state_q == S_REPLAY && !wp_q && (!move_valid_q || move_ready_i);

reg [2:0] refuse_code;
always @* begin
    if (ONE_PERIOD != 0)            refuse_code = ERR_NONE;
    else if (in_u_i == {UW{1'b0}})  refuse_code = ERR_U_ZERO;
    else if (in_v_i > in_u_i)       refuse_code = ERR_V_GT_U;
    else if (in_u_i > UMAX_U)       refuse_code = ERR_U_GT_UMAX;
    else if (in_k_i > KMAX_K)       refuse_code = ERR_K_GT_KMAX;
    else if (in_rep_i == {RW{1'b0}}) refuse_code = ERR_REP_ZERO;
    else                            refuse_code = ERR_NONE;
end

// Build: the iteration's target is M2 when x > y (M2 = M1 + reverse(M2)),
// else M1 (M1 = M2 + reverse(M1)). The target is already reversed.
wire          to2      = x_q > y_q;
// The next iteration's decisions, compared beside the subtraction rather than after
// it (x - y against y is x against 2y; y - x against x is 2x against y); the same
// for the first one at acceptance (u - v against v).
wire [UW:0]   x2       = {x_q, 1'b0};
wire [UW:0]   y2       = {y_q, 1'b0};
wire [UW:0]   v2       = {in_v_i, 1'b0};
wire          nx_eq    = to2 ? {1'b0, x_q} == y2 : {1'b0, y_q} == x2;
wire          nx_gt    = to2 ? {1'b0, x_q} > y2 : x2 > {1'b0, y_q};
wire          in_eq    = {1'b0, in_u_i} == v2;
wire          in_gt    = {1'b0, in_u_i} > v2;
wire          src_rev  = to2 ? m1_rev_q : m2_rev_q;
wire          tgt_rev  = to2 ? m2_rev_q : m1_rev_q;
wire [AW-1:0] tgt_lo   = to2 ? m2_lo_q : m1_lo_q;
wire [AW-1:0] tgt_len  = to2 ? m2_len_q : m1_len_q;
wire [AW-1:0] tgt_addr = tgt_rev ? tgt_lo + tgt_len : tgt_lo - 1'b1;
wire          pat_end  = const_q || (ph_q && rp_cnt_q == 1);
// The pattern's length so far; a bit more than W means u/gcd(u, v) > W.
wire [AW:0]   pat_len  = {1'b0, m1_len_q} + {1'b0, m2_len_q};

always @* begin
    state_d      = state_q;
    wp_d         = 1'b0;
    move_valid_d = move_valid_q;
    err_d        = 1'b0;
    err_code_d   = err_code_q;
    dbg_iter_d   = 1'b0;

    x_d = x_q;  y_d = y_q;  k_d = k_q;  rep_d = rep_q;
    const_d = const_q;  cbit_d = cbit_q;
    m1_lo_d = m1_lo_q;  m1_len_d = m1_len_q;  m1_rev_d = m1_rev_q;
    m2_lo_d = m2_lo_q;  m2_len_d = m2_len_q;  m2_rev_d = m2_rev_q;
    rd_cnt_d = rd_cnt_q;  rd_ptr_d = rd_ptr_q;
    wp_to2_d = wp_to2_q;  wp_addr_d = wp_addr_q;
    ph_d = ph_q;  rp_cnt_d = rp_cnt_q;  rp_ptr_d = rp_ptr_q;
    inner_d = inner_q;  outer_d = outer_q;
    out_ph_d = out_ph_q;  out_last_d = out_last_q;  out_pend_d = out_pend_q;
    dbg_x_d = dbg_x_q;  dbg_y_d = dbg_y_q;
    dbg_m1_lo_d = dbg_m1_lo_q;  dbg_m1_len_d = dbg_m1_len_q;  dbg_m1_rev_d = dbg_m1_rev_q;
    dbg_m2_lo_d = dbg_m2_lo_q;  dbg_m2_len_d = dbg_m2_len_q;  dbg_m2_rev_d = dbg_m2_rev_q;

    re1 = 1'b0;  raddr1 = {AW{1'b0}};
    re2 = 1'b0;  raddr2 = {AW{1'b0}};
    // Write port: the pending build write lands in its target.
    we1 = wp_q && !wp_to2_q;  waddr1 = wp_addr_q;  wbit1 = rdata2_q;
    we2 = wp_q &&  wp_to2_q;  waddr2 = wp_addr_q;  wbit2 = rdata1_q;

    // A move leaves the output register.
    if (move_valid_q && move_ready_i) move_valid_d = 1'b0;

    case (state_q)
    S_IDLE: begin
        if (accept) begin
            if (refuse_code != ERR_NONE) begin
                err_d      = 1'b1;
                err_code_d = refuse_code;
            end else begin
                k_d   = in_k_i;
                rep_d = in_rep_i;
                outer_d = in_rep_i;
                if (in_v_i == {UW{1'b0}} || in_v_i == in_u_i) begin
                    const_d = 1'b1;
                    cbit_d  = in_v_i != {UW{1'b0}};
                    x_d     = in_u_i;
                    inner_d = shifted(in_u_i, in_k_i);
                    state_d = S_REPLAY;
                end else begin
                    const_d = 1'b0;
                    x_d = in_u_i - in_v_i;
                    y_d = in_v_i;
                    // M1 = "0", M2 = "1".
                    we1 = 1'b1;  waddr1 = {AW{1'b0}};  wbit1 = 1'b0;
                    we2 = 1'b1;  waddr2 = {AW{1'b0}};  wbit2 = 1'b1;
                    m1_lo_d = {AW{1'b0}};  m1_len_d = 1;  m1_rev_d = 1'b0;
                    m2_lo_d = {AW{1'b0}};  m2_len_d = 1;  m2_rev_d = 1'b0;
                    if (in_eq) begin  // x_d == y_d
                        ph_d     = 1'b0;
                        rp_cnt_d = 1;
                        rp_ptr_d = {AW{1'b0}};
                        inner_d  = shifted(x_d, in_k_i);
                        state_d  = S_REPLAY;
                    end else begin
                        // First target reversed; the source is one bit at 0.
                        if (in_gt) m2_rev_d = 1'b1;  // x_d > y_d
                        else           m1_rev_d = 1'b1;
                        rd_cnt_d = 1;
                        rd_ptr_d = {AW{1'b0}};
                        state_d  = S_BUILD;
                    end
                end
            end
        end
    end

    S_BUILD: if (pat_len == W_L) begin
        // One more bit would make the pattern longer than the registers hold.
        err_d      = 1'b1;
        err_code_d = ERR_PATTERN_GT_W;
        state_d    = S_IDLE;
    end else begin
        // Read the source's logical bit rd_cnt-1; its write lands next clock
        // at the target's logical front.
        if (to2) begin re1 = 1'b1; raddr1 = rd_ptr_q; end
        else     begin re2 = 1'b1; raddr2 = rd_ptr_q; end
        wp_d      = 1'b1;
        wp_to2_d  = to2;
        wp_addr_d = tgt_addr;
        if (to2) begin
            m2_len_d = m2_len_q + 1'b1;
            if (!m2_rev_q) m2_lo_d = m2_lo_q - 1'b1;
        end else begin
            m1_len_d = m1_len_q + 1'b1;
            if (!m1_rev_q) m1_lo_d = m1_lo_q - 1'b1;
        end
        rd_cnt_d = rd_cnt_q - 1'b1;
        rd_ptr_d = src_rev ? rd_ptr_q + 1'b1 : rd_ptr_q - 1'b1;

        if (rd_cnt_q == 1) begin
            // Iteration done: subtract, snapshot, pick the next target.
            if (to2) x_d = x_q - y_q;
            else     y_d = y_q - x_q;
            dbg_iter_d   = 1'b1;
            dbg_x_d      = x_d;          dbg_y_d      = y_d;
            dbg_m1_lo_d  = m1_lo_d;      dbg_m1_len_d = m1_len_d;  dbg_m1_rev_d = m1_rev_d;
            dbg_m2_lo_d  = m2_lo_d;      dbg_m2_len_d = m2_len_d;  dbg_m2_rev_d = m2_rev_d;
            if (nx_eq) begin  // x_d == y_d
                ph_d     = 1'b0;
                rp_cnt_d = m2_len_d;
                rp_ptr_d = log_first(m2_lo_d, m2_len_d, m2_rev_d);
                inner_d  = shifted(x_d, k_q);
                state_d  = S_REPLAY;
            end else if (nx_gt) begin  // x_d > y_d
                m2_rev_d = !m2_rev_d;
                rd_cnt_d = m1_len_d;
                rd_ptr_d = log_last(m1_lo_d, m1_len_d, m1_rev_d);
            end else begin
                m1_rev_d = !m1_rev_d;
                rd_cnt_d = m2_len_d;
                rd_ptr_d = log_last(m2_lo_d, m2_len_d, m2_rev_d);
            end
        end
    end

    S_REPLAY: begin
        if (issue) begin
            if (!const_q) begin
                if (ph_q) begin re1 = 1'b1; raddr1 = rp_ptr_q; end
                else      begin re2 = 1'b1; raddr2 = rp_ptr_q; end
            end
            move_valid_d = 1'b1;
            out_ph_d     = ph_q;
            out_last_d   = pat_end && (ONE_PERIOD != 0 || (inner_q == 1 && outer_q == 1));
            out_pend_d   = pat_end;
            if (pat_end) begin
                ph_d     = 1'b0;
                rp_cnt_d = m2_len_q;
                rp_ptr_d = log_first(m2_lo_q, m2_len_q, m2_rev_q);
                if (ONE_PERIOD != 0) begin
                    state_d = S_IDLE;
                end else if (inner_q != 1) begin
                    inner_d = inner_q - 1'b1;
                end else if (outer_q != 1) begin
                    outer_d = outer_q - 1'b1;
                    inner_d = shifted(x_q, k_q);
                end else begin
                    state_d = S_IDLE;
                end
            end else if (rp_cnt_q == 1) begin
                // End of M2: continue with reverse(M1), from its logical end.
                ph_d     = 1'b1;
                rp_cnt_d = m1_len_q;
                rp_ptr_d = log_last(m1_lo_q, m1_len_q, m1_rev_q);
            end else begin
                rp_cnt_d = rp_cnt_q - 1'b1;
                if (ph_q) rp_ptr_d = m1_rev_q ? rp_ptr_q + 1'b1 : rp_ptr_q - 1'b1;
                else      rp_ptr_d = m2_rev_q ? rp_ptr_q - 1'b1 : rp_ptr_q + 1'b1;
            end
        end
    end

    default: state_d = S_IDLE;
    endcase
end

always @(posedge clk) begin
    if (rst) begin
        state_q      <= S_IDLE;
        wp_q         <= 1'b0;
        move_valid_q <= 1'b0;
        err_q        <= 1'b0;
        dbg_iter_q   <= 1'b0;
    end else begin
        state_q      <= state_d;
        wp_q         <= wp_d;
        move_valid_q <= move_valid_d;
        err_q        <= err_d;
        dbg_iter_q   <= dbg_iter_d;
    end
    x_q <= x_d;  y_q <= y_d;  k_q <= k_d;  rep_q <= rep_d;
    const_q <= const_d;  cbit_q <= cbit_d;
    m1_lo_q <= m1_lo_d;  m1_len_q <= m1_len_d;  m1_rev_q <= m1_rev_d;
    m2_lo_q <= m2_lo_d;  m2_len_q <= m2_len_d;  m2_rev_q <= m2_rev_d;
    rd_cnt_q <= rd_cnt_d;  rd_ptr_q <= rd_ptr_d;
    wp_to2_q <= wp_to2_d;  wp_addr_q <= wp_addr_d;
    ph_q <= ph_d;  rp_cnt_q <= rp_cnt_d;  rp_ptr_q <= rp_ptr_d;
    inner_q <= inner_d;  outer_q <= outer_d;
    out_ph_q <= out_ph_d;  out_last_q <= out_last_d;  out_pend_q <= out_pend_d;
    err_code_q <= err_code_d;
    dbg_x_q <= dbg_x_d;  dbg_y_q <= dbg_y_d;
    dbg_m1_lo_q <= dbg_m1_lo_d;  dbg_m1_len_q <= dbg_m1_len_d;  dbg_m1_rev_q <= dbg_m1_rev_d;
    dbg_m2_lo_q <= dbg_m2_lo_d;  dbg_m2_len_q <= dbg_m2_len_d;  dbg_m2_rev_q <= dbg_m2_rev_d;
end

// ---------------------------------------------------------------- outputs
wire move_bit = const_q ? cbit_q : (out_ph_q ? rdata1_q : rdata2_q);

assign in_ready_o   = state_q == S_IDLE && !move_valid_q;
assign err_o        = err_q;
assign err_code_o   = err_q ? err_code_q : ERR_NONE;
assign move_valid_o = move_valid_q;
assign move_o       = move_valid_q && move_bit;
assign move_last_o  = move_valid_q && out_last_q;
assign move_pend_o  = move_valid_q && out_pend_q;

assign dbg_we1_o    = we1;
assign dbg_waddr1_o = we1 ? waddr1 : {AW{1'b0}};
assign dbg_wbit1_o  = we1 && wbit1;
assign dbg_we2_o    = we2;
assign dbg_waddr2_o = we2 ? waddr2 : {AW{1'b0}};
assign dbg_wbit2_o  = we2 && wbit2;
assign dbg_iter_o   = dbg_iter_q;
assign dbg_x_o      = dbg_iter_q ? dbg_x_q : {UW{1'b0}};
assign dbg_y_o      = dbg_iter_q ? dbg_y_q : {UW{1'b0}};
assign dbg_m1_lo_o  = dbg_iter_q ? dbg_m1_lo_q : {AW{1'b0}};
assign dbg_m1_len_o = dbg_iter_q ? dbg_m1_len_q : {AW{1'b0}};
assign dbg_m1_rev_o = dbg_iter_q && dbg_m1_rev_q;
assign dbg_m2_lo_o  = dbg_iter_q ? dbg_m2_lo_q : {AW{1'b0}};
assign dbg_m2_len_o = dbg_iter_q ? dbg_m2_len_q : {AW{1'b0}};
assign dbg_m2_rev_o = dbg_iter_q && dbg_m2_rev_q;

`ifdef FORMAL
// ---------------------------------------------------------------- formal
// Properties for yosys-smtbmc (docs/FORMAL.md, scripts/formal, row `engine` of
// formal/proofs.tsv), written from docs/ENGINE.md. The environment is free: any
// request and any move_ready_i on any cycle, reset in the first. A shadow keeps
// what the ports say: the request in progress (u, k, rep, its refusal code) and
// the moves transferred for it.
reg f_past_valid = 1'b0;
always @(posedge clk) f_past_valid <= 1'b1;
always @* if (!f_past_valid) assume(rst);

// The refusal table of docs/ENGINE.md "Refusal", first match wins.
reg [2:0] f_code;
always @* begin
    if (ONE_PERIOD != 0)                f_code = 3'd0;
    else if (in_u_i == 0)               f_code = 3'd1;   // U_ZERO
    else if (in_v_i > in_u_i)           f_code = 3'd2;   // V_GT_U
    else if (in_u_i > UMAX)             f_code = 3'd3;   // U_GT_UMAX
    else if (in_k_i > KMAX)             f_code = 3'd4;   // K_GT_KMAX
    else if (in_rep_i == 0)             f_code = 3'd5;   // REP_ZERO
    else                                f_code = 3'd0;
end

localparam integer FW = AW + NW + RW + 4;     // wide enough for u * 2^k * rep
wire f_accept = in_valid_i && in_ready_o;
wire f_take   = move_valid_o && move_ready_i;
wire f_err6   = err_o && err_code_o == ERR_PATTERN_GT_W;
// The moves an accepted request owes: u * 2^k * rep (one period in ONE_PERIOD mode).
wire [FW-1:0] f_u_in    = {{(FW-UW){1'b0}}, in_u_i};
wire [FW-1:0] f_rep_in  = {{(FW-RW){1'b0}}, in_rep_i};

reg          f_busy = 1'b0;   // a request taken, not refused, its last move not yet out
reg          f_moved;         // a move of that request has been valid
reg [FW-1:0] f_u, f_rep, f_total, f_cnt;
reg [KW-1:0] f_k;
always @(posedge clk) begin
    if (f_take) f_cnt <= f_cnt + 1'b1;
    if (move_valid_o) f_moved <= 1'b1;
    if ((f_take && move_last_o) || f_err6) f_busy <= 1'b0;
    if (f_accept && f_code == 3'd0) begin
        f_busy  <= 1'b1;
        f_moved <= 1'b0;
        f_u     <= f_u_in;
        f_k     <= in_k_i;
        f_rep   <= f_rep_in;
        f_total <= (f_u_in << in_k_i) * f_rep_in;
        f_cnt   <= {FW{1'b0}};
    end
    if (rst) f_busy <= 1'b0;
end

// The engine's state as moves still owed (auxiliary, for induction): the output
// register, the rest of the current pattern, then whole patterns of length P.
wire [FW-1:0] f_len1 = {{(FW-AW){1'b0}}, m1_len_q};
wire [FW-1:0] f_len2 = {{(FW-AW){1'b0}}, m2_len_q};
wire [FW-1:0] f_rpc  = {{(FW-AW){1'b0}}, rd_cnt_q};
wire [FW-1:0] f_rpn  = {{(FW-AW){1'b0}}, rp_cnt_q};
wire [FW-1:0] f_x    = {{(FW-UW){1'b0}}, x_q};
wire [FW-1:0] f_y    = {{(FW-UW){1'b0}}, y_q};
wire [FW-1:0] f_xk   = {{(FW-NW){1'b0}}, shifted(x_q, k_q)};
wire [FW-1:0] f_in   = {{(FW-NW){1'b0}}, inner_q};
wire [FW-1:0] f_out  = {{(FW-RW){1'b0}}, outer_q};
wire [FW-1:0] f_pat  = const_q ? 1 : f_len1 + f_len2;
wire [FW-1:0] f_rest = const_q ? 1 : (ph_q ? f_rpn : f_rpn + f_len1);
wire [FW-1:0] f_owed = {{(FW-1){1'b0}}, move_valid_q} + f_rest
                     + f_pat * ((f_in - 1'b1) + (f_out - 1'b1) * f_xk);

always @* if (f_past_valid) begin
    // Nothing accepted while busy, and ready whenever not (docs/ENGINE.md
    // "States and cycles": in_ready_o = IDLE && no move waiting).
    assert(in_ready_o == (!f_busy || f_err6));
    // No move without a request; nothing but zeros while not valid.
    if (move_valid_o) assert(f_busy);
    if (!move_valid_o) assert(!move_o && !move_last_o && !move_pend_o);
    if (!err_o) assert(err_code_o == ERR_NONE);
    // Exactly u * 2^k * rep moves: none beyond, and the last one says so.
    if (move_valid_o) begin
        assert(f_cnt < f_total);
        assert(move_last_o == (f_cnt + 1'b1 == f_total));
        if (move_last_o) assert(move_pend_o);
    end

    // Auxiliary invariants.
    assert(state_q != 2'd3);
    assert(f_busy == (state_q != S_IDLE || move_valid_q || (err_q && err_code_q == ERR_PATTERN_GT_W)));
    if (err_q && err_code_q == ERR_PATTERN_GT_W) assert(state_q == S_IDLE && !move_valid_q && !f_moved);
    if (wp_q) assert(state_q != S_IDLE && !move_valid_q);
    if (state_q == S_IDLE && move_valid_q) assert(out_last_q && out_pend_q && f_cnt + 1'b1 == f_total);
    if (f_busy) begin
        assert(f_u != 0 && f_u <= UMAX && f_k <= KMAX && f_rep != 0);
        assert(f_total == (f_u << f_k) * f_rep);
    end
    if (state_q != S_IDLE) assert(k_q == f_k && {{(FW-RW){1'b0}}, rep_q} == f_rep);
    if (state_q == S_BUILD) begin
        // Euclid's loop keeps x*len(M1) + y*len(M2) = u between iterations.
        // Mid-iteration (target M2, say) the target has len(M1) - rd_cnt of the
        // source's bits already and x is not yet reduced, so
        // (x - y)*len(M1) + y*(len(M2) + rd_cnt) = u.
        assert(!move_valid_q && !f_moved && f_cnt == 0 && !const_q);
        assert(f_out == f_rep && x_q != 0 && y_q != 0 && x_q != y_q && rd_cnt_q != 0);
        if (to2) begin
            assert(rd_cnt_q <= m1_len_q);
            assert((f_x - f_y) * f_len1 + f_y * (f_len2 + f_rpc) == f_u);
        end else begin
            assert(rd_cnt_q <= m2_len_q);
            assert(f_x * (f_len1 + f_rpc) + (f_y - f_x) * f_len2 == f_u);
        end
        assert(pat_len <= W_L);
    end
    if (state_q == S_REPLAY) begin
        assert(f_owed == f_total - f_cnt);
        assert(f_in != 0 && f_in <= f_xk && f_out != 0 && f_out <= f_rep);
        if (const_q) assert(f_x == f_u);
        else begin
            assert(x_q == y_q && f_x * (f_len1 + f_len2) == f_u);
            assert(rp_cnt_q != 0 && m1_len_q != 0 && m2_len_q != 0);
            if (ph_q) assert(rp_cnt_q <= m1_len_q);
            else      assert(rp_cnt_q <= m2_len_q);
        end
        if (move_valid_q && !out_last_q) assert(!wp_q);
    end
end

always @(posedge clk) if (f_past_valid && !$past(rst)) begin
    // A request taken in the last cycle: refused (err_o and its code) or not.
    if ($past(f_accept)) begin
        assert(err_o == ($past(f_code) != 3'd0));
        assert(err_code_o == $past(f_code));
    end else if (err_o) begin
        // The one later refusal: a pattern longer than W, during the build,
        // before any move.
        assert(err_code_o == ERR_PATTERN_GT_W && $past(f_busy) && !$past(f_moved));
    end
    // Valid/ready: while valid && !ready the move holds still.
    if ($past(move_valid_o && !move_ready_i)) begin
        assert(move_valid_o);
        assert(move_o == $past(move_o) && move_last_o == $past(move_last_o)
               && move_pend_o == $past(move_pend_o));
    end
    // No bubble: with move_ready_i high, the next move follows at once.
    if ($past(f_take && !move_last_o)) assert(move_valid_o);
end
// Latency: when no loop iteration runs (v = 0, v = u or u = 2v), the first move
// is valid two cycles after the handshake's cycle.
reg f_trivial_q1 = 1'b0, f_trivial_q2 = 1'b0;
always @(posedge clk) begin
    f_trivial_q1 <= !rst && f_accept && f_code == 3'd0 &&
                    (in_v_i == 0 || in_v_i == in_u_i || {1'b0, in_u_i} == {in_v_i, 1'b0});
    f_trivial_q2 <= !rst && f_trivial_q1;
end
always @* if (f_trivial_q2) assert(move_valid_o);
`endif

endmodule

`resetall
