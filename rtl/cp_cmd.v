// SPDX-License-Identifier: MIT
// cp_cmd — the motion core's command parser and chunk check.
//
// Takes the command words (docs/CORE.md "Command port"), one a clock, and
// validates every segment whole: its header and v_i go into the segment queue
// and its chunks into the chunk queue uncommitted; after its last chunk both are
// committed together, or both rolled back when any check failed. Each chunk's
// last increment and last delay are checked bit-serially, least significant bit
// first, in 51 clocks: two serial-parallel multipliers and three serial
// adders instead of 49-bit datapaths (the link brings a chunk in hundreds of
// clocks). CONFIG, CONTROL and READ become one-cycle
// requests to cp_status and cp_run; a refusal is a fault request with its code
// (cp_status decides).
//
// With PTIMER = 1 (the phase timer's build, docs/PROTOCOL.md "Toward a compact
// wire") segments carry no chunks but, after their v_i (and a conic's words), their
// length per move L (a word, not 0: SEG_LENGTH), and are committed with it. Their
// H0[15:0] is the axis form: 0, every axis's v_i sent; or the compact form
// {1, 3'b0, major valid, major[2:0], sent[7:0]}: only the axes of `sent` have a v_i
// word (in axis order), the major axis's v_i is U, every other axis's 0 (the parser
// writes those into the segment queue itself, a clock each); anything else, or an
// axis past N named, or the major axis also sent, is refused whole (SEG_FORM).
// PHASE commands (opcode 0x6: {kind[3:0], ticks[23:0]} in H0, then u, r's two
// words if kind[0], S's and H's four if kind[3]) go to the chunk queue as the phase
// timer's words {sel, data}, W0 last, committed whole.
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_cmd.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_cmd #(
    parameter integer N = 4,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer TW = 16,
    // 1: CONIC segments (opcode 0x5, docs/CORE.md) are taken; 0: refused as BAD_OPCODE.
    parameter integer CONIC = 0,
    // 1: CONFIG field 9 (the feed ramp's tick, cp_feed) is taken; 0: refused.
    parameter integer FEED = 0,
    // 1: CONFIG field 10 (the seek, cp_inputs) is taken; 0: refused. Fields above 10: refused.
    parameter integer INPUTS = 0,
    // 1: segments timed by the phase timer and PHASE commands (above); 0: chunks.
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,
    // FLUSH (out of band): the command in hand is dropped, nothing of it written.
    input  wire          flush_i,

    input  wire          cmd_valid_i,
    output wire          cmd_ready_o,
    input  wire [31:0]   cmd_data_i,
    output wire          rsp_valid_o,
    input  wire          rsp_ready_i,
    output wire [31:0]   rsp_data_o,
    output wire [7:0]    rsp_addr_o,
    // The register cmd_data_i[7:0] names, now (cp_status's first read port).
    input  wire [31:0]   read_data_i,

    input  wire          fault_i,          // a fault is latched
    input  wire          running_i,
    input  wire          pulse_busy_i,     // some STEP pin is at its active level

    // Segment queue (words of the segment being read) and chunk queue.
    input  wire          seg_full_i,
    output reg           seg_wr_o,
    output reg  [SWW-1:0] seg_wdata_o,
    output reg           seg_commit_o,
    output reg           seg_rollback_o,
    input  wire          ch_full_i,
    output reg           ch_wr_o,
    output wire [80:0]   ch_wdata_o,
    output reg           ch_commit_o,
    output reg           ch_rollback_o,

    // One-cycle requests of the word taken now.
    output reg           start_o,
    output reg           abort_o,
    output reg           clear_o,
    output reg           drivers_on_o,
    output reg           drivers_off_o,
    output reg           cfg_write_o,      // CONFIG accepted: cmd_data_i is the word
    output reg           fault_o,          // a refusal, with its code
    output reg  [7:0]    fault_code_o
);

// Segment queue words: {out, end, k, dir[N], value[23:0]} (out: the torch output
// while the segment runs, H0[16]), with CONIC the conic flag and the continuation flag
// above them, and a conic's seven words of 32 bits (two, K5 and K6, for a continuation).
localparam integer SWW0 = (CONIC == 0) ? 30 + N : 32 + N;
localparam integer SWW = (PTIMER != 0 && SWW0 < 32) ? 32 : SWW0;   // (a PTIMER segment's L: 32 bits)
localparam [3:0] OP_SEGMENT = 4'h1;
localparam [3:0] OP_CONFIG  = 4'h2;
localparam [3:0] OP_CONTROL = 4'h3;
localparam [3:0] OP_READ    = 4'h4;
localparam [3:0] OP_CONIC   = 4'h5;
localparam [3:0] OP_PHASE   = 4'h6;

