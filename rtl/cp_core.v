// cp_core — the motion core: command port, segment and chunk queues, one
// Castle–Pitteway engine that builds every axis's pattern into that axis's
// two-lane pattern bank (double buffering), the replay, the move-event timer,
// per-axis pulse timing, status and faults.
//
// docs/CORE.md is the contract: the command words, the validation and fault
// codes, and the cycle behaviour the golden model (model/cp_core.*) follows.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_core #(
    // Number of axes (x y z a ...).
    parameter integer N = 4,
    // Pattern capacity of the engine and the banks: the longest pattern U/gcd(U, v).
    parameter integer W = 1024,
    // Largest move count U of a segment (before doubling).
    parameter integer UMAX = 1048575,
    // Largest step-doubling exponent k.
    parameter integer KMAX = 8,
    // Chunk queue address width: it holds 2^CAW chunks plus its head.
    parameter integer CAW = 6,
    // Segment queue address width.
    parameter integer SAW = 2,
    // Width of the pulse timing fields.
    parameter integer TW = 16,
    // Width of the position counters.
    parameter integer PW = 32,
    // The chunk check's multiplier: 0 bit-serial in logic (one adder), 1 a hard
    // multiplier (`*`: the iCE40 UP5K's SB_MAC16 DSP blocks). Same cycles either way.
    parameter integer MUL_DSP = 0,
    // Pulse timing after reset, in clock cycles (the host configures the real ones).
    parameter integer STEP_HIGH_RESET = 1,
    parameter integer STEP_LOW_RESET = 1,
    parameter integer DIR_SETUP_RESET = 1,
    parameter integer DIR_HOLD_RESET = 1,
    // Pin polarity after reset: 1 = STEP active high, 1 = DIR high is positive.
    parameter [0:0] STEP_POL_RESET = 1'b1,
    parameter [0:0] DIR_POL_RESET = 1'b1,
    // Only reported, in the capability registers (READ 0x23..0x25): the address
    // width of the command buffer in front of the core (cp_spi; 0: none), the
    // clock in Hz and the build id (rtl/builds.json sets them for every build).
    parameter integer CBUF_AW = 0,
    parameter integer CLK_HZ = 48000000,
    parameter [31:0] BUILD_ID = 32'h0
) (
    input  wire          clk,
    input  wire          rst,

    // Command words (docs/CORE.md).
    input  wire          cmd_valid_i,
    output wire          cmd_ready_o,
    input  wire [31:0]   cmd_data_i,
    // Replies to READ.
    output wire          rsp_valid_o,
    input  wire          rsp_ready_i,
    output wire [31:0]   rsp_data_o,
    output wire [7:0]    rsp_addr_o,       // the register the reply names
    // A second read of the READ registers, combinational, at any time (the SPI
    // front end's reply words).
    input  wire [7:0]    rd_addr_i,
    output wire [31:0]   rd_data_o,

    // E-stop, synchronous to clk, active high.
    input  wire          estop_i,

    // Pins.
    output wire [N-1:0]  step_o,
    output wire [N-1:0]  dir_o,

    // Status, also readable over the command port.
    output wire          running_o,
    output wire          fault_o,
    output wire [7:0]    err_code_o,
    output wire          stretched_o,
    output wire [N*PW-1:0] position_o,
    // Drivers enabled (CONTROL bits 3/4; E-stop forces off).
    output wire          enable_o,
    // The READ registers 0x00..0x03, live (the SPI front end's status reply).
    output wire [31:0]   status_o,
    output wire [31:0]   stretch_cnt_o,
    output wire [31:0]   moves_done_o,
    output wire [31:0]   segs_done_o
);

// ---------------------------------------------------------------- constants
localparam integer UW = $clog2(UMAX + 2);           // engine u/v width
// Pattern bank address width: a bank holds one pattern of up to W moves.
localparam integer AW = (W > 2) ? $clog2(W) : 1;
// Segment queue word: the header {end, k, dir[N], U} or a v_i in [23:0].
localparam integer SWW = 29 + N;
// Segment queue address width: 2^SAW segments of N + 1 words each, at least.
localparam integer SQW = SAW + $clog2(N + 1);
// A built segment, waiting in the run queue: lane, end, moving[N], dir[N].
localparam integer RDW = 2 + 2 * N;
// Chunk queue word: last chunk of its segment, add2, count, add, interval.
localparam integer CDW = 81;

localparam [3:0] OP_SEGMENT = 4'h1;
localparam [3:0] OP_CONFIG  = 4'h2;
localparam [3:0] OP_CONTROL = 4'h3;
localparam [3:0] OP_READ    = 4'h4;

localparam [7:0] E_NONE           = 8'd0;
localparam [7:0] E_SEG_U          = 8'd1;
localparam [7:0] E_SEG_V_GT_U     = 8'd2;
localparam [7:0] E_SEG_K          = 8'd3;
localparam [7:0] E_SEG_CHUNKS     = 8'd4;
localparam [7:0] E_SEG_CHUNK_ZERO = 8'd5;
localparam [7:0] E_SEG_DELAY      = 8'd6;
localparam [7:0] E_SEG_COUNT_SUM  = 8'd7;
localparam [7:0] E_SEG_PATTERN    = 8'd8;
localparam [7:0] E_UNDERRUN       = 8'd9;
localparam [7:0] E_ESTOP          = 8'd10;
localparam [7:0] E_ABORT          = 8'd11;
localparam [7:0] E_BAD_OPCODE     = 8'd12;
localparam [7:0] E_CONFIG_BUSY    = 8'd13;
localparam [7:0] E_CONFIG_VALUE   = 8'd14;
localparam [7:0] E_SEG_ADD2       = 8'd15;
// The bits of a 16-bit CONFIG value that a TW-bit timing field holds.
localparam [15:0] TMASK = (TW >= 16) ? 16'hFFFF : ((16'd1 << TW) - 16'd1);

