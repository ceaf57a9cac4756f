// SPDX-License-Identifier: MIT
// cp_hx8k — cpstep on Lattice's iCE40-HX8K breakout board (iCE40HX8K-CT256,
// 12 MHz oscillator on J3). Pins on headers J2 and J3 (constraints/hx8k.pcf,
// docs/BOARDS.md); LED0: running, LED1: fault. No button: reset at power-up.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_hx8k #(
    // PLL: F_out = 12 MHz · (DIVF + 1) / (2^DIVQ · (DIVR + 1)) (icepll's figures).
    parameter [3:0] PLL_DIVR = 4'd0,
    parameter [6:0] PLL_DIVF = 7'd63,
    parameter [2:0] PLL_DIVQ = 3'd4,
    parameter [2:0] PLL_FILTER = 3'd1,
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer SAW = 2,
    parameter integer TW = 16,
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
    // Limit switches and the probe (docs/CORE.md "Inputs").
    parameter integer INPUTS = 0,
    parameter integer FEED = 0,
    // Moves timed by the phase timer (docs/CORE.md "Phase-timer builds"; no board sets it yet).
    parameter integer PTIMER = 0,
    parameter [0:0] ENABLE_ACTIVE_HIGH = 1'b0
) (
    input  wire         CLK,
    output wire         LED0,
    output wire         LED1,
    output wire [N-1:0] STEP,
    output wire [N-1:0] DIR,
    output wire [N-1:0] ENABLE,
    output wire         TORCH,      // J3, T7: the torch (or spindle) output, active high
    input  wire         SPI_SCK,
    input  wire         SPI_CS_N,
    input  wire         SPI_MOSI,
    inout  wire         SPI_MISO,
    inout  wire         ESTOP_LOOP,    // an input: the pad's output driver is off
    // J3: limit switches min and max per axis and the probe, inputs pulled up (the
    // pads' output drivers are off).
    inout  wire [N-1:0] LIM_MIN,
    inout  wire [N-1:0] LIM_MAX,
    inout  wire         PROBE
);

// The inputs' pads: pulled up, so that an open switch (or a cut wire) reads high.
wire [2*N:0] in_pins;
genvar gi;
generate
    for (gi = 0; gi <= 2 * N; gi = gi + 1) begin : g_in
        if (gi < N) begin : g_min
            SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_pad (
                .PACKAGE_PIN(LIM_MIN[gi]), .CLOCK_ENABLE(1'b0), .OUTPUT_CLK(1'b0),
                .OUTPUT_ENABLE(1'b0), .D_OUT_0(1'b0), .D_IN_0(in_pins[gi]));
        end else if (gi < 2 * N) begin : g_max
            SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_pad (
                .PACKAGE_PIN(LIM_MAX[gi - N]), .CLOCK_ENABLE(1'b0), .OUTPUT_CLK(1'b0),
                .OUTPUT_ENABLE(1'b0), .D_OUT_0(1'b0), .D_IN_0(in_pins[gi]));
        end else begin : g_probe
            SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_pad (
                .PACKAGE_PIN(PROBE), .CLOCK_ENABLE(1'b0), .OUTPUT_CLK(1'b0),
                .OUTPUT_ENABLE(1'b0), .D_OUT_0(1'b0), .D_IN_0(in_pins[gi]));
        end
    end
endgenerate

wire led_run_n, led_fault_n;
cp_board #(.PLL_PAD(1'b0), .PLL_DIVR(PLL_DIVR), .PLL_DIVF(PLL_DIVF), .PLL_DIVQ(PLL_DIVQ),
           .PLL_FILTER(PLL_FILTER), .N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW),
           .SAW(SAW), .TW(TW), .CBUF_AW(CBUF_AW),
           .STEP_POL_RESET(STEP_POL_RESET), .DIR_POL_RESET(DIR_POL_RESET), .CLK_HZ(CLK_HZ),
           .BUILD_ID(BUILD_ID), .CONIC(CONIC), .CIW(CIW), .INPUTS(INPUTS), .FEED(FEED), .PTIMER(PTIMER),
           .ENABLE_ACTIVE_HIGH(ENABLE_ACTIVE_HIGH)) u_board (
    .osc_i(CLK), .btn_n(1'b1),
    .spi_sck_i(SPI_SCK), .spi_cs_n_i(SPI_CS_N), .spi_mosi_i(SPI_MOSI), .spi_miso_io(SPI_MISO),
    .estop_loop_i(ESTOP_LOOP),
    .lim_min_i(in_pins[N-1:0]), .lim_max_i(in_pins[2*N-1:N]), .probe_i(in_pins[2*N]),
    .step_o(STEP), .dir_o(DIR), .enable_o(ENABLE), .torch_o(TORCH),
    .led_run_n_o(led_run_n), .led_fault_n_o(led_fault_n));

// The breakout's LEDs light when their pin is high.
assign LED0 = !led_run_n;
assign LED1 = !led_fault_n;

endmodule

`resetall