localparam [7:0] E_NONE           = 8'd0;
localparam [7:0] E_SEG_U          = 8'd1;
localparam [7:0] E_SEG_V_GT_U     = 8'd2;
localparam [7:0] E_SEG_K          = 8'd3;
localparam [7:0] E_SEG_CHUNKS     = 8'd4;
localparam [7:0] E_SEG_CHUNK_ZERO = 8'd5;
localparam [7:0] E_SEG_DELAY      = 8'd6;
localparam [7:0] E_SEG_COUNT_SUM  = 8'd7;
localparam [7:0] E_BAD_OPCODE     = 8'd12;
localparam [7:0] E_CONFIG_BUSY    = 8'd13;
localparam [7:0] E_CONFIG_VALUE   = 8'd14;
localparam [7:0] E_SEG_ADD2       = 8'd15;
localparam [7:0] E_CONIC_AXES     = 8'd16;
localparam [7:0] E_CONIC_CONT     = 8'd18;
localparam [7:0] E_SEG_LENGTH     = 8'd21;
localparam [7:0] E_SEG_FORM       = 8'd22;
// The bits of a 16-bit CONFIG value that a TW-bit timing field holds.
localparam [15:0] TMASK = (TW >= 16) ? 16'hFFFF : ((16'd1 << TW) - 16'd1);

localparam [3:0] P_CMD  = 4'd0;   // first word of a command
localparam [3:0] P_H1   = 4'd1;   // segment: dir and U
localparam [3:0] P_V    = 4'd2;   // segment: v_i
localparam [3:0] P_C0   = 4'd3;   // chunk: interval
localparam [3:0] P_C1   = 4'd4;   // chunk: add and count
localparam [3:0] P_CHK  = 4'd5;   // chunk: checking its last increment and last delay
localparam [3:0] P_RSP  = 4'd6;   // a reply waits to be taken
localparam [3:0] P_C2   = 4'd7;   // chunk: add2 (segments whose chunks carry it)
localparam [3:0] P_K    = 4'd8;   // conic: its seven words
localparam [3:0] P_L    = 4'd9;   // PTIMER segment: its length per move, then the commit
localparam [3:0] P_PH   = 4'd10;  // PHASE: its words (v_idx_q: the next one's sel)
localparam [3:0] P_PW0  = 4'd11;  // PHASE: W0 (interval_q) to the chunk queue, and the commit
// The check's clocks: bit i of every serial value in clock i = 0 .. 50. The values
// are exact in 50-bit two's complement (|(count-1)*(add + last increment)| < 2^47),
// and bits past that are the sign's copies.
localparam [5:0] CHECK_LAST = 6'd50;