localparam [3:0] P_CMD  = 4'd0;   // first word of a command
localparam [3:0] P_H1   = 4'd1;   // segment: dir and U
localparam [3:0] P_V    = 4'd2;   // segment: v_i
localparam [3:0] P_C0   = 4'd3;   // chunk: interval
localparam [3:0] P_C1   = 4'd4;   // chunk: add and count
localparam [3:0] P_MUL  = 4'd5;   // chunk: checking its last delay
localparam [3:0] P_RSP  = 4'd6;   // a reply waits to be taken
localparam [3:0] P_C2   = 4'd7;   // chunk: add2 (segments whose chunks carry it)
localparam [3:0] P_INC  = 4'd8;   // chunk: its last increment add + (count-2)*add2
// Width of the validator's products: |(count-1)*(add + last increment)| < 2^47.
localparam integer MW = 49;

generate
    if (N < 1 || N > 8) begin : g_check_n
        cp_core_parameter_N_must_be_1_to_8 u_bad ();
    end
    if (UMAX < W || UMAX > 16777214) begin : g_check_umax
        cp_core_parameter_UMAX_must_be_W_to_2pow24_minus_2 u_bad ();
    end
    if (KMAX > 10) begin : g_check_kmax
        cp_core_parameter_KMAX_must_be_at_most_10 u_bad ();
    end
    if (TW < 1 || TW > 16) begin : g_check_tw
        cp_core_parameter_TW_must_be_1_to_16 u_bad ();
    end
    if (PW < 32) begin : g_check_pw
        cp_core_parameter_PW_must_be_at_least_32 u_bad ();
    end
    if (CAW < 1 || CAW > 15) begin : g_check_caw
        cp_core_parameter_CAW_must_be_1_to_15 u_bad ();
    end
    if (CBUF_AW < 0 || CBUF_AW > 14) begin : g_check_cbuf_aw
        cp_core_parameter_CBUF_AW_must_be_0_to_14 u_bad ();
    end
    if (CLK_HZ < 1) begin : g_check_clk_hz
        cp_core_parameter_CLK_HZ_must_be_positive u_bad ();
    end
    if (MUL_DSP < 0 || MUL_DSP > 1) begin : g_check_mul_dsp
        cp_core_parameter_MUL_DSP_must_be_0_or_1 u_bad ();
    end
endgenerate

// ---------------------------------------------------------------- state
// Control (reset).
reg [3:0]    p_state_q, p_state_d;
reg          discard_q, discard_d;       // the segment being read is dropped
reg          rsp_valid_q, rsp_valid_d;
reg          running_q, running_d;
reg          cur_valid_q, cur_valid_d;   // a segment is loaded for running
reg          cur_lane_q, cur_lane_d;
reg          build_lane_q, build_lane_d;
reg          ch_loaded_q, ch_loaded_d;
reg          late_q, late_d;             // the pending move has been counted as stretched
reg [1:0]    b_state_q, b_state_d;       // builder
reg          rp_valid_q, rp_valid_d;     // the replay registers hold the next move
reg [SQW:0]  segq_q, segq_d;             // committed segments in the segment queue
reg          fault_q, fault_d;
reg [7:0]    err_q, err_d;
reg          stretched_q, stretched_d;
reg          enable_q, enable_d;         // drivers enabled
reg [31:0]   stretch_cnt_q, stretch_cnt_d;
reg [31:0]   moves_done_q, moves_done_d;
reg [31:0]   segs_done_q, segs_done_d;
reg [TW-1:0] cfg_high_q [0:N-1];
reg [TW-1:0] cfg_low_q [0:N-1];
reg [TW-1:0] cfg_setup_q [0:N-1];
reg [TW-1:0] cfg_hold_q [0:N-1];
reg [N-1:0]  cfg_step_pol_q, cfg_dir_pol_q;
reg [N-1:0]  dir_q, dir_d;               // direction each axis is to step in

// Datapath (no reset).
reg          hdr_end_q, hdr_end_d;       // the segment being read: end flag, k, U
reg [3:0]    hdr_k_q, hdr_k_d;
reg [23:0]   seg_u_q, seg_u_d;
reg          seg_add2_q, seg_add2_d;     // its chunks carry add2 (three words)
reg [15:0]   nchunks_q, nchunks_d;       // chunks still to read
reg [2:0]    v_idx_q, v_idx_d;
reg [31:0]   interval_q, interval_d;
reg [15:0]   count_q, count_d;
reg [15:0]   add_q, add_d;
reg [15:0]   add2_q, add2_d;
reg [33:0]   sum_q, sum_d;               // chunk counts so far
reg [MW-1:0] prod_q, prod_d;             // a product, built bit by bit
reg [15:0]   mul_a_q, mul_a_d;           // multiplier bits left
reg [MW-1:0] mul_b_q, mul_b_d;           // multiplicand (shifted when bit-serial)
reg [15:0]   mul_a0_q, mul_a0_d;         // the multiplier whole (MUL_DSP)
reg [31:0]   rsp_data_q, rsp_data_d;
reg [7:0]    rsp_addr_q, rsp_addr_d;
reg          cur_end_q, cur_end_d;
reg [31:0]   delay_q, delay_d;
reg [15:0]   left_q, left_d;
reg [31:0]   tinc_q, tinc_d;             // the running increment (signed)
reg [15:0]   tadd2_q, tadd2_d;
reg [31:0]   elapsed_q, elapsed_d;
reg          tlast_q, tlast_d;           // the timer's chunk is its segment's last
// Builder datapath.
reg [2:0]    b_axis_q, b_axis_d;
reg [UW-1:0] b_u_q, b_u_d;
reg          b_end_q, b_end_d;
reg [N-1:0]  b_dir_q, b_dir_d, b_moving_q, b_moving_d;
reg [AW-1:0] cap_addr_q, cap_addr_d;

