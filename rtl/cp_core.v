// SPDX-License-Identifier: MIT
// cp_core — the motion core: four parts joined by three queues.
//
//   cp_cmd    command parser and chunk check ─► segment queue, chunk queue
//   cp_build  segment queue ─► one Castle–Pitteway engine ─► pattern banks, run queue
//   cp_run    banks and replay, move-event timer, fire, stretch ◄─ chunk and run queues
//   cp_status faults (one priority encoder), counters, configuration, READ registers
//   cp_pulse  per axis: STEP/DIR timing and the position counter
//
// docs/CORE.md is the contract: the command words, the validation and fault
// codes, and the cycle behaviour the golden model (model/cp_core.*, built from
// the twins of the same parts) follows.
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
    parameter [31:0] BUILD_ID = 32'h0,
    // 1: CONIC segments (opcode 0x5) walked by the bit-serial conic walker of CIW bits
    // (docs/CONIC.md section 8); 0: refused as BAD_OPCODE, and no walker.
    parameter integer CONIC = 0,
    parameter integer CIW = 40,
    // Limit switches, the probe and the seek (cp_inputs; docs/CORE.md "Inputs"); 0:
    // the inputs are not looked at (READ 0x27 reads 0, no LIMIT, CONFIG field 10 refused).
    parameter integer INPUTS = 0,
    // Feed hold, resume and override on scaled time (cp_feed; docs/CORE.md "Feed hold
    // and override"); 0: the timer runs at scale 1, the URGENT feed bits are ignored,
    // CONFIG field 9 refused, READ 0x29/0x2A read 0.
    parameter integer FEED = 0,
    // 1: moves timed by the phase timer (rtl/cp_ptimer.v) from PHASE commands
    // instead of chunks, each segment carrying its length per move (docs/PROTOCOL.md
    // "Toward a compact wire"); READ 0x23 [26].
    parameter integer PTIMER = 0
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
    // Out of band (the SPI front end's URGENT frames, docs/PROTOCOL.md): START as
    // CONTROL's; STOP: no move fires from this cycle on, the run is off, the
    // segment under way and the queues stay for a START to go on with.
    input  wire          ctl_start_i,
    input  wire          ctl_stop_i,
    // FLUSH (out of band): the parser drops the command in hand, every queue, the
    // builder and the runner are emptied, the run is off; no fault is latched.
    input  wire          ctl_flush_i,
    // ACK (out of band): clears a latched fault, an E-stop's included (CONTROL's
    // CLEAR does not clear an E-stop), when the E-stop input is released.
    input  wire          ctl_ack_i,
    // HOLD, RESUME, OVERRIDE (out of band; FEED builds): the feed's target, and the
    // override's value (Q2.14) with OVERRIDE.
    input  wire          ctl_hold_i,
    input  wire          ctl_resume_i,
    input  wire          ctl_ovr_i,
    input  wire [15:0]   ctl_ovr_val_i,
    // A whole frame with a good CRC ended (the SPI front end): the watchdog's kick
    // (docs/CORE.md "Watchdog"; CONFIG field 5 sets its timeout, 0 = off).
    input  wire          kick_i,
    // Limit switches and the probe, synchronous to clk (cp_card synchronizes the pins).
    input  wire [N-1:0]  lim_min_i,
    input  wire [N-1:0]  lim_max_i,
    input  wire          probe_i,

    // Pins.
    output wire [N-1:0]  step_o,
    output wire [N-1:0]  dir_o,
    // The torch (a digital output): the out bit (H0[16]) of the segment under way,
    // while the run is on (docs/CORE.md "Torch").
    output wire          torch_o,

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
localparam integer AW = (W > 2) ? $clog2(W) : 1;    // pattern bank address width
// Segment queue word: the header {end, k, dir[N], U} or a v_i in [23:0] (PTIMER: its
// length per move, 32 bits).
localparam integer SWW0 = (CONIC == 0) ? 30 + N : 32 + N;
localparam integer SWW = (PTIMER != 0 && SWW0 < 32) ? 32 : SWW0;
// Segment queue address width: 2^SAW segments of N + 1 words each (N + 2 with
// PTIMER), at least.
localparam integer SQW = SAW + $clog2(N + 1 + ((PTIMER != 0) ? 1 : 0));
// A built segment, waiting in the run queue: lane, end, moving[N], dir[N] (PTIMER:
// and its L, k, U).
localparam integer RDW = 3 + 2 * N + ((CONIC == 0) ? 0 : 7) + ((PTIMER == 0) ? 0 : 60);
// Chunk queue word: last chunk of its segment, add2, count, add, interval (PTIMER:
// the phase timer's words, {sel, data}).
localparam integer CDW = (PTIMER == 0) ? 81 : 35;

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
endgenerate