// ---------------------------------------------------------------- state
reg [3:0]    p_state_q, p_state_d;       // reset
reg          discard_q, discard_d;       // the segment being read is dropped (reset)
reg          rsp_valid_q, rsp_valid_d;   // reset
reg          hdr_end_q, hdr_end_d;       // the segment being read: end flag, k, U
reg          hdr_out_q, hdr_out_d;       // ... the torch output while it runs (H0[16])
reg [3:0]    hdr_k_q, hdr_k_d;
reg [23:0]   seg_u_q, seg_u_d;
reg          seg_add2_q, seg_add2_d;     // its chunks carry add2 (three words)
reg          hdr_conic_q, hdr_conic_d;   // a CONIC segment: its plane axes and direction
reg [2:0]    hdr_au_q, hdr_au_d, hdr_av_q, hdr_av_d;
reg          hdr_cw_q, hdr_cw_d;
reg          hdr_cont_q, hdr_cont_d;     // a CONIC that continues the last walk (H0[18])
// The last segment committed was a CONIC, on these axes, in this direction (none
// since a fault or an ABORT): what a continuation may follow.
reg          lc_valid_q, lc_valid_d;
reg [2:0]    lc_au_q, lc_au_d, lc_av_q, lc_av_d;
reg          lc_cw_q, lc_cw_d;
reg [15:0]   nchunks_q, nchunks_d;       // chunks still to read (PTIMER: H0[15:0], the axis form)
reg [2:0]    v_idx_q, v_idx_d;
reg [31:0]   interval_q, interval_d;
reg [15:0]   count_q, count_d;
reg [15:0]   add_q, add_d;
reg [15:0]   add2_q, add2_d;
reg [33:0]   sum_q, sum_d;               // chunk counts so far
// The serial check (P_CHK): the clock's bit index, the two multipliers' partial
// sums, the three adders' carries and what the bits seen so far say.
reg [5:0]    ck_i_q, ck_i_d;
reg [15:0]   acc1_q, acc1_d;             // (count-2)*add2
reg [15:0]   acc2_q, acc2_d;             // (count-1)*(add + last increment)
reg          c1_q, c1_d;                 // last increment = add + (count-2)*add2
reg          li_sign_q, li_sign_d;       // its bit of the last clock
reg          b_q, b_d;                   // bit i-1 of add + last increment (pass 2's input)
reg          c2_q, c2_d;                 // add + last increment
reg          c3_q, c3_d;                 // last delay = interval + product/2
reg          li_nz_q, li_nz_d;           // the last increment is not 0
reg          dl_nz_q, dl_nz_d;           // the last delay has a bit set below 32
reg          dl_hi_q, dl_hi_d;           // ... at or above 32 (too long, or negative)
reg          sum_ne_q, sum_ne_d;         // the count sum differs from U*2^k in a bit seen
reg [31:0]   rsp_data_q, rsp_data_d;
reg [7:0]    rsp_addr_q, rsp_addr_d;