// ---------------------------------------------------------------- queues
wire          seg_full, seg_head_valid;
wire [SQW:0]  seg_used, seg_level;
wire [SWW-1:0] seg_head;
reg           seg_wr, seg_pop, seg_commit, seg_rollback;
reg [SWW-1:0] seg_wdata;

wire          run_full, run_head_valid;
wire [1:0]    run_used, run_level;
wire [RDW-1:0] run_head;
reg           run_wr, run_pop;
reg [RDW-1:0] run_wdata;

wire          ch_full, ch_head_valid;
wire [CAW:0]  ch_used, ch_level;
wire [CDW-1:0] ch_head;
reg           ch_wr, ch_commit, ch_rollback, ch_pop;

reg           flush;

cp_fifo #(.DW(SWW), .AW(SQW)) u_seg_fifo (
    .clk(clk), .rst(rst), .clear_i(flush),
    .wr_i(seg_wr), .wr_data_i(seg_wdata), .commit_i(seg_commit), .rollback_i(seg_rollback),
    .full_o(seg_full), .used_o(seg_used), .level_o(seg_level),
    .out_valid_o(seg_head_valid), .out_ready_i(seg_pop), .out_data_o(seg_head));

cp_fifo #(.DW(RDW), .AW(1)) u_run_fifo (
    .clk(clk), .rst(rst), .clear_i(flush),
    .wr_i(run_wr), .wr_data_i(run_wdata), .commit_i(1'b1), .rollback_i(1'b0),
    .full_o(run_full), .used_o(run_used), .level_o(run_level),
    .out_valid_o(run_head_valid), .out_ready_i(run_pop), .out_data_o(run_head));

