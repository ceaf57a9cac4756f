// SPDX-License-Identifier: MIT
// cp_card — the card, independent of the board: the SPI front end (cp_spi) feeding
// the motion core (cp_core), and the E-stop input.
//
// Board tops (rtl/boards/) add the clock, the reset, the pads and the MISO
// tristate. docs/PROTOCOL.md is the wire contract, docs/CORE.md the core's.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_card #(
    // Number of axes.
    parameter integer N = 4,
    // Pattern capacity of every engine: the longest pattern U/gcd(U, v).
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
    // Command buffer address width: it holds 2^CBUF_AW words.
    parameter integer CBUF_AW = 9,
    // Pulse timing after reset, in clock cycles (the host configures the real ones).
    parameter integer STEP_HIGH_RESET = 1,
    parameter integer STEP_LOW_RESET = 1,
    parameter integer DIR_SETUP_RESET = 1,
    parameter integer DIR_HOLD_RESET = 1,
    // Pin polarity after reset: 1 = STEP active high, 1 = DIR high is positive.
    parameter [0:0] STEP_POL_RESET = 1'b1,
    parameter [0:0] DIR_POL_RESET = 1'b1,
    // The card clock in Hz and the build id, only reported (READ 0x24 / 0x25):
    // rtl/builds.json sets both for every build.
    parameter integer CLK_HZ = 48000000,
    parameter [31:0] BUILD_ID = 32'h0,
    // CONIC segments and the conic walker's width (docs/CORE.md "CONIC").
    parameter integer CONIC = 0,
    parameter integer CIW = 40,
    // Limit switches and the probe (docs/CORE.md "Inputs").
    parameter integer INPUTS = 0,
    // Feed hold, resume and override (docs/CORE.md "Feed hold and override").
    parameter integer FEED = 0,
    // Moves timed by the phase timer (docs/CORE.md "Phase-timer builds").
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,

    // SPI (asynchronous to clk, SCK at most clk/8).
    input  wire          spi_sck_i,
    input  wire          spi_cs_n_i,
    input  wire          spi_mosi_i,
    output wire          spi_miso_o,
    output wire          spi_miso_oe_o,

    // E-stop, asynchronous, active high here (a normally closed switch to ground
    // with a pull-up reads high when pressed or when its wire is cut).
    input  wire          estop_i,
    // Limit switches (min, max per axis) and the probe, asynchronous; their active
    // level is configured (CONFIG fields 7 and 8).
    input  wire [N-1:0]  lim_min_i,
    input  wire [N-1:0]  lim_max_i,
    input  wire          probe_i,

    // Pins.
    output wire [N-1:0]  step_o,
    output wire [N-1:0]  dir_o,
    output wire          torch_o,          // the torch (docs/CORE.md "Torch")
    output wire          enable_o,
    output wire          running_o,
    output wire          fault_o,

    // For simulation and observation.
    output wire [7:0]    err_code_o,
    output wire          stretched_o,
    output wire [N*32-1:0] position_o
);

// E-stop into the clk domain.
reg [1:0] estop_q;
always @(posedge clk) estop_q <= {estop_q[0], estop_i};
wire estop = estop_q[1];
// The inputs into the clk domain, as the E-stop.
reg [2*N:0] in_q0, in_q1;
always @(posedge clk) begin
    in_q0 <= {probe_i, lim_max_i, lim_min_i};
    in_q1 <= in_q0;
end

wire        cmd_valid, cmd_ready, rsp_valid, rsp_ready;
wire [31:0] cmd_data, rsp_data, rd_data, status, stretch_cnt, moves_done, segs_done;
wire [7:0]  rsp_addr, rd_addr;
wire        ctl_start, ctl_stop, ctl_flush, ctl_ack;  // an URGENT frame's bits (docs/PROTOCOL.md)
wire        ctl_hold, ctl_resume, ctl_ovr;          // its feed bits, and the override value
wire [15:0] ctl_ovr_val;
wire        frame_ok;   // a whole frame with a good CRC: the watchdog's kick
// The core's READ reply data, status and counter outputs: the SPI front end reads
// the same registers through the core's read port instead.
wire unused_core = &{1'b0, rsp_data, status, stretch_cnt, moves_done, segs_done};

cp_spi #(.N(N), .CBUF_AW(CBUF_AW), .CONIC(CONIC), .PTIMER(PTIMER)) u_spi (
    .clk(clk), .rst(rst),
    .spi_sck_i(spi_sck_i), .spi_cs_n_i(spi_cs_n_i), .spi_mosi_i(spi_mosi_i),
    .spi_miso_o(spi_miso_o), .spi_miso_oe_o(spi_miso_oe_o),
    .cmd_valid_o(cmd_valid), .cmd_ready_i(cmd_ready), .cmd_data_o(cmd_data),
    .rsp_valid_i(rsp_valid), .rsp_ready_o(rsp_ready), .rsp_addr_i(rsp_addr),
    .rd_addr_o(rd_addr), .rd_data_i(rd_data),
    .estop_i(estop), .enable_i(enable_o),
    .ctl_start_o(ctl_start), .ctl_stop_o(ctl_stop), .ctl_flush_o(ctl_flush), .ctl_ack_o(ctl_ack),
    .ctl_hold_o(ctl_hold), .ctl_resume_o(ctl_resume), .ctl_ovr_o(ctl_ovr), .ctl_ovr_val_o(ctl_ovr_val),
    .frame_ok_o(frame_ok));

cp_core #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW), .PW(32),
          .CBUF_AW(CBUF_AW), .CLK_HZ(CLK_HZ), .BUILD_ID(BUILD_ID), .CONIC(CONIC), .CIW(CIW),
          .INPUTS(INPUTS), .FEED(FEED), .PTIMER(PTIMER), .STEP_HIGH_RESET(STEP_HIGH_RESET), .STEP_LOW_RESET(STEP_LOW_RESET),
          .DIR_SETUP_RESET(DIR_SETUP_RESET), .DIR_HOLD_RESET(DIR_HOLD_RESET),
          .STEP_POL_RESET(STEP_POL_RESET), .DIR_POL_RESET(DIR_POL_RESET)) u_core (
    .clk(clk), .rst(rst),
    .cmd_valid_i(cmd_valid), .cmd_ready_o(cmd_ready), .cmd_data_i(cmd_data),
    .rsp_valid_o(rsp_valid), .rsp_ready_i(rsp_ready), .rsp_data_o(rsp_data),
    .rsp_addr_o(rsp_addr), .rd_addr_i(rd_addr), .rd_data_o(rd_data),
    .estop_i(estop), .ctl_start_i(ctl_start), .ctl_stop_i(ctl_stop), .ctl_flush_i(ctl_flush),
    .ctl_ack_i(ctl_ack), .kick_i(frame_ok),
    .ctl_hold_i(ctl_hold), .ctl_resume_i(ctl_resume), .ctl_ovr_i(ctl_ovr), .ctl_ovr_val_i(ctl_ovr_val),
    .lim_min_i(in_q1[N-1:0]), .lim_max_i(in_q1[2*N-1:N]), .probe_i(in_q1[2*N]),
    .step_o(step_o), .dir_o(dir_o), .torch_o(torch_o),
    .running_o(running_o), .fault_o(fault_o), .err_code_o(err_code_o),
    .stretched_o(stretched_o), .position_o(position_o),
    .enable_o(enable_o), .status_o(status), .stretch_cnt_o(stretch_cnt),
    .moves_done_o(moves_done), .segs_done_o(segs_done));

endmodule

`resetall