// ---------------------------------------------------------------- word fields
// The last CONFIG field taken.
// Fields 0..8 always; 9 (the feed ramp) in FEED builds, 10 (the seek) in INPUTS builds.
wire [3:0] cfg_field = cmd_data_i[23:20];
wire       cfg_field_bad = cfg_field > 4'd10 || (cfg_field == 4'd9 && FEED == 0) ||
                           (cfg_field == 4'd10 && INPUTS == 0);
wire [3:0]  op        = cmd_data_i[31:28];
wire        take      = cmd_valid_i && cmd_ready_o;
wire [15:0] c1_count  = cmd_data_i[15:0];
wire [15:0] c1_add    = cmd_data_i[31:16];
wire [15:0] c2_add2   = cmd_data_i[15:0];
wire        keep      = !discard_q && !fault_i;   // the segment being read is still good
// A PTIMER segment's axis form (H0[15:0], kept in nchunks_q): the compact form sends
// v_i only for the axes in [7:0]; the major axis ([11] valid, [10:8]) has v_i = U.
wire [7:0]  axes_all  = (N >= 8) ? 8'hFF : ((8'd1 << N) - 8'd1);
wire [15:0] h0_form   = cmd_data_i[15:0];
wire [7:0]  h0_sent   = h0_form[7:0];
wire [7:0]  v_sent_m  = nchunks_q[7:0];    // the axes whose v_i is sent
wire        form_ok   = h0_form == 16'd0 ||
                        (h0_form[15] && h0_form[14:12] == 3'd0 && (h0_form[7:0] & ~axes_all) == 8'd0 &&
                         (!h0_form[11] || ({29'd0, h0_form[10:8]} < N && !h0_sent[h0_form[10:8]])));
wire        v_compact = PTIMER != 0 && nchunks_q[15];
wire        v_sent    = !v_compact || v_sent_m[v_idx_q];
wire        v_major   = v_compact && nchunks_q[11] && nchunks_q[10:8] == v_idx_q;
// The v_i of this clock: the word taken, or (not sent) U or 0.
wire [23:0] v_value   = v_sent ? cmd_data_i[23:0] : v_major ? seg_u_q : 24'd0;
wire        v_step    = v_sent ? take : (!keep || !seg_full_i);
// ---------------------------------------------------------------- the serial check
// A serial adder's next carry.
function carry;
    input a, b, c;
    carry = (a & b) | (a & c) | (b & c);
endfunction

// Pass 1 takes bit i of add2 and add (sign-extended) in clock i; pass 2 runs one
// clock behind it (its input bit is registered, so no clock holds both adders),
// and the last delay one more: bit i-2 of interval in clock i.
wire [3:0]  ck_b16   = (ck_i_q > 6'd15) ? 4'd15 : ck_i_q[3:0];
wire        ck_add2  = add2_q[ck_b16];
wire        ck_add   = add_q[ck_b16];
wire [5:0]  ck_j     = ck_i_q - 6'd2;
wire        ck_jv    = ck_i_q >= 6'd2;            // a delay bit (j = i-2) this clock
wire        ck_iv    = ck_jv && ck_j < 6'd32 && interval_q[ck_j[4:0]];
// The multipliers, unsigned: count-2 (0 when count < 2) and count-1.
wire [15:0] ck_m1    = (count_q < 16'd2) ? 16'd0 : count_q - 16'd2;
wire [15:0] ck_m2    = count_q - 1'b1;
// Pass 1: bit i of (count-2)*add2, then of the last increment and of add + it.
wire [16:0] ck_s1    = {1'b0, acc1_q} + (ck_add2 ? {1'b0, ck_m1} : 17'd0);
wire        ck_li    = ck_s1[0] ^ ck_add ^ c1_q;
wire        ck_b     = ck_add ^ ck_li ^ c2_q;
// Pass 2: bit i-1 of (count-1)*(add + last increment), from bit i-1 of add + it
// (b_q); that is bit i-2 of product/2, which interval's bit i-2 meets. (Bit 0 of the
// product is 0: it is even.)
wire [16:0] ck_s2    = {1'b0, acc2_q} + (b_q ? {1'b0, ck_m2} : 17'd0);
wire        ck_dl    = ck_iv ^ ck_s2[0] ^ c3_q;
// At the last clock (i = 50) the verdicts, from the flags alone: the values are exact
// in 48 bits (|last delay| < 2^47, |last increment| < 2^32), so the last increment's
// bit 49 (li_sign_q) and the last delay's bits up to 47 are all it takes.
wire        inc_flip = (!add_q[15] && add_q != 16'd0 && li_sign_q) || (add_q[15] && !li_sign_q && li_nz_q);
wire        dl_bad   = dl_hi_q || !dl_nz_q;
// The count sum against the segment's moves U*2^k, one bit a clock (i = 0 .. 33),
// during every chunk's check; after the last chunk's, the verdict.
wire [5:0]  ck_uk    = ck_i_q - {2'd0, hdr_k_q};
wire        ck_moves = ck_i_q < 6'd34 && ck_i_q >= {2'd0, hdr_k_q} && ck_uk < 6'd24 && seg_u_q[ck_uk[4:0]];
wire        ck_sum   = ck_i_q < 6'd34 && sum_q[ck_i_q];

// The chunk queue word: last chunk of its segment, add2, count, add, interval; with
// PTIMER the phase timer's word {sel, data} (W0: sel 0, the PHASE header kept).
wire        pw0      = p_state_q == P_PW0;
wire [2:0]  pw_sel   = pw0 ? 3'd0 : v_idx_q;
wire [31:0] pw_data  = pw0 ? interval_q : cmd_data_i;
assign ch_wdata_o = (PTIMER != 0) ? {46'd0, pw_sel, pw_data}
                                  : {nchunks_q == 16'd1, add2_d, count_d, add_d, interval_q};
// The PHASE word after the one with sel s: u (1), r (2, 3) if kind[0], S and H (4 .. 7)
// if kind[3], then W0 (0).
wire        ph_load_r  = interval_q[28];   // kind[0]: load r
wire        ph_load_sh = interval_q[31];   // kind[3]: load S and H
wire [2:0]  ph_next  = (v_idx_q == 3'd1) ? (ph_load_r ? 3'd2 : ph_load_sh ? 3'd4 : 3'd0)
                     : (v_idx_q == 3'd3) ? (ph_load_sh ? 3'd4 : 3'd0)
                     : (v_idx_q == 3'd7) ? 3'd0 : v_idx_q + 1'b1;

// ---------------------------------------------------------------- next state
reg refuse;          // a refusal of the parser's own this cycle
reg [7:0] refuse_code;
reg [40:0] seg_wide; // a segment queue word before it is cut to SWW bits
wire unused_wide = &{1'b0, seg_wide[40:SWW]};  // what a narrower queue does not keep

always @* begin
    p_state_d   = p_state_q;
    discard_d   = discard_q;
    rsp_valid_d = rsp_valid_q && !rsp_ready_i;
    rsp_data_d  = rsp_data_q;
    rsp_addr_d  = rsp_addr_q;
    hdr_end_d = hdr_end_q;  hdr_out_d = hdr_out_q;  hdr_k_d = hdr_k_q;  seg_u_d = seg_u_q;
    nchunks_d = nchunks_q;  v_idx_d = v_idx_q;
    interval_d = interval_q;  count_d = count_q;  add_d = add_q;  add2_d = add2_q;  sum_d = sum_q;
    seg_add2_d = seg_add2_q;
    hdr_conic_d = hdr_conic_q;  hdr_au_d = hdr_au_q;  hdr_av_d = hdr_av_q;  hdr_cw_d = hdr_cw_q;
    hdr_cont_d = hdr_cont_q;
    lc_valid_d = lc_valid_q;  lc_au_d = lc_au_q;  lc_av_d = lc_av_q;  lc_cw_d = lc_cw_q;
    // The serial check clocks its bits in P_CHK; each chunk word restarts it.
    ck_i_d  = ck_i_q + 1'b1;
    acc1_d  = ck_s1[16:1];  acc2_d = ck_s2[16:1];
    c1_d    = carry(ck_s1[0], ck_add, c1_q);
    c2_d    = carry(ck_add, ck_li, c2_q);
    c3_d    = ck_jv && carry(ck_iv, ck_s2[0], c3_q);
    b_d     = ck_b;
    li_sign_d = ck_li;
    li_nz_d = li_nz_q || ck_li;
    dl_nz_d = dl_nz_q || (ck_jv && ck_j < 6'd32 && ck_dl);
    dl_hi_d = dl_hi_q || (ck_i_q > 6'd33 && ck_dl);
    sum_ne_d = sum_ne_q || ck_sum != ck_moves;
    if (PTIMER != 0 || p_state_q != P_CHK) begin
        ck_i_d = 6'd0;  acc1_d = 16'd0;  acc2_d = 16'd0;
        c1_d = 1'b0;  c2_d = 1'b0;  c3_d = 1'b0;  b_d = 1'b0;  li_sign_d = 1'b0;
        li_nz_d = 1'b0;  dl_nz_d = 1'b0;  dl_hi_d = 1'b0;  sum_ne_d = 1'b0;
    end

    seg_wr_o = 1'b0;  seg_wdata_o = {SWW{1'b0}};  seg_wide = 41'd0;  seg_commit_o = 1'b0;  seg_rollback_o = 1'b0;
    ch_wr_o = 1'b0;  ch_commit_o = 1'b0;  ch_rollback_o = 1'b0;
    start_o = 1'b0;  abort_o = 1'b0;  clear_o = 1'b0;  drivers_on_o = 1'b0;  drivers_off_o = 1'b0;
    cfg_write_o = 1'b0;
    refuse = 1'b0;  refuse_code = E_NONE;

    case (p_state_q)
    P_CMD: if (cmd_valid_i) begin  // cmd_ready_o is 1 in P_CMD: taken
        case (op)
        OP_SEGMENT, OP_CONIC: if (op == OP_SEGMENT || CONIC != 0) begin
            // A CONIC header: [26] clockwise, [25:23] axis u, [21:19] axis v; no k.
            hdr_conic_d = CONIC != 0 && op == OP_CONIC;
            hdr_end_d = cmd_data_i[27];
            hdr_out_d = cmd_data_i[16];
            hdr_k_d   = hdr_conic_d ? 4'd0 : cmd_data_i[26:23];
            nchunks_d = cmd_data_i[15:0];
            seg_add2_d = cmd_data_i[22];
            hdr_cw_d  = cmd_data_i[26];
            hdr_au_d  = cmd_data_i[25:23];
            hdr_av_d  = cmd_data_i[21:19];
            hdr_cont_d = hdr_conic_d && cmd_data_i[18];
            sum_d     = 34'd0;
            discard_d = fault_i;
            if (!fault_i) begin
                if ({28'd0, hdr_k_d} > KMAX) begin
                    refuse = 1'b1;  refuse_code = E_SEG_K;  discard_d = 1'b1;
                end else if (PTIMER == 0 && (cmd_data_i[15:0] == 16'd0 || {16'd0, cmd_data_i[15:0]} > (32'd1 << CAW))) begin
                    refuse = 1'b1;  refuse_code = E_SEG_CHUNKS;  discard_d = 1'b1;
                end else if (PTIMER != 0 && !form_ok) begin
                    refuse = 1'b1;  refuse_code = E_SEG_FORM;  discard_d = 1'b1;
                end else if (hdr_conic_d && (hdr_au_d == hdr_av_d || {29'd0, hdr_au_d} >= N ||
                                             {29'd0, hdr_av_d} >= N)) begin
                    refuse = 1'b1;  refuse_code = E_CONIC_AXES;  discard_d = 1'b1;
                end else if (hdr_cont_d && !(lc_valid_q && lc_au_q == hdr_au_d && lc_av_q == hdr_av_d &&
                                             lc_cw_q == hdr_cw_d)) begin
                    refuse = 1'b1;  refuse_code = E_CONIC_CONT;  discard_d = 1'b1;
                end
            end
            p_state_d = P_H1;
        end else begin
            refuse = 1'b1;  refuse_code = E_BAD_OPCODE;
        end
        OP_PHASE: if (PTIMER != 0) begin
            // W0 = {kind, 4'b0, ticks} kept for the end; u next.
            interval_d = {cmd_data_i[27:24], 4'd0, cmd_data_i[23:0]};
            v_idx_d    = 3'd1;
            discard_d  = fault_i;
            p_state_d  = P_PH;
        end else begin
            refuse = 1'b1;  refuse_code = E_BAD_OPCODE;
        end
        OP_CONFIG: begin
            // Refused while running, and while a STEP pulse is still high (after ABORT,
            // E-stop or the run's last move): a polarity or timing write never cuts it.
            if (running_i || pulse_busy_i) begin
                refuse = 1'b1;  refuse_code = E_CONFIG_BUSY;
            end else if ({28'd0, cmd_data_i[27:24]} >= N || cfg_field_bad ||
                         (cmd_data_i[23:20] <= 4'd1 && cmd_data_i[15:0] == 16'd0) ||
                         (cmd_data_i[23:20] <= 4'd3 && (cmd_data_i[15:0] & ~TMASK) != 16'd0)) begin
                refuse = 1'b1;  refuse_code = E_CONFIG_VALUE;
            end else begin
                cfg_write_o = 1'b1;
            end
        end
        OP_CONTROL: begin
            start_o       = cmd_data_i[0];
            abort_o       = cmd_data_i[1];
            clear_o       = cmd_data_i[2];
            drivers_on_o  = cmd_data_i[3];
            drivers_off_o = cmd_data_i[4];
        end
        OP_READ: begin
            rsp_valid_d = 1'b1;
            rsp_data_d  = read_data_i;
            rsp_addr_d  = cmd_data_i[7:0];
            p_state_d   = P_RSP;
        end
        default: begin
            refuse = 1'b1;  refuse_code = E_BAD_OPCODE;
        end
        endcase
    end

    P_H1: if (take) begin
        seg_u_d     = cmd_data_i[23:0];
        seg_wr_o    = keep;
        seg_wide    = {{(41-30-N){1'b0}}, hdr_out_q, hdr_end_q, hdr_k_q, cmd_data_i[24 +: N], cmd_data_i[23:0]};
        seg_wide[30+N] = CONIC != 0 && hdr_conic_q;
        seg_wide[31+N] = CONIC != 0 && hdr_cont_q;
        seg_wdata_o = seg_wide[SWW-1:0];
        if (keep && (cmd_data_i[23:0] == 24'd0 || {8'd0, cmd_data_i[23:0]} > UMAX)) begin
            refuse = 1'b1;  refuse_code = E_SEG_U;  discard_d = 1'b1;
        end
        v_idx_d   = 3'd0;
        p_state_d = P_V;
    end

    // (An axis the compact form does not send: its v_i written without a word taken.)
    P_V: if (v_step) begin
        seg_wr_o    = keep;
        seg_wdata_o = {{(SWW-24){1'b0}}, v_value};
        // A conic's plane axes step by the conic engine: their v must be 0.
        if (keep && CONIC != 0 && hdr_conic_q && (v_idx_q == hdr_au_q || v_idx_q == hdr_av_q) &&
            v_value != 24'd0) begin
            refuse = 1'b1;  refuse_code = E_CONIC_AXES;  discard_d = 1'b1;
        end else if (keep && v_value > seg_u_q) begin
            refuse = 1'b1;  refuse_code = E_SEG_V_GT_U;  discard_d = 1'b1;
        end
        v_idx_d = v_idx_q + 1'b1;
        // A segment announced with no chunk was refused at its header; it ends here.
        if ({29'd0, v_idx_q} == N - 1) begin
            v_idx_d   = hdr_cont_q ? 3'd5 : 3'd0;   // a continuation has K5, K6 only
            p_state_d = (CONIC != 0 && hdr_conic_q) ? P_K : (PTIMER != 0) ? P_L :
                        (nchunks_q == 16'd0) ? P_CMD : P_C0;
        end
    end

    // A conic's words K0 .. K6, as they come but K1: the header's plane axes and
    // direction go with C to the builder, {cw, u, v, 9'b0, C}.
    P_K: if (CONIC != 0 && take) begin
        seg_wr_o = keep;
        seg_wide = {9'd0, cmd_data_i};
        if (v_idx_q == 3'd1) seg_wide[31:16] = {hdr_cw_q, hdr_au_q, hdr_av_q, 9'd0};
        if (v_idx_q == 3'd5 && hdr_cont_q) seg_wide[31:24] = {hdr_cw_q, hdr_au_q, hdr_av_q, 1'b0};
        seg_wdata_o = seg_wide[SWW-1:0];
        v_idx_d = v_idx_q + 1'b1;
        if (v_idx_q == 3'd6) p_state_d = (PTIMER != 0) ? P_L : (nchunks_q == 16'd0) ? P_CMD : P_C0;
    end

    // A PTIMER segment's length per move, its last word: committed, or rolled back.
    P_L: if (PTIMER != 0 && take) begin
        seg_wr_o  = keep;
        seg_wide  = {9'd0, cmd_data_i};
        seg_wdata_o = seg_wide[SWW-1:0];
        p_state_d = P_CMD;
        if (keep && cmd_data_i == 32'd0) begin
            refuse = 1'b1;  refuse_code = E_SEG_LENGTH;  discard_d = 1'b1;
        end
        seg_rollback_o = !keep || refuse;
        seg_commit_o   = keep && !refuse;
    end

    // A PHASE's words after H0, as the phase timer's; then W0 and the commit.
    P_PH: if (PTIMER != 0 && take) begin
        ch_wr_o = keep;
        v_idx_d = ph_next;
        if (ph_next == 3'd0) p_state_d = P_PW0;
    end
    P_PW0: if (PTIMER != 0 && (!keep || !ch_full_i)) begin
        ch_wr_o       = keep;
        ch_commit_o   = keep;
        ch_rollback_o = !keep;
        p_state_d     = P_CMD;
    end

    // (The chunk states: never reached in PTIMER builds, so their logic is not built.)
    P_C0: if (PTIMER == 0 && take) begin
        interval_d = cmd_data_i;
        p_state_d  = P_C1;
    end

    P_C1: if (PTIMER == 0 && take) begin
        count_d = c1_count;
        add_d   = c1_add;
        sum_d   = sum_q + {18'd0, c1_count};
        if (keep && (interval_q == 32'd0 || c1_count == 16'd0)) begin
            refuse = 1'b1;  refuse_code = E_SEG_CHUNK_ZERO;  discard_d = 1'b1;
        end
        if (seg_add2_q) begin
            p_state_d = P_C2;
        end else begin
            // The chunk's last word: add2 = 0.
            add2_d  = 16'd0;
            ch_wr_o = keep;
            p_state_d = P_CHK;
        end
    end

    P_C2: if (PTIMER == 0 && take) begin
        add2_d  = c2_add2;
        ch_wr_o = keep;
        p_state_d = P_CHK;
    end

    P_CHK: if (PTIMER == 0) begin
        // The last clock of the check: the last increment must not have the
        // opposite sign of add; the last delay must be 1 .. 2^32-1. Then, after the
        // segment's last chunk, the count sum and the commit.
        if (ck_i_q == CHECK_LAST) begin
            if (keep && inc_flip) begin
                refuse = 1'b1;  refuse_code = E_SEG_ADD2;  discard_d = 1'b1;
            end else if (keep && dl_bad) begin
                refuse = 1'b1;  refuse_code = E_SEG_DELAY;  discard_d = 1'b1;
            end
            nchunks_d = nchunks_q - 1'b1;
            if (nchunks_q != 16'd1) begin
                p_state_d = P_C0;
            end else if (!keep || refuse) begin
                ch_rollback_o  = 1'b1;
                seg_rollback_o = 1'b1;
                p_state_d      = P_CMD;
            end else if (sum_ne_q) begin
                refuse = 1'b1;  refuse_code = E_SEG_COUNT_SUM;
                ch_rollback_o  = 1'b1;
                seg_rollback_o = 1'b1;
                p_state_d      = P_CMD;
            end else begin
                // The whole segment passed: its words and its chunks appear together.
                seg_commit_o = 1'b1;
                ch_commit_o  = 1'b1;
                p_state_d    = P_CMD;
            end
        end
    end

    P_RSP: if (!rsp_valid_q || rsp_ready_i) p_state_d = P_CMD;

    default: p_state_d = P_CMD;
    endcase

    // A fault (E-stop among them) or an ABORT flushes the walk a continuation would
    // go on from.
    // A segment committed: what a continuation may follow (a conic, its axes and way).
    if (seg_commit_o) begin
        lc_valid_d = hdr_conic_q;
        lc_au_d    = hdr_au_q;
        lc_av_d    = hdr_av_q;
        lc_cw_d    = hdr_cw_q;
    end
    if (fault_i || refuse || abort_o) lc_valid_d = 1'b0;
    fault_o      = refuse;
    fault_code_o = refuse_code;
    // FLUSH: back to a command's first word; what this cycle would have done is not
    // done (the queues are emptied in this cycle: nothing to commit or roll back).
    if (flush_i) begin
        p_state_d = P_CMD;  discard_d = 1'b0;  rsp_valid_d = 1'b0;  lc_valid_d = 1'b0;
        seg_wr_o = 1'b0;  seg_commit_o = 1'b0;  seg_rollback_o = 1'b0;
        ch_wr_o = 1'b0;  ch_commit_o = 1'b0;  ch_rollback_o = 1'b0;
        start_o = 1'b0;  abort_o = 1'b0;  clear_o = 1'b0;  drivers_on_o = 1'b0;  drivers_off_o = 1'b0;
        cfg_write_o = 1'b0;  fault_o = 1'b0;  fault_code_o = 8'd0;
    end
end

// ---------------------------------------------------------------- registers
always @(posedge clk) begin
    if (rst) begin
        p_state_q   <= P_CMD;
        discard_q   <= 1'b0;
        rsp_valid_q <= 1'b0;
        lc_valid_q  <= 1'b0;
    end else begin
        p_state_q   <= p_state_d;
        discard_q   <= discard_d;
        rsp_valid_q <= rsp_valid_d;
        lc_valid_q  <= lc_valid_d;
    end
    hdr_end_q <= hdr_end_d;  hdr_out_q <= hdr_out_d;  hdr_k_q <= hdr_k_d;  seg_u_q <= seg_u_d;
    nchunks_q <= nchunks_d;  v_idx_q <= v_idx_d;
    interval_q <= interval_d;  count_q <= count_d;  add_q <= add_d;  add2_q <= add2_d;
    sum_q <= sum_d;  seg_add2_q <= seg_add2_d;
    hdr_conic_q <= hdr_conic_d;  hdr_au_q <= hdr_au_d;  hdr_av_q <= hdr_av_d;  hdr_cw_q <= hdr_cw_d;
    hdr_cont_q <= hdr_cont_d;  lc_au_q <= lc_au_d;  lc_av_q <= lc_av_d;  lc_cw_q <= lc_cw_d;
    ck_i_q <= ck_i_d;  acc1_q <= acc1_d;  acc2_q <= acc2_d;
    c1_q <= c1_d;  c2_q <= c2_d;  c3_q <= c3_d;  b_q <= b_d;  li_sign_q <= li_sign_d;
    li_nz_q <= li_nz_d;  dl_nz_q <= dl_nz_d;  dl_hi_q <= dl_hi_d;  sum_ne_q <= sum_ne_d;
    rsp_data_q <= rsp_data_d;  rsp_addr_q <= rsp_addr_d;
end

// ---------------------------------------------------------------- outputs
assign cmd_ready_o = (p_state_q == P_CMD) ||
                     ((p_state_q == P_H1 || (p_state_q == P_V && v_sent) || p_state_q == P_K || p_state_q == P_L) &&
                      (!keep || !seg_full_i)) ||
                     (p_state_q == P_PH && (!keep || !ch_full_i)) ||
                     (PTIMER == 0 && p_state_q == P_C0) ||
                     (PTIMER == 0 && p_state_q == P_C1 && (seg_add2_q || !keep || !ch_full_i)) ||
                     (PTIMER == 0 && p_state_q == P_C2 && (!keep || !ch_full_i));
assign rsp_valid_o = rsp_valid_q;
assign rsp_data_o  = rsp_valid_q ? rsp_data_q : 32'd0;
assign rsp_addr_o  = rsp_valid_q ? rsp_addr_q : 8'd0;

endmodule

`resetall