cp_fifo #(.DW(CDW), .AW(CAW)) u_chunk_fifo (
    .clk(clk), .rst(rst), .clear_i(flush),
    .wr_i(ch_wr), .wr_data_i({nchunks_q == 16'd1, add2_d, count_d, add_d, interval_q}),
    .commit_i(ch_commit),
    .rollback_i(ch_rollback),
    .full_o(ch_full), .used_o(ch_used), .level_o(ch_level),
    .out_valid_o(ch_head_valid), .out_ready_i(ch_pop), .out_data_o(ch_head));

// Segment queue word fields.
wire          head_end = seg_head[28 + N];
wire [N-1:0]  head_dir = seg_head[24 +: N];
wire [23:0]   head_val = seg_head[23:0];

genvar ga;

// ---------------------------------------------------------------- pattern builder
// One Castle–Pitteway engine builds every axis's pattern in turn; its first
// period, M2·reverse(M1), is copied into the axis's pattern bank (lane half).
reg            eng_in_valid, eng_move_ready, eng_rst, cap_done;
wire           eng_in_ready, eng_err, eng_move_valid, eng_move, eng_move_last, eng_move_pend;
wire [2:0]     eng_err_code;
wire           unused_dbg;
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
// The debug port is for the engine's own bench.
assign unused_dbg = &{1'b0, dbg_we1, dbg_wbit1, dbg_we2, dbg_wbit2, dbg_iter,
                      dbg_m1_rev, dbg_m2_rev, dbg_waddr1, dbg_waddr2, dbg_m1_lo,
                      dbg_m1_len, dbg_m2_lo, dbg_m2_len, dbg_x, dbg_y};

localparam [1:0] B_IDLE = 2'd0;   // waiting for a committed segment and a free lane
localparam [1:0] B_V    = 2'd1;   // next axis: its v_i at the segment queue's head
localparam [1:0] B_CAP  = 2'd2;   // the engine's first period into the bank

// ---------------------------------------------------------------- pattern banks and replay
// Axis a's bank holds lane l's pattern at {l, address}; the builder writes the
// build lane while the replay reads the running lane, one move a clock.
reg  [N-1:0]   bank_we;
reg  [AW-1:0]  bank_waddr;
reg            bank_wbit;
reg            bank_re;
reg  [AW-1:0]  rp_next [0:N-1];          // the address each axis reads next
reg            rp_lane;                  // and the lane
reg  [AW-1:0]  rp_ptr_q [0:N-1];         // the address of the move in the replay register
reg  [AW-1:0]  lm1_q [0:15];             // lane l, axis a: pattern length - 1 at {l, a}
wire [N-1:0]   lane_move;                // the replay registers: the next move's bits

generate
    for (ga = 0; ga < N; ga = ga + 1) begin : g_bank
        reg bank [0:2*(1<<AW)-1];
        reg rbit_q;
        always @(posedge clk) begin
            if (bank_we[ga]) bank[{build_lane_q, bank_waddr}] <= bank_wbit;
            if (bank_re) rbit_q <= bank[{rp_lane, rp_next[ga]}];
        end
        assign lane_move[ga] = rbit_q;
    end
endgenerate
wire unused_eng = &{1'b0, eng_err_code, eng_move_last, seg_used, run_used, ch_used, seg_level, run_full};

// ---------------------------------------------------------------- pulses
wire [N-1:0]  pulse_ready, pulse_busy;
reg  [N-1:0]  pulse_step;
wire [PW-1:0] pulse_pos [0:N-1];

generate
    for (ga = 0; ga < N; ga = ga + 1) begin : g_pulse
        cp_pulse #(.TW(TW), .PW(PW), .STEP_POL_RESET(STEP_POL_RESET),
                   .DIR_POL_RESET(DIR_POL_RESET)) u_pulse (
            .clk(clk), .rst(rst),
            .cfg_step_high_i(cfg_high_q[ga]), .cfg_step_low_i(cfg_low_q[ga]),
            .cfg_dir_setup_i(cfg_setup_q[ga]), .cfg_dir_hold_i(cfg_hold_q[ga]),
            .cfg_step_pol_i(cfg_step_pol_q[ga]), .cfg_dir_pol_i(cfg_dir_pol_q[ga]),
            .dir_i(dir_q[ga]), .step_i(pulse_step[ga]),
            .ready_o(pulse_ready[ga]), .step_o(step_o[ga]), .dir_o(dir_o[ga]),
            .position_o(pulse_pos[ga]), .busy_o(pulse_busy[ga]));
        assign position_o[PW*ga +: PW] = pulse_pos[ga];
    end
endgenerate
// pulse_busy[a]: axis a's STEP pin is at its active level (CONFIG is refused then).

// ---------------------------------------------------------------- command word fields
wire [3:0]  op        = cmd_data_i[31:28];
wire        take      = cmd_valid_i && cmd_ready_o;
wire [15:0] c1_count  = cmd_data_i[15:0];
wire [15:0] c1_add    = cmd_data_i[31:16];
wire [15:0] c2_add2   = cmd_data_i[15:0];
wire [33:0] seg_moves = {10'd0, seg_u_q} << hdr_k_q;
// Pass 2 of a chunk's check: prod = (count-1)*(add + last increment), even, so the
// last delay is interval + prod/2.
wire [MW:0]   last_delay = {{(MW-31){1'b0}}, interval_q} + {{2{prod_q[MW-1]}}, prod_q[MW-1:1]};
wire [MW-1:0] add_sx   = {{(MW-16){add_q[15]}}, add_q};
// Pass 1: prod = (count-2)*add2; the last increment add + prod.
wire [MW-1:0] last_inc = add_sx + prod_q;
// MUL_DSP: the whole product at once. Every multiplicand fits 34 signed bits
// (2·add, add2, add + last increment: |.| < 2^32 + 2^16), the multiplier 16
// unsigned; the product is taken mod 2^MW like the bit-serial one.
wire signed [16:0] mul_sa   = {1'b0, mul_a0_q};
wire signed [33:0] mul_sb   = mul_b_q[33:0];
wire signed [50:0] mul_full = mul_sa * mul_sb;
wire [MW-1:0]      mul_prod = mul_full[MW-1:0];
wire unused_mul = &{1'b0, mul_full[50:MW]};
wire          inc_flip = (!add_q[15] && add_q != 16'd0 && last_inc[MW-1]) ||
                         (add_q[15] && !last_inc[MW-1] && last_inc != {MW{1'b0}});

wire [31:0] ch_level32 = {{(31 - CAW){1'b0}}, ch_level};
// Segments queued: committed, being built, built and waiting, loaded.
wire [7:0]  segs_queued = {{(7 - SQW){1'b0}}, segq_q} + {7'd0, b_state_q != B_IDLE} +
                          {6'd0, run_level} + {7'd0, cur_valid_q};

// Registers readable by READ.
wire [31:0] status_word = {ch_level32 > 32'd255 ? 8'd255 : ch_level32[7:0],
                           segs_queued,
                           err_q, 3'd0, enable_q, estop_i, stretched_q, fault_q, running_q};
// Capabilities (READ 0x20..0x22): what the host must know of this build.
localparam [31:0] CAPS = {3'd0, TW[4:0], SAW[3:0], CAW[3:0], KMAX[7:0], N[7:0]};
localparam [31:0] W_WORD = W;
localparam [31:0] UMAX_WORD = UMAX;
// The version of the command set and register map (docs/CORE.md) together with
// the SPI frames (docs/PROTOCOL.md); the host refuses a card of another version.
localparam [7:0] PROTOCOL_VERSION = 8'd2;
localparam [31:0] CAPS2 = {8'd0, PROTOCOL_VERSION, CBUF_AW[7:0], PW[7:0]};
localparam [31:0] CLK_WORD = CLK_HZ;
// Two reads: [0] the READ command's, [1] the read port's.
wire [7:0] read_addr [0:1];
assign read_addr[0] = cmd_data_i[7:0];
assign read_addr[1] = rd_addr_i;
reg [31:0] read_value [0:1];
integer    ri, rp;
always @* begin
    for (rp = 0; rp < 2; rp = rp + 1) begin
        read_value[rp] = 32'd0;
        case (read_addr[rp])
        8'h00: read_value[rp] = status_word;
        8'h20: read_value[rp] = CAPS;
        8'h21: read_value[rp] = W_WORD;
        8'h22: read_value[rp] = UMAX_WORD;
        8'h23: read_value[rp] = CAPS2;
        8'h24: read_value[rp] = CLK_WORD;
        8'h25: read_value[rp] = BUILD_ID;
        8'h01: read_value[rp] = stretch_cnt_q;
        8'h02: read_value[rp] = moves_done_q;
        8'h03: read_value[rp] = segs_done_q;
        8'h1F: read_value[rp] = 32'h43505331;   // "CPS1"
        default: begin
            for (ri = 0; ri < N; ri = ri + 1)
                if (read_addr[rp] == 8'h10 + ri[7:0]) read_value[rp] = pulse_pos[ri][31:0];
        end
        endcase
    end
end

// ---------------------------------------------------------------- next state
reg        fire, due, seg_done, fault_set, start_cmd, abort_cmd, clear_cmd, cfg_write;
reg        drivers_on, drivers_off;
reg        clearing, stretch_inc;
reg [N-1:0] b_axis_onehot;
reg [7:0]  fault_code;
integer    i;

always @* begin
    p_state_d   = p_state_q;
    discard_d   = discard_q;
    rsp_valid_d = rsp_valid_q && !rsp_ready_i;
    rsp_data_d  = rsp_data_q;
    rsp_addr_d  = rsp_addr_q;
    hdr_end_d = hdr_end_q;  hdr_k_d = hdr_k_q;  seg_u_d = seg_u_q;
    nchunks_d = nchunks_q;  v_idx_d = v_idx_q;
    interval_d = interval_q;  count_d = count_q;  add_d = add_q;  add2_d = add2_q;  sum_d = sum_q;
    seg_add2_d = seg_add2_q;
    prod_d = prod_q;  mul_a_d = mul_a_q;  mul_b_d = mul_b_q;  mul_a0_d = mul_a0_q;
    running_d = running_q;  cur_valid_d = cur_valid_q;  cur_lane_d = cur_lane_q;
    cur_end_d = cur_end_q;  build_lane_d = build_lane_q;  ch_loaded_d = ch_loaded_q;
    late_d = late_q;  b_state_d = b_state_q;  rp_valid_d = rp_valid_q;  segq_d = segq_q;
    tlast_d = tlast_q;  b_axis_d = b_axis_q;  b_u_d = b_u_q;  b_end_d = b_end_q;
    b_dir_d = b_dir_q;  b_moving_d = b_moving_q;  cap_addr_d = cap_addr_q;
    fault_d = fault_q;  err_d = err_q;  stretched_d = stretched_q;  enable_d = enable_q;
    stretch_cnt_d = stretch_cnt_q;  moves_done_d = moves_done_q;  segs_done_d = segs_done_q;
    delay_d = delay_q;  left_d = left_q;  tinc_d = tinc_q;  tadd2_d = tadd2_q;  dir_d = dir_q;
    elapsed_d = (elapsed_q == 32'hFFFF_FFFF) ? elapsed_q : elapsed_q + 1'b1;

    seg_wr = 1'b0;  seg_pop = 1'b0;  seg_commit = 1'b0;  seg_rollback = 1'b0;
    seg_wdata = {SWW{1'b0}};  run_wr = 1'b0;  run_pop = 1'b0;
    run_wdata = {RDW{1'b0}};
    ch_wr = 1'b0;  ch_commit = 1'b0;  ch_rollback = 1'b0;  ch_pop = 1'b0;
    eng_in_valid = 1'b0;  eng_move_ready = 1'b0;  cap_done = 1'b0;  pulse_step = {N{1'b0}};
    bank_we = {N{1'b0}};  bank_waddr = {AW{1'b0}};  bank_wbit = 1'b0;
    bank_re = 1'b0;  rp_lane = cur_lane_q;
    for (i = 0; i < N; i = i + 1) rp_next[i] = rp_ptr_q[i];
    fault_set = 1'b0;  fault_code = E_NONE;
    start_cmd = 1'b0;  abort_cmd = 1'b0;  clear_cmd = 1'b0;  cfg_write = 1'b0;
    drivers_on = 1'b0;  drivers_off = 1'b0;

    // ---- command parser
    case (p_state_q)
    P_CMD: if (take) begin
        case (op)
        OP_SEGMENT: begin
            hdr_end_d = cmd_data_i[27];
            hdr_k_d   = cmd_data_i[26:23];
            nchunks_d = cmd_data_i[15:0];
            seg_add2_d = cmd_data_i[22];
            sum_d     = 34'd0;
            discard_d = fault_q;
            if (!fault_q) begin
                if ({28'd0, cmd_data_i[26:23]} > KMAX) begin
                    fault_set = 1'b1;  fault_code = E_SEG_K;  discard_d = 1'b1;
                end else if (cmd_data_i[15:0] == 16'd0 || {16'd0, cmd_data_i[15:0]} > (32'd1 << CAW)) begin
                    fault_set = 1'b1;  fault_code = E_SEG_CHUNKS;  discard_d = 1'b1;
                end
            end
            p_state_d = P_H1;
        end
        OP_CONFIG: begin
            // Refused while running, and while a STEP pulse is still high (after ABORT,
            // E-stop or the run's last move): a polarity or timing write never cuts it.
            if (running_q || |pulse_busy) begin
                fault_set = 1'b1;  fault_code = E_CONFIG_BUSY;
            end else if ({28'd0, cmd_data_i[27:24]} >= N || cmd_data_i[23:20] > 4'd4 ||
                         (cmd_data_i[23:20] <= 4'd1 && cmd_data_i[15:0] == 16'd0) ||
                         (cmd_data_i[23:20] <= 4'd3 && (cmd_data_i[15:0] & ~TMASK) != 16'd0)) begin
                fault_set = 1'b1;  fault_code = E_CONFIG_VALUE;
            end else begin
                cfg_write = 1'b1;
            end
        end
        OP_CONTROL: begin
            start_cmd = cmd_data_i[0];
            abort_cmd = cmd_data_i[1];
            clear_cmd = cmd_data_i[2];
            drivers_on  = cmd_data_i[3];
            drivers_off = cmd_data_i[4];
        end
        OP_READ: begin
            rsp_valid_d = 1'b1;
            rsp_data_d  = read_value[0];
            rsp_addr_d  = cmd_data_i[7:0];
            p_state_d   = P_RSP;
        end
        default: begin
            fault_set = 1'b1;  fault_code = E_BAD_OPCODE;
        end
        endcase
    end

    P_H1: if (take) begin
        seg_u_d   = cmd_data_i[23:0];
        seg_wr    = !discard_q && !fault_q;
        seg_wdata = {hdr_end_q, hdr_k_q, cmd_data_i[24 +: N], cmd_data_i[23:0]};
        if (!discard_q && !fault_q &&
            (cmd_data_i[23:0] == 24'd0 || {8'd0, cmd_data_i[23:0]} > UMAX)) begin
            fault_set = 1'b1;  fault_code = E_SEG_U;  discard_d = 1'b1;
        end
        v_idx_d   = 3'd0;
        p_state_d = P_V;
    end

    P_V: if (take) begin
        seg_wr    = !discard_q && !fault_q;
        seg_wdata = {{(SWW-24){1'b0}}, cmd_data_i[23:0]};
        if (!discard_q && !fault_q && cmd_data_i[23:0] > seg_u_q) begin
            fault_set = 1'b1;  fault_code = E_SEG_V_GT_U;  discard_d = 1'b1;
        end
        v_idx_d = v_idx_q + 1'b1;
        // A segment announced with no chunk was refused at its header; it ends here.
        if ({29'd0, v_idx_q} == N - 1) p_state_d = (nchunks_q == 16'd0) ? P_CMD : P_C0;
    end

    P_C0: if (take) begin
        interval_d = cmd_data_i;
        p_state_d  = P_C1;
    end

    P_C1: if (take) begin
        count_d = c1_count;
        add_d   = c1_add;
        sum_d   = sum_q + {18'd0, c1_count};
        if (!discard_q && !fault_q && (interval_q == 32'd0 || c1_count == 16'd0)) begin
            fault_set = 1'b1;  fault_code = E_SEG_CHUNK_ZERO;  discard_d = 1'b1;
        end
        prod_d  = {MW{1'b0}};
        if (seg_add2_q) begin
            p_state_d = P_C2;
        end else begin
            // The chunk's last word: add2 = 0, straight to pass 2 with 2*add.
            add2_d  = 16'd0;
            ch_wr   = !discard_q && !fault_q;
            mul_a_d = c1_count - 1'b1;
            mul_b_d = {{(MW-17){c1_add[15]}}, c1_add, 1'b0};
            p_state_d = P_MUL;
        end
    end

    P_C2: if (take) begin
        add2_d = c2_add2;
        ch_wr  = !discard_q && !fault_q;
        prod_d = {MW{1'b0}};
        if (c2_add2 == 16'd0) begin
            mul_a_d = count_q - 1'b1;
            mul_b_d = {add_sx[MW-2:0], 1'b0};
            p_state_d = P_MUL;
        end else begin
            // Pass 1: (count-2)*add2, no multiplier bit when count < 2.
            mul_a_d = (count_q < 16'd2) ? 16'd0 : count_q - 16'd2;
            mul_b_d = {{(MW-16){c2_add2[15]}}, c2_add2};
            p_state_d = P_INC;
        end
    end

    P_INC: begin
        // (count-2) * add2 (the multiplier below); then the sign rule and pass 2.
        if (mul_a_q == 16'd0) begin
            if (!discard_q && !fault_q && inc_flip) begin
                fault_set = 1'b1;  fault_code = E_SEG_ADD2;  discard_d = 1'b1;
            end
            prod_d  = {MW{1'b0}};
            mul_a_d = count_q - 1'b1;
            mul_b_d = add_sx + last_inc;
            p_state_d = P_MUL;
        end
    end

    P_MUL: begin
        // (count-1) * (add + last increment) (the multiplier below); then the last delay.
        if (mul_a_q == 16'd0) begin
            if (!discard_q && !fault_q && (last_delay[MW] || last_delay[MW-1:32] != {(MW-32){1'b0}} ||
                                           last_delay == {(MW+1){1'b0}})) begin
                fault_set = 1'b1;  fault_code = E_SEG_DELAY;  discard_d = 1'b1;
            end
            nchunks_d = nchunks_q - 1'b1;
            if (nchunks_q != 16'd1) begin
                p_state_d = P_C0;
            end else if (discard_q || fault_q || fault_set) begin
                ch_rollback  = 1'b1;
                seg_rollback = 1'b1;
                p_state_d    = P_CMD;
            end else if (sum_q != seg_moves) begin
                fault_set    = 1'b1;  fault_code = E_SEG_COUNT_SUM;
                ch_rollback  = 1'b1;
                seg_rollback = 1'b1;
                p_state_d    = P_CMD;
            end else begin
                // The whole segment passed: its words and its chunks appear together.
                seg_commit = 1'b1;
                ch_commit  = 1'b1;
                segq_d     = segq_q + 1'b1;
                p_state_d  = P_CMD;
            end
        end
    end

    P_RSP: if (!rsp_valid_q || rsp_ready_i) p_state_d = P_CMD;

    default: p_state_d = P_CMD;
    endcase

    // The chunk check's multiplier: one bit of mul_a a cycle while any is left.
    // Bit-serial, the product grows by the shifted multiplicand; MUL_DSP, it is
    // the whole product of the operands, which hold still (a multiplier of 0
    // takes no cycle and leaves the product 0, as bit-serial).
    if ((p_state_q == P_INC || p_state_q == P_MUL) && mul_a_q != 16'd0) begin
        if (MUL_DSP != 0) begin
            prod_d = mul_prod;
        end else begin
            if (mul_a_q[0]) prod_d = prod_q + mul_b_q;
            mul_b_d = mul_b_q << 1;
        end
        mul_a_d = mul_a_q >> 1;
    end else begin
        mul_a0_d = mul_a_d;
    end

    // ---- builder: the next committed segment's patterns into the build lane's banks
    for (i = 0; i < N; i = i + 1) b_axis_onehot[i] = b_axis_q == i[2:0];
    case (b_state_q)
    B_IDLE: if (seg_head_valid && !fault_q && {1'b0, run_level} + {2'd0, cur_valid_q} <= 3'd1) begin
        seg_pop    = 1'b1;
        segq_d     = segq_d - 1'b1;
        b_u_d      = head_val[UW-1:0];
        b_dir_d    = head_dir;
        b_end_d    = head_end;
        b_axis_d   = 3'd0;
        b_moving_d = {N{1'b0}};
        b_state_d  = B_V;
    end
    B_V: if (seg_head_valid && eng_in_ready) begin
        seg_pop = 1'b1;
        b_moving_d = b_moving_q | (b_axis_onehot & {N{head_val != 24'd0}});
        if (head_val == 24'd0 || head_val[UW-1:0] == b_u_q) begin
            // A constant pattern: one move.
            bank_we    = b_axis_onehot;
            bank_waddr = {AW{1'b0}};
            bank_wbit  = head_val != 24'd0;
            cap_done   = 1'b1;
        end else begin
            eng_in_valid = 1'b1;
            cap_addr_d   = {AW{1'b0}};
            b_state_d    = B_CAP;
        end
    end
    B_CAP: begin
        eng_move_ready = 1'b1;
        if (eng_move_valid) begin
            bank_we    = b_axis_onehot;
            bank_waddr = cap_addr_q;
            bank_wbit  = eng_move;
            cap_addr_d = cap_addr_q + 1'b1;
            cap_done   = eng_move_pend;
        end
        if (eng_err) begin
            fault_set = 1'b1;  fault_code = E_SEG_PATTERN;
            b_state_d = B_IDLE;
        end
    end
    default: b_state_d = B_IDLE;
    endcase
    if (cap_done) begin
        if ({29'd0, b_axis_q} == N - 1) begin
            run_wr    = 1'b1;
            run_wdata = {build_lane_q, b_end_q, b_moving_d, b_dir_q};
            build_lane_d = !build_lane_q;
            b_state_d = B_IDLE;
        end else begin
            b_axis_d  = b_axis_q + 1'b1;
            b_state_d = B_V;
        end
    end

    // ---- timer and runner
    due  = ch_loaded_q && elapsed_q >= delay_q;
    fire = running_q && cur_valid_q && !estop_i && !abort_cmd && due && rp_valid_q &&
           &(pulse_ready | ~lane_move);
    // A move is counted late once: in the first cycle it is due and does not fire,
    // or when it fires after its time without having waited due (its chunk came late).
    stretch_inc = running_q && due && !late_q && !estop_i && !abort_cmd &&
                  (!fire || elapsed_q != delay_q);
    if (stretch_inc) begin
        stretched_d   = 1'b1;
        stretch_cnt_d = stretch_cnt_q + 1'b1;
        late_d        = 1'b1;
    end
    if (fire) late_d = 1'b0;
    seg_done = fire && left_q == 16'd1 && tlast_q;

    if (!ch_loaded_q && ch_head_valid) begin
        ch_pop      = 1'b1;
        ch_loaded_d = 1'b1;
        delay_d     = ch_head[31:0];
        tinc_d      = {{16{ch_head[47]}}, ch_head[47:32]};
        left_d      = ch_head[63:48];
        tadd2_d     = ch_head[79:64];
        tlast_d     = ch_head[80];
    end
    if (fire) begin
        pulse_step     = lane_move;
        moves_done_d   = moves_done_q + 1'b1;
        elapsed_d      = 32'd1;
        if (left_q != 16'd1) begin
            left_d  = left_q - 1'b1;
            delay_d = delay_q + tinc_q;
            tinc_d  = tinc_q + {{16{tadd2_q[15]}}, tadd2_q};
        end else if (ch_head_valid) begin
            ch_pop  = 1'b1;
            delay_d = ch_head[31:0];
            tinc_d  = {{16{ch_head[47]}}, ch_head[47:32]};
            left_d  = ch_head[63:48];
            tadd2_d = ch_head[79:64];
            tlast_d = ch_head[80];
        end else begin
            ch_loaded_d = 1'b0;
        end
        // The replay registers fetch the next move of the running lane's patterns.
        if (!seg_done) begin
            bank_re = 1'b1;
            for (i = 0; i < N; i = i + 1)
                rp_next[i] = (rp_ptr_q[i] == lm1_q[{cur_lane_q, i[2:0]}]) ? {AW{1'b0}} : rp_ptr_q[i] + 1'b1;
        end
    end
    if (seg_done) begin
        segs_done_d = segs_done_q + 1'b1;
        cur_valid_d = 1'b0;
        rp_valid_d  = 1'b0;
        if (cur_end_q) begin
            running_d = 1'b0;
        end else if (run_level == 2'd0 && segq_q == {(SQW+1){1'b0}} && b_state_q == B_IDLE &&
                     !fault_q) begin
            running_d = 1'b0;
            fault_set = 1'b1;  fault_code = E_UNDERRUN;
        end
    end
    // Load the next built segment; its moving axes take their directions.
    if ((!cur_valid_q || seg_done) && run_head_valid && !fault_q) begin
        run_pop     = 1'b1;
        cur_valid_d = 1'b1;
        cur_lane_d  = run_head[RDW-1];
        cur_end_d   = run_head[RDW-2];
        for (i = 0; i < N; i = i + 1)
            if (run_head[N + i]) dir_d[i] = run_head[i];
        // The replay registers fetch each pattern's first move.
        bank_re    = 1'b1;
        rp_lane    = run_head[RDW-1];
        rp_valid_d = 1'b1;
        for (i = 0; i < N; i = i + 1) rp_next[i] = {AW{1'b0}};
    end

    if (start_cmd && !fault_q && !running_q) begin
        running_d = 1'b1;
        elapsed_d = 32'd1;
    end
    if (abort_cmd) begin
        fault_set = 1'b1;  fault_code = E_ABORT;
    end
    if (estop_i) begin
        fault_set = 1'b1;  fault_code = E_ESTOP;
    end
    // Drivers: off wins over on; E-stop holds them off.
    if (drivers_on) enable_d = 1'b1;
    if (drivers_off || estop_i) enable_d = 1'b0;

    // ---- faults: CLEAR drops what was latched before this cycle; then the first
    // fault latches; a segment under way completes unless its own lane refused it.
    clearing = clear_cmd && !estop_i;
    if (clearing) begin
        fault_d     = 1'b0;
        err_d       = E_NONE;
        stretched_d = stretch_inc;
    end
    if (fault_set && (!fault_q || clearing)) begin
        fault_d = 1'b1;
        err_d   = fault_code;
    end
    flush = estop_i || abort_cmd || (fault_q && !(running_q && cur_valid_q && !seg_done));
    if (flush) begin
        running_d   = 1'b0;
        cur_valid_d = 1'b0;
        ch_loaded_d = 1'b0;
        cur_lane_d  = 1'b0;
        build_lane_d = 1'b0;
        late_d      = 1'b0;
        b_state_d   = B_IDLE;
        rp_valid_d  = 1'b0;
        segq_d      = {(SQW+1){1'b0}};
    end
end

// The engine is reset when a pattern's first period is in its bank, and by a flush.
always @* eng_rst = flush || (b_state_q == B_CAP && cap_done);

// ---------------------------------------------------------------- registers
integer a;
always @(posedge clk) begin
    if (rst) begin
        p_state_q     <= P_CMD;
        discard_q     <= 1'b0;
        rsp_valid_q   <= 1'b0;
        running_q     <= 1'b0;
        cur_valid_q   <= 1'b0;
        cur_lane_q    <= 1'b0;
        build_lane_q  <= 1'b0;
        ch_loaded_q   <= 1'b0;
        late_q        <= 1'b0;
        b_state_q     <= B_IDLE;
        rp_valid_q    <= 1'b0;
        segq_q        <= {(SQW+1){1'b0}};
        fault_q       <= 1'b0;
        err_q         <= E_NONE;
        stretched_q   <= 1'b0;
        enable_q      <= 1'b0;
        stretch_cnt_q <= 32'd0;
        moves_done_q  <= 32'd0;
        segs_done_q   <= 32'd0;
        dir_q         <= {N{1'b0}};
        cfg_step_pol_q <= {N{STEP_POL_RESET}};
        cfg_dir_pol_q  <= {N{DIR_POL_RESET}};
        for (a = 0; a < N; a = a + 1) begin
            cfg_high_q[a]  <= STEP_HIGH_RESET[TW-1:0];
            cfg_low_q[a]   <= STEP_LOW_RESET[TW-1:0];
            cfg_setup_q[a] <= DIR_SETUP_RESET[TW-1:0];
            cfg_hold_q[a]  <= DIR_HOLD_RESET[TW-1:0];
        end
    end else begin
        p_state_q     <= p_state_d;
        discard_q     <= discard_d;
        rsp_valid_q   <= rsp_valid_d;
        running_q     <= running_d;
        cur_valid_q   <= cur_valid_d;
        cur_lane_q    <= cur_lane_d;
        build_lane_q  <= build_lane_d;
        ch_loaded_q   <= ch_loaded_d;
        late_q        <= late_d;
        b_state_q     <= b_state_d;
        rp_valid_q    <= rp_valid_d;
        segq_q        <= segq_d;
        fault_q       <= fault_d;
        err_q         <= err_d;
        stretched_q   <= stretched_d;
        enable_q      <= enable_d;
        stretch_cnt_q <= stretch_cnt_d;
        moves_done_q  <= moves_done_d;
        segs_done_q   <= segs_done_d;
        dir_q         <= dir_d;
        if (cfg_write) begin
            for (a = 0; a < N; a = a + 1) begin
                if (cmd_data_i[27:24] == a[3:0]) begin
                    case (cmd_data_i[23:20])
                    4'd0: cfg_high_q[a]  <= cmd_data_i[TW-1:0];
                    4'd1: cfg_low_q[a]   <= cmd_data_i[TW-1:0];
                    4'd2: cfg_setup_q[a] <= cmd_data_i[TW-1:0];
                    4'd3: cfg_hold_q[a]  <= cmd_data_i[TW-1:0];
                    default: begin
                        cfg_step_pol_q[a] <= cmd_data_i[0];
                        cfg_dir_pol_q[a]  <= cmd_data_i[1];
                    end
                    endcase
                end
            end
        end
    end
    hdr_end_q <= hdr_end_d;  hdr_k_q <= hdr_k_d;  seg_u_q <= seg_u_d;
    nchunks_q <= nchunks_d;  v_idx_q <= v_idx_d;
    tlast_q <= tlast_d;  b_axis_q <= b_axis_d;  b_u_q <= b_u_d;  b_end_q <= b_end_d;
    b_dir_q <= b_dir_d;  b_moving_q <= b_moving_d;  cap_addr_q <= cap_addr_d;
    for (a = 0; a < N; a = a + 1) if (bank_re) rp_ptr_q[a] <= rp_next[a];
    if (cap_done)
        for (a = 0; a < N; a = a + 1)
            if (b_axis_q == a[2:0])
                lm1_q[{build_lane_q, a[2:0]}] <= (b_state_q == B_CAP) ? cap_addr_q : {AW{1'b0}};
    interval_q <= interval_d;  count_q <= count_d;  add_q <= add_d;  add2_q <= add2_d;
    sum_q <= sum_d;  seg_add2_q <= seg_add2_d;
    prod_q <= prod_d;  mul_a_q <= mul_a_d;  mul_b_q <= mul_b_d;  mul_a0_q <= mul_a0_d;
    rsp_data_q <= rsp_data_d;  rsp_addr_q <= rsp_addr_d;  cur_end_q <= cur_end_d;
    delay_q <= delay_d;  left_q <= left_d;  tinc_q <= tinc_d;  tadd2_q <= tadd2_d;
    elapsed_q <= elapsed_d;
end

// ---------------------------------------------------------------- outputs
assign cmd_ready_o = (p_state_q == P_CMD) ||
                     ((p_state_q == P_H1 || p_state_q == P_V) && (discard_q || fault_q || !seg_full)) ||
                     (p_state_q == P_C0) ||
                     (p_state_q == P_C1 && (seg_add2_q || discard_q || fault_q || !ch_full)) ||
                     (p_state_q == P_C2 && (discard_q || fault_q || !ch_full));
assign rsp_valid_o = rsp_valid_q;
assign rsp_data_o  = rsp_valid_q ? rsp_data_q : 32'd0;
assign rsp_addr_o  = rsp_valid_q ? rsp_addr_q : 8'd0;
assign rd_data_o   = read_value[1];
assign running_o   = running_q;
assign fault_o     = fault_q;
assign err_code_o  = err_q;
assign stretched_o = stretched_q;
assign enable_o    = enable_q;
assign status_o    = status_word;
assign stretch_cnt_o = stretch_cnt_q;
assign moves_done_o  = moves_done_q;
assign segs_done_o   = segs_done_q;

endmodule

`resetall
