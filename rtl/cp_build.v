// SPDX-License-Identifier: MIT
// cp_build — the motion core's pattern builder.
//
// Takes the next committed segment from the segment queue (its header, then v_i
// for each axis in turn) once a lane is free, and writes each axis's pattern
// into the build lane of that axis's bank (in cp_run): a constant pattern
// (v = 0 or v = U) is one move; any other is built by the one Castle–Pitteway
// engine from the unreduced (U, v_i), whose first period M2·reverse(M1) is
// copied one move a clock. When the last axis is written, the segment (torch output, lane,
// end flag, moving axes, directions) goes into the run queue and the build lane
// flips. It also counts the committed segments waiting in the segment queue.
//
// A CONIC segment (CONIC = 1, docs/CORE.md): its plane axes have v = 0 (constant
// patterns); after the last axis, once the conic walker is free (the previous
// conic's last move taken), its seven words go from the segment queue into the
// walker, one a clock, the last with the walker's start, and the segment goes into
// the run queue with its plane axes.
//
// With PTIMER = 1 (the phase timer's build) a segment's last word is its length per
// move L: the segment goes into the run queue with it, its k and its U (the run
// counts its moves U*2^k itself), after its last axis (or its conic's words).
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_build.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_build #(
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer UMAX = 1048575,
    parameter integer SAW = 2,
    parameter integer CONIC = 0,
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          flush_i,          // empty everything (cp_status)
    input  wire          fault_i,          // a fault is latched: start nothing new

    // Segment queue head, and the parser's commit of a whole segment.
    input  wire          seg_valid_i,
    input  wire [SWW-1:0] seg_head_i,
    output reg           seg_pop_o,
    input  wire          seg_commit_i,

    // Lanes in use by the runner: built segments waiting, and the one loaded.
    input  wire [1:0]    run_level_i,
    input  wire          cur_valid_i,
    output reg           run_wr_o,
    output reg  [RDW-1:0] run_wdata_o,     // {[L, k, U,] [conic, u, v,] out, lane, end, moving[N], dir[N]}

    // Write port of the pattern banks (cp_run): axis, address, bit, in the build
    // lane; and the pattern's length - 1 when an axis is done.
    output reg           bank_we_o,
    output wire [2:0]    bank_axis_o,
    output reg  [AW-1:0] bank_waddr_o,
    output reg           bank_wbit_o,
    output wire          build_lane_o,
    output reg           len_we_o,
    output wire [AW-1:0] len_m1_o,

    // The conic walker (in cp_run): free for the next conic, and its word port.
    input  wire          walker_free_i,
    output reg           cw_wr_o,
    output reg  [2:0]    cw_sel_o,
    output reg  [31:0]   cw_data_o,
    output reg           cw_start_o,
    output reg           cw_cont_o,        // with cw_start_o: the walk continues the last one

    output reg           fault_o,          // the engine refused a pattern (too long)
    output wire          busy_o,           // a segment is being built
    output wire [SQW:0]  segq_o            // committed segments in the segment queue
);

localparam integer UW = $clog2(UMAX + 2);           // engine u/v width
localparam integer AW = (W > 2) ? $clog2(W) : 1;
localparam integer SQW = SAW + $clog2(N + 1 + ((PTIMER != 0) ? 1 : 0));
localparam integer SWW0 = (CONIC == 0) ? 30 + N : 32 + N;
localparam integer SWW = (PTIMER != 0 && SWW0 < 32) ? 32 : SWW0;   // (a PTIMER segment's L: 32 bits)
localparam integer RCW = 3 + 2 * N + ((CONIC == 0) ? 0 : 7);
localparam integer RDW = RCW + ((PTIMER == 0) ? 0 : 60);

localparam [2:0] B_IDLE = 3'd0;   // waiting for a committed segment and a free lane
localparam [2:0] B_V    = 3'd1;   // next axis: its v_i at the segment queue's head
localparam [2:0] B_CAP  = 3'd2;   // the engine's first period into the bank
localparam [2:0] B_K    = 3'd3;   // a conic's seven words into the walker
localparam [2:0] B_L    = 3'd4;   // PTIMER: the length per move, and the run queue