// ---------------------------------------------------------------- the seams
// Status to the others.
wire          fault, flush;
wire          wd_trip;     // the watchdog ran out: the runner stops (cp_status)
wire          lim_hit;     // the runner stopped at an active limit
wire [N-1:0]  lim_min, lim_max;   // active limits (cp_inputs)
wire          probe;
wire          seek_stop;   // the seek trips on the probe: the runner stops (cp_inputs)
wire          seek_lim;    // a limit hit is the seek's trip, not LIMIT (cp_inputs)
wire [2:0]    seek;        // {tripped, mode}, READ 0x27
wire [17:0]   scale;       // the timer's scale (cp_feed), Q2.16
wire [31:0]   feed_word;   // READ 0x29
wire [15:0]   override;    // READ 0x2A
// What empties the queues, the builder and the runner: the status's flush (a fault,
// E-stop, ABORT) or an out-of-band FLUSH.
wire          flush_all = flush || ctl_flush_i;
wire [N*TW-1:0] cfg_high, cfg_low, cfg_setup, cfg_hold;
wire [N-1:0]  cfg_step_pol, cfg_dir_pol;
wire          cfg_new;
wire [31:0]   read_cmd_data;
// Parser requests.
wire          start_req, abort_req, clear_req, drivers_on_req, drivers_off_req, cfg_write;
wire          cmd_fault;
wire [7:0]    cmd_code;
// Queues.
wire          seg_wr, seg_commit, seg_rollback, seg_pop, seg_full, seg_head_valid;
wire [SWW-1:0] seg_wdata, seg_head;
wire [SQW:0]  seg_used, seg_level;
wire          ch_wr, ch_commit, ch_rollback, ch_pop, ch_full, ch_head_valid;
wire [80:0]   ch_wdata;
wire [CDW-1:0] ch_head;
wire [81:0]   ch_head_x = {{(82-CDW){1'b0}}, ch_head};   // as cp_run takes it
wire [CAW:0]  ch_used, ch_level;
wire          run_wr, run_pop, run_full, run_head_valid;
wire [RDW-1:0] run_wdata, run_head;
wire [1:0]    run_used, run_level;
// Builder to runner: the banks' write port.
wire          bank_we, bank_wbit, build_lane, len_we;
wire [2:0]    bank_axis;
wire [AW-1:0] bank_waddr, len_m1;
wire          build_fault, build_busy;
wire [SQW:0]  segq;
// Runner.
wire          running, torch, cur_valid, fire, seg_done, stretch, seg_active, run_fault, run_conic;
wire          walker_free, cw_wr, cw_start, cw_cont;
wire [2:0]    cw_sel;
wire [31:0]   cw_data;
wire [N-1:0]  pulse_step, run_dir, pulse_ready, pulse_busy;
wire [PW-1:0] pulse_pos [0:N-1];
wire unused = &{1'b0, seg_used, seg_level, ch_used, run_used, run_full, ch_wdata, ch_head_x[81]};

// ---------------------------------------------------------------- parts
cp_cmd #(.N(N), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .TW(TW), .CONIC(CONIC), .FEED(FEED),
         .INPUTS(INPUTS), .PTIMER(PTIMER)) u_cmd (
    .clk(clk), .rst(rst), .flush_i(ctl_flush_i),
    .cmd_valid_i(cmd_valid_i), .cmd_ready_o(cmd_ready_o), .cmd_data_i(cmd_data_i),
    .rsp_valid_o(rsp_valid_o), .rsp_ready_i(rsp_ready_i), .rsp_data_o(rsp_data_o),
    .rsp_addr_o(rsp_addr_o), .read_data_i(read_cmd_data),
    .fault_i(fault), .running_i(running), .pulse_busy_i(|pulse_busy),
    .seg_full_i(seg_full), .seg_wr_o(seg_wr), .seg_wdata_o(seg_wdata),
    .seg_commit_o(seg_commit), .seg_rollback_o(seg_rollback),
    .ch_full_i(ch_full), .ch_wr_o(ch_wr), .ch_wdata_o(ch_wdata),
    .ch_commit_o(ch_commit), .ch_rollback_o(ch_rollback),
    .start_o(start_req), .abort_o(abort_req), .clear_o(clear_req),
    .drivers_on_o(drivers_on_req), .drivers_off_o(drivers_off_req), .cfg_write_o(cfg_write),
    .fault_o(cmd_fault), .fault_code_o(cmd_code));

cp_fifo #(.DW(SWW), .AW(SQW)) u_seg_fifo (
    .clk(clk), .rst(rst), .clear_i(flush_all),
    .wr_i(seg_wr), .wr_data_i(seg_wdata), .commit_i(seg_commit), .rollback_i(seg_rollback),
    .full_o(seg_full), .used_o(seg_used), .level_o(seg_level),
    .out_valid_o(seg_head_valid), .out_ready_i(seg_pop), .out_data_o(seg_head));

cp_fifo #(.DW(CDW), .AW(CAW)) u_chunk_fifo (
    .clk(clk), .rst(rst), .clear_i(flush_all),
    .wr_i(ch_wr), .wr_data_i(ch_wdata[CDW-1:0]), .commit_i(ch_commit), .rollback_i(ch_rollback),
    .full_o(ch_full), .used_o(ch_used), .level_o(ch_level),
    .out_valid_o(ch_head_valid), .out_ready_i(ch_pop), .out_data_o(ch_head));

cp_build #(.N(N), .W(W), .UMAX(UMAX), .SAW(SAW), .CONIC(CONIC), .PTIMER(PTIMER)) u_build (
    .clk(clk), .rst(rst), .flush_i(flush_all), .fault_i(fault),
    .seg_valid_i(seg_head_valid), .seg_head_i(seg_head), .seg_pop_o(seg_pop),
    .seg_commit_i(seg_commit),
    .run_level_i(run_level), .cur_valid_i(cur_valid),
    .run_wr_o(run_wr), .run_wdata_o(run_wdata),
    .bank_we_o(bank_we), .bank_axis_o(bank_axis), .bank_waddr_o(bank_waddr),
    .bank_wbit_o(bank_wbit), .build_lane_o(build_lane), .len_we_o(len_we), .len_m1_o(len_m1),
    .walker_free_i(walker_free), .cw_wr_o(cw_wr), .cw_sel_o(cw_sel), .cw_data_o(cw_data),
    .cw_start_o(cw_start), .cw_cont_o(cw_cont),
    .fault_o(build_fault), .busy_o(build_busy), .segq_o(segq));

