// SPDX-License-Identifier: MIT
// cp_icebreaker — cpstep on the iCEBreaker (iCE40UP5K-SG48, 12 MHz oscillator).
//
// The PLL multiplies the 12 MHz oscillator up to the card's clock (scripts/synth
// picks the PLL setting; docs/BOARDS.md lists the pins). Four axes: STEP and DIR on
// PMOD 1A, the drivers' ENABLE on PMOD 1B's lower row, the host's SPI on PMOD 1B's
// upper row, the E-stop loop on PMOD 2 pin 10. Green LED: running; red LED: fault,
// blinking while the E-stop input is open. BTN_N resets the card.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_icebreaker #(
    // PLL: F_out = 12 MHz · (DIVF + 1) / (2^DIVQ · (DIVR + 1)) (icepll's figures).
    parameter [3:0] PLL_DIVR = 4'd0,
    parameter [6:0] PLL_DIVF = 7'd63,
    parameter [2:0] PLL_DIVQ = 3'd4,
    parameter [2:0] PLL_FILTER = 3'd1,
    // The motion core (docs/CORE.md).
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer SAW = 2,
    parameter integer TW = 16,
    // ENABLE pins: 1 = high enables the drivers (docs/BOARDS.md).
    // Command buffer address width (docs/PROTOCOL.md).
    parameter integer CBUF_AW = 9,
    // Pin polarity after reset (docs/CORE.md).
    parameter [0:0] STEP_POL_RESET = 1'b1,
    parameter [0:0] DIR_POL_RESET = 1'b1,
    // The card clock in Hz and the build id, reported in READ 0x24 / 0x25
    // (scripts/synth sets both from rtl/builds.json).
    parameter integer CLK_HZ = 48000000,
    parameter [31:0] BUILD_ID = 32'h0,
    // CONIC segments and the conic walker's width (docs/CORE.md "CONIC").
    parameter integer CONIC = 0,
    parameter integer CIW = 40,
    // Limit switches and the probe: none on this build (its pins are tied off).
    parameter integer INPUTS = 0,
    parameter integer FEED = 0,
    // Moves timed by the phase timer (docs/CORE.md "Phase-timer builds"; no board sets it yet).
    parameter integer PTIMER = 0,
    parameter [0:0] ENABLE_ACTIVE_HIGH = 1'b0
) (
    input  wire         CLK,        // 12 MHz oscillator, pin 35
    input  wire         BTN_N,      // user button: reset
    output wire         LEDR_N,     // red: fault
    output wire         LEDG_N,     // green: running
    // PMOD 1A: STEP on the upper row, DIR on the lower row (axes x y z a).
    output wire [N-1:0] STEP,
    output wire [N-1:0] DIR,
    // PMOD 1B lower row: ENABLE per axis.
    output wire [N-1:0] ENABLE,
    // PMOD 2 pin 1: the torch (or spindle) output, active high.
    output wire         TORCH,
    // PMOD 1B upper row: the host's SPI.
    input  wire         SPI_SCK,
    input  wire         SPI_CS_N,
    input  wire         SPI_MOSI,
    inout  wire         SPI_MISO,
    // PMOD 2 pin 10: E-stop loop, a normally closed switch to ground (pulled up:
    // open, pressed or cut reads as E-stop).
    inout  wire         ESTOP_LOOP     // an input: the pad's output driver is off
);

cp_board #(.PLL_PAD(1'b1), .PLL_DIVR(PLL_DIVR), .PLL_DIVF(PLL_DIVF), .PLL_DIVQ(PLL_DIVQ),
           .PLL_FILTER(PLL_FILTER), .N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW),
           .SAW(SAW), .TW(TW), .CBUF_AW(CBUF_AW),
           .STEP_POL_RESET(STEP_POL_RESET), .DIR_POL_RESET(DIR_POL_RESET), .CLK_HZ(CLK_HZ),
           .BUILD_ID(BUILD_ID), .CONIC(CONIC), .CIW(CIW), .INPUTS(INPUTS), .FEED(FEED), .PTIMER(PTIMER),
           .ENABLE_ACTIVE_HIGH(ENABLE_ACTIVE_HIGH)) u_board (
    .osc_i(CLK), .btn_n(BTN_N),
    .spi_sck_i(SPI_SCK), .spi_cs_n_i(SPI_CS_N), .spi_mosi_i(SPI_MOSI), .spi_miso_io(SPI_MISO),
    .estop_loop_i(ESTOP_LOOP),
    .lim_min_i({N{1'b0}}), .lim_max_i({N{1'b0}}), .probe_i(1'b0),   // no inputs on this build
    .step_o(STEP), .dir_o(DIR), .enable_o(ENABLE), .torch_o(TORCH),
    .led_run_n_o(LEDG_N), .led_fault_n_o(LEDR_N));

endmodule

`resetall