reg [2:0]    b_state_q, b_state_d;       // reset
reg [3:0]    b_k_q, b_k_d;               // PTIMER: the segment's k
reg          build_lane_q, build_lane_d; // reset
reg [SQW:0]  segq_q, segq_d;             // reset
reg [2:0]    b_axis_q, b_axis_d;
reg [UW-1:0] b_u_q, b_u_d;
reg          b_end_q, b_end_d;
reg          b_out_q, b_out_d;           // the torch output while the segment runs
reg [N-1:0]  b_dir_q, b_dir_d, b_moving_q, b_moving_d;
reg [AW-1:0] cap_addr_q, cap_addr_d;
reg          b_conic_q, b_conic_d;       // the segment being built is a conic
reg          b_cont_q, b_cont_d;         // ... that continues the last walk (K5, K6 only)
reg [2:0]    b_au_q, b_au_d, b_av_q, b_av_d, k_idx_q, k_idx_d;

// Segment queue word fields.
wire          head_end = seg_head_i[28 + N];
wire          head_out = seg_head_i[29 + N];
wire [N-1:0]  head_dir = seg_head_i[24 +: N];
wire [23:0]   head_val = seg_head_i[23:0];
wire [40:0]   head_wide = {{(41-SWW){1'b0}}, seg_head_i};
wire          head_conic = CONIC != 0 && head_wide[30 + N];
wire          head_cont  = CONIC != 0 && head_wide[31 + N];
wire unused_head = &{1'b0, head_wide[40:32]};

// ---------------------------------------------------------------- the engine
reg            eng_in_valid, eng_move_ready, eng_rst, cap_done;
wire           eng_in_ready, eng_err, eng_move_valid, eng_move, eng_move_last, eng_move_pend;
wire [2:0]     eng_err_code;
wire           dbg_we1, dbg_wbit1, dbg_we2, dbg_wbit2, dbg_iter, dbg_m1_rev, dbg_m2_rev;
wire [AW-1:0]  dbg_waddr1, dbg_waddr2, dbg_m1_lo, dbg_m1_len, dbg_m2_lo, dbg_m2_len;
wire [UW-1:0]  dbg_x, dbg_y;

cp_engine #(.W(W), .UMAX(UMAX), .KMAX(0), .RW(1), .ONE_PERIOD(1)) u_engine (
    .clk(clk), .rst(rst || eng_rst),
    .in_valid_i(eng_in_valid), .in_ready_o(eng_in_ready),
    .in_u_i(b_u_q), .in_v_i(head_val[UW-1:0]), .in_k_i(1'b0), .in_rep_i(1'b1),
    .err_o(eng_err), .err_code_o(eng_err_code),
    .move_valid_o(eng_move_valid), .move_ready_i(eng_move_ready),
    .move_o(eng_move), .move_last_o(eng_move_last), .move_pend_o(eng_move_pend),
    .dbg_we1_o(dbg_we1), .dbg_waddr1_o(dbg_waddr1), .dbg_wbit1_o(dbg_wbit1),
    .dbg_we2_o(dbg_we2), .dbg_waddr2_o(dbg_waddr2), .dbg_wbit2_o(dbg_wbit2),
    .dbg_iter_o(dbg_iter), .dbg_x_o(dbg_x), .dbg_y_o(dbg_y),
    .dbg_m1_lo_o(dbg_m1_lo), .dbg_m1_len_o(dbg_m1_len), .dbg_m1_rev_o(dbg_m1_rev),
    .dbg_m2_lo_o(dbg_m2_lo), .dbg_m2_len_o(dbg_m2_len), .dbg_m2_rev_o(dbg_m2_rev));
// The debug port is for the engine's own bench; the code is not needed (one refusal).
wire unused = &{1'b0, dbg_we1, dbg_wbit1, dbg_we2, dbg_wbit2, dbg_iter,
                dbg_m1_rev, dbg_m2_rev, dbg_waddr1, dbg_waddr2, dbg_m1_lo,
                dbg_m1_len, dbg_m2_lo, dbg_m2_len, dbg_x, dbg_y, eng_err_code, eng_move_last};

// ---------------------------------------------------------------- next state
// A run queue word with the conic fields, before it is cut to RCW bits (and one
// spare bit, so that the part a build without conics drops is never empty); with
// PTIMER the fields {L, k, U} above them.
localparam integer RFW = 10 + 2 * N;
reg [RFW:0] run_wide;
wire unused_run = &{1'b0, run_wide[RFW:RCW]};
reg [RCW+60:0] run_x;     // the word written: run_wide's fields, then L, k, U
wire [24:0] b_u25 = {{(25-UW){1'b0}}, b_u_q};
wire unused_x = &{1'b0, b_u25[24], run_x};   // (the bits past RDW)
always @* begin
    run_wide = {(RFW+1){1'b0}};
    run_x = {(RCW+61){1'b0}};
    b_state_d = b_state_q;  build_lane_d = build_lane_q;
    segq_d = segq_q + {{SQW{1'b0}}, seg_commit_i};
    b_axis_d = b_axis_q;  b_u_d = b_u_q;  b_end_d = b_end_q;  b_out_d = b_out_q;
    b_dir_d = b_dir_q;  b_moving_d = b_moving_q;  cap_addr_d = cap_addr_q;
    b_conic_d = b_conic_q;  b_cont_d = b_cont_q;  b_au_d = b_au_q;  b_av_d = b_av_q;  k_idx_d = k_idx_q;
    b_k_d = b_k_q;
    seg_pop_o = 1'b0;  run_wr_o = 1'b0;  run_wdata_o = {RDW{1'b0}};
    cw_wr_o = 1'b0;  cw_sel_o = k_idx_q;  cw_data_o = head_wide[31:0];  cw_start_o = 1'b0;
    cw_cont_o = 1'b0;
    bank_we_o = 1'b0;  bank_waddr_o = {AW{1'b0}};  bank_wbit_o = 1'b0;
    eng_in_valid = 1'b0;  eng_move_ready = 1'b0;  cap_done = 1'b0;
    fault_o = 1'b0;

    case (b_state_q)
    B_IDLE: if (seg_valid_i && !fault_i && {1'b0, run_level_i} + {2'd0, cur_valid_i} <= 3'd1) begin
        seg_pop_o  = 1'b1;
        segq_d     = segq_d - 1'b1;
        b_u_d      = head_val[UW-1:0];
        b_dir_d    = head_dir;
        b_end_d    = head_end;
        b_out_d    = head_out;
        b_conic_d  = head_conic;
        b_cont_d   = head_cont;
        b_k_d      = seg_head_i[24 + N +: 4];
        b_axis_d   = 3'd0;
        b_moving_d = {N{1'b0}};
        b_state_d  = B_V;
    end
    B_V: if (seg_valid_i && eng_in_ready) begin
        seg_pop_o  = 1'b1;
        b_moving_d = b_moving_q | ({{(N-1){1'b0}}, head_val != 24'd0} << b_axis_q);
        if (head_val == 24'd0 || head_val[UW-1:0] == b_u_q) begin
            // A constant pattern: one move.
            bank_we_o    = 1'b1;
            bank_waddr_o = {AW{1'b0}};
            bank_wbit_o  = head_val != 24'd0;
            cap_done     = 1'b1;
        end else begin
            eng_in_valid = 1'b1;
            cap_addr_d   = {AW{1'b0}};
            b_state_d    = B_CAP;
        end
    end
    B_CAP: begin
        eng_move_ready = 1'b1;
        if (eng_move_valid) begin
            bank_we_o    = 1'b1;
            bank_waddr_o = cap_addr_q;
            bank_wbit_o  = eng_move;
            cap_addr_d   = cap_addr_q + 1'b1;
            cap_done     = eng_move_pend;
        end
        if (eng_err) begin
            fault_o   = 1'b1;
            b_state_d = B_IDLE;
        end
    end
    B_K: if (CONIC != 0 && seg_valid_i && walker_free_i) begin
        // K1 carries the plane axes: {cw, u, v, 9 zeros, C}; a continuation has only
        // K5 and K6, and K5 carries them: {cw, u, v, 0, du}.
        seg_pop_o = 1'b1;
        cw_wr_o   = 1'b1;
        if (k_idx_q == (b_cont_q ? 3'd5 : 3'd1)) begin
            b_au_d = head_wide[30:28];
            b_av_d = head_wide[27:25];
        end
        k_idx_d = k_idx_q + 1'b1;
        if (k_idx_q == 3'd6) begin
            cw_start_o   = 1'b1;
            cw_cont_o    = b_cont_q;
            if (PTIMER != 0) begin
                b_state_d    = B_L;
            end else begin
                run_wr_o     = 1'b1;
                run_wide     = {2'b01, b_au_q, b_av_q, b_out_q, build_lane_q, b_end_q, b_moving_q, b_dir_q};
                build_lane_d = !build_lane_q;
                b_state_d    = B_IDLE;
            end
        end
    end
    // PTIMER: the segment's last word, its length per move, goes with it into the run queue.
    B_L: if (PTIMER != 0 && seg_valid_i) begin
        seg_pop_o    = 1'b1;
        run_wr_o     = 1'b1;
        run_wide     = {1'b0, b_conic_q, b_au_q, b_av_q, b_out_q, build_lane_q, b_end_q, b_moving_q, b_dir_q};
        build_lane_d = !build_lane_q;
        b_state_d    = B_IDLE;
    end
    default: b_state_d = B_IDLE;
    endcase
    if (cap_done) begin
        if ({29'd0, b_axis_q} == N - 1 && CONIC != 0 && b_conic_q) begin
            k_idx_d   = b_cont_q ? 3'd5 : 3'd0;
            b_state_d = B_K;
        end else if ({29'd0, b_axis_q} == N - 1 && PTIMER != 0) begin
            b_state_d    = B_L;
        end else if ({29'd0, b_axis_q} == N - 1) begin
            run_wr_o     = 1'b1;
            run_wide     = {8'd0, b_out_q, build_lane_q, b_end_q, b_moving_d, b_dir_q};
            build_lane_d = !build_lane_q;
            b_state_d    = B_IDLE;
        end else begin
            b_axis_d  = b_axis_q + 1'b1;
            b_state_d = B_V;
        end
    end
    if (flush_i) begin
        b_state_d    = B_IDLE;
        build_lane_d = 1'b0;
        segq_d       = {(SQW+1){1'b0}};
    end
    len_we_o = cap_done;
    run_x = {1'b0, head_wide[31:0], b_k_q, b_u25[23:0], run_wide[RCW-1:0]};
    if (run_wr_o) run_wdata_o = run_x[RDW-1:0];
end

// The engine is reset when a pattern's first period is in its bank, and by a flush.
always @* eng_rst = flush_i || (b_state_q == B_CAP && cap_done);

// ---------------------------------------------------------------- registers
always @(posedge clk) begin
    if (rst) begin
        b_state_q    <= B_IDLE;
        build_lane_q <= 1'b0;
        segq_q       <= {(SQW+1){1'b0}};
    end else begin
        b_state_q    <= b_state_d;
        build_lane_q <= build_lane_d;
        segq_q       <= segq_d;
    end
    b_axis_q <= b_axis_d;  b_u_q <= b_u_d;  b_end_q <= b_end_d;  b_out_q <= b_out_d;
    b_dir_q <= b_dir_d;  b_moving_q <= b_moving_d;  cap_addr_q <= cap_addr_d;
    b_conic_q <= b_conic_d;  b_cont_q <= b_cont_d;  b_au_q <= b_au_d;  b_av_q <= b_av_d;  k_idx_q <= k_idx_d;
    b_k_q <= b_k_d;
end

// ---------------------------------------------------------------- outputs
assign bank_axis_o  = b_axis_q;
assign build_lane_o = build_lane_q;
// The pattern's length - 1: the last address written (a constant pattern: 0).
assign len_m1_o     = (b_state_q == B_CAP) ? cap_addr_q : {AW{1'b0}};
assign busy_o       = b_state_q != B_IDLE;
assign segq_o       = segq_q;

endmodule

`resetall