cp_fifo #(.DW(RDW), .AW(1)) u_run_fifo (
    .clk(clk), .rst(rst), .clear_i(flush_all),
    .wr_i(run_wr), .wr_data_i(run_wdata), .commit_i(1'b1), .rollback_i(1'b0),
    .full_o(run_full), .used_o(run_used), .level_o(run_level),
    .out_valid_o(run_head_valid), .out_ready_i(run_pop), .out_data_o(run_head));

cp_run #(.N(N), .W(W), .CONIC(CONIC), .CIW(CIW), .FEED(FEED), .PTIMER(PTIMER)) u_run (
    .clk(clk), .rst(rst), .flush_i(flush_all), .estop_i(estop_i),
    .start_i(start_req || ctl_start_i), .stop_i(ctl_stop_i || wd_trip || seek_stop), .abort_i(abort_req), .fault_i(fault),
    .ch_valid_i(ch_head_valid), .ch_head_i(ch_head_x[80:0]), .ch_pop_o(ch_pop),
    .run_valid_i(run_head_valid), .run_head_i(run_head), .run_level_i(run_level),
    .run_pop_o(run_pop),
    .segq_empty_i(segq == {(SQW+1){1'b0}}), .build_busy_i(build_busy),
    .bank_we_i(bank_we), .bank_axis_i(bank_axis), .bank_waddr_i(bank_waddr),
    .bank_wbit_i(bank_wbit), .bank_lane_i(build_lane), .len_we_i(len_we), .len_m1_i(len_m1),
    .cw_wr_i(cw_wr), .cw_sel_i(cw_sel), .cw_data_i(cw_data), .cw_start_i(cw_start), .cw_cont_i(cw_cont),
    .walker_free_o(walker_free),
    .pulse_ready_i(pulse_ready), .step_o(pulse_step), .dir_o(run_dir),
    .running_o(running), .torch_o(torch), .cur_valid_o(cur_valid), .fire_o(fire), .seg_done_o(seg_done),
    .stretch_o(stretch), .seg_active_o(seg_active), .fault_o(run_fault),
    .fault_conic_o(run_conic), .lim_min_i(lim_min), .lim_max_i(lim_max), .lim_hit_o(lim_hit), .scale_i(scale));

cp_status #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW), .PW(PW),
            .STEP_HIGH_RESET(STEP_HIGH_RESET), .STEP_LOW_RESET(STEP_LOW_RESET),
            .DIR_SETUP_RESET(DIR_SETUP_RESET), .DIR_HOLD_RESET(DIR_HOLD_RESET),
            .STEP_POL_RESET(STEP_POL_RESET), .DIR_POL_RESET(DIR_POL_RESET),
            .CBUF_AW(CBUF_AW), .CLK_HZ(CLK_HZ), .BUILD_ID(BUILD_ID), .CONIC(CONIC),
            .CIW(CIW), .INPUTS(INPUTS), .FEED(FEED), .PTIMER(PTIMER)) u_status (
    .clk(clk), .rst(rst), .estop_i(estop_i),
    .abort_i(abort_req), .clear_i(clear_req), .ack_i(ctl_ack_i), .kick_i(kick_i), .drivers_on_i(drivers_on_req),
    .drivers_off_i(drivers_off_req), .cfg_write_i(cfg_write), .cfg_word_i(cmd_data_i),
    .cmd_fault_i(cmd_fault), .cmd_code_i(cmd_code), .build_fault_i(build_fault),
    .run_fault_i(run_fault), .run_conic_i(run_conic), .lim_hit_i(lim_hit && !seek_lim),
    .lim_min_i(lim_min), .lim_max_i(lim_max), .probe_i(probe), .seek_i(seek),
    .feed_i(feed_word), .override_i(override),
    .stretch_i(stretch), .fire_i(fire), .seg_done_i(seg_done), .seg_active_i(seg_active),
    .running_i(running), .torch_i(torch), .cur_valid_i(cur_valid), .segq_i(segq), .build_busy_i(build_busy),
    .run_level_i(run_level), .ch_level_i(ch_level), .position_i(position_o),
    .rd_addr0_i(cmd_data_i[7:0]), .rd_data0_o(read_cmd_data),
    .rd_addr1_i(rd_addr_i), .rd_data1_o(rd_data_o),
    .fault_o(fault), .err_o(err_code_o), .flush_o(flush), .stretched_o(stretched_o),
    .enable_o(enable_o), .status_o(status_o), .stretch_cnt_o(stretch_cnt_o),
    .moves_done_o(moves_done_o), .segs_done_o(segs_done_o),
    .cfg_high_o(cfg_high), .cfg_low_o(cfg_low), .cfg_setup_o(cfg_setup), .cfg_hold_o(cfg_hold),
    .cfg_step_pol_o(cfg_step_pol), .cfg_dir_pol_o(cfg_dir_pol), .cfg_new_o(cfg_new),
    .wd_trip_o(wd_trip));

// The inputs: filtered, made active by their polarity (CONFIG fields 6..8).
generate
    if (INPUTS != 0) begin : g_inputs
        cp_inputs #(.N(N)) u_inputs (
            .clk(clk), .rst(rst), .lim_min_i(lim_min_i), .lim_max_i(lim_max_i), .probe_i(probe_i),
            .cfg_write_i(cfg_write), .cfg_word_i(cmd_data_i), .running_i(running), .lim_hit_i(lim_hit),
            .lim_min_o(lim_min), .lim_max_o(lim_max), .probe_o(probe),
            .seek_stop_o(seek_stop), .seek_lim_o(seek_lim), .seek_o(seek));
    end else begin : g_no_inputs
        assign lim_min = {N{1'b0}};
        assign lim_max = {N{1'b0}};
        assign probe   = 1'b0;
        assign seek_stop = 1'b0;
        assign seek_lim  = 1'b0;
        assign seek      = 3'd0;
        wire unused_pins = &{1'b0, lim_min_i, lim_max_i, probe_i};
    end
endgenerate

// Feed hold and override: the timer's scale (CONFIG field 9, URGENT bits 4..6).
generate
    if (FEED != 0) begin : g_feed
        cp_feed u_feed (
            .clk(clk), .rst(rst), .cfg_write_i(cfg_write), .cfg_word_i(cmd_data_i),
            .hold_i(ctl_hold_i), .resume_i(ctl_resume_i), .ovr_i(ctl_ovr_i), .ovr_val_i(ctl_ovr_val_i),
            .scale_o(scale), .feed_o(feed_word), .override_o(override));
    end else begin : g_no_feed
        assign scale     = 18'h10000;
        assign feed_word = 32'd0;
        assign override  = 16'd0;
        wire unused_feed = &{1'b0, ctl_hold_i, ctl_resume_i, ctl_ovr_i, ctl_ovr_val_i};
    end
endgenerate

// pulse_busy[a]: axis a's STEP pin is at its active level (CONFIG is refused then).
genvar ga;
generate
    for (ga = 0; ga < N; ga = ga + 1) begin : g_pulse
        cp_pulse #(.TW(TW), .PW(PW), .STEP_POL_RESET(STEP_POL_RESET),
                   .DIR_POL_RESET(DIR_POL_RESET)) u_pulse (
            .clk(clk), .rst(rst),
            .cfg_step_high_i(cfg_high[TW*ga +: TW]), .cfg_step_low_i(cfg_low[TW*ga +: TW]),
            .cfg_dir_setup_i(cfg_setup[TW*ga +: TW]), .cfg_dir_hold_i(cfg_hold[TW*ga +: TW]),
            .cfg_step_pol_i(cfg_step_pol[ga]), .cfg_dir_pol_i(cfg_dir_pol[ga]),
            .cfg_new_i(cfg_new),
            .dir_i(run_dir[ga]), .step_i(pulse_step[ga]),
            .ready_o(pulse_ready[ga]), .step_o(step_o[ga]), .dir_o(dir_o[ga]),
            .position_o(pulse_pos[ga]), .busy_o(pulse_busy[ga]));
        assign position_o[PW*ga +: PW] = pulse_pos[ga];
    end
endgenerate

assign running_o = running;
assign torch_o   = torch;
assign fault_o   = fault;

endmodule

`resetall
