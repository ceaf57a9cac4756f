// SPDX-License-Identifier: MIT
// cp_board — what every iCE40 board top shares: the PLL from the 12 MHz
// oscillator, the SPI MISO and E-stop pads, the reset after the PLL locks, the
// card (cp_card), the drivers' ENABLE polarity and the two status LEDs. A board
// top (rtl/boards/<board>/) only names its pins and picks the parameters.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_board #(
    // 1: the oscillator is on the PLL's own pad (SB_PLL40_PAD), 0: any clock pin
    // (SB_PLL40_CORE).
    parameter [0:0] PLL_PAD = 1'b1,
    // PLL: F_out = 12 MHz · (DIVF + 1) / (2^DIVQ · (DIVR + 1)) (icepll's figures;
    // scripts/synth sets them).
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
    // ENABLE pins: 1 = high enables the drivers (TMC2209, A4988 and most others
    // want low: their EN/ENABLE input is active low).
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
    parameter integer INPUTS = 0,
    parameter integer FEED = 0,
    parameter integer PTIMER = 0,
    parameter [0:0] ENABLE_ACTIVE_HIGH = 1'b0
) (
    input  wire         osc_i,          // the 12 MHz oscillator's pin
    input  wire         btn_n,          // reset button, active low (tie high if none)
    input  wire         spi_sck_i,
    input  wire         spi_cs_n_i,
    input  wire         spi_mosi_i,
    inout  wire         spi_miso_io,    // driven only while CS is low
    // E-stop loop: NC switch to ground, pulled up here. An inout as the SB_IO pad
    // is (its output driver is configured off: PIN_TYPE 0000_01).
    inout  wire         estop_loop_i,
    // Limit switches and the probe, from the board top's pads (tie to 0 without).
    input  wire [N-1:0] lim_min_i,
    input  wire [N-1:0] lim_max_i,
    input  wire         probe_i,
    output wire [N-1:0] step_o,
    output wire [N-1:0] dir_o,
    output wire [N-1:0] enable_o,
    output wire         torch_o,        // the torch (or spindle) output, active high
    output wire         led_run_n_o,    // on (low) while running
    output wire         led_fault_n_o   // on while a fault is latched, blinking at E-stop
);

// ---------------------------------------------------------------- clock
wire clk, pll_lock;
generate
    if (PLL_PAD) begin : g_pll_pad
        SB_PLL40_PAD #(
            .FEEDBACK_PATH("SIMPLE"),
            .DIVR(PLL_DIVR), .DIVF(PLL_DIVF), .DIVQ(PLL_DIVQ), .FILTER_RANGE(PLL_FILTER)
        ) u_pll (
            .PACKAGEPIN(osc_i), .PLLOUTGLOBAL(clk), .LOCK(pll_lock),
            .RESETB(1'b1), .BYPASS(1'b0),
            .EXTFEEDBACK(1'b0), .DYNAMICDELAY(8'd0), .LATCHINPUTVALUE(1'b0),
            .SDI(1'b0), .SCLK(1'b0));
    end else begin : g_pll_core
        SB_PLL40_CORE #(
            .FEEDBACK_PATH("SIMPLE"),
            .DIVR(PLL_DIVR), .DIVF(PLL_DIVF), .DIVQ(PLL_DIVQ), .FILTER_RANGE(PLL_FILTER)
        ) u_pll (
            .REFERENCECLK(osc_i), .PLLOUTGLOBAL(clk), .LOCK(pll_lock),
            .RESETB(1'b1), .BYPASS(1'b0),
            .EXTFEEDBACK(1'b0), .DYNAMICDELAY(8'd0), .LATCHINPUTVALUE(1'b0),
            .SDI(1'b0), .SCLK(1'b0));
    end
endgenerate

// ---------------------------------------------------------------- pads
// Every pin of the cells tied explicitly (an input the pad does not use reads 0).
wire miso, miso_oe, estop, miso_in;
SB_IO #(.PIN_TYPE(6'b1010_01)) u_miso (
    .PACKAGE_PIN(spi_miso_io), .CLOCK_ENABLE(1'b0), .OUTPUT_CLK(1'b0),
    .OUTPUT_ENABLE(miso_oe), .D_OUT_0(miso), .D_IN_0(miso_in));
SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_estop (
    .PACKAGE_PIN(estop_loop_i), .CLOCK_ENABLE(1'b0), .OUTPUT_CLK(1'b0),
    .OUTPUT_ENABLE(1'b0), .D_OUT_0(1'b0), .D_IN_0(estop));

// STEP and DIR leave through the IO cells' output registers: each pin changes at a
// clock edge, a clock after cp_core's pin (docs/BOARDS.md "Pins"), with the IO cell's
// fixed clock-to-out and no fabric logic after the flip-flop. The register powers up
// 0; a pin whose idle level is high is registered inverted (PIN_TYPE 0111) so that it
// idles high from configuration on, before the PLL runs.
wire [N-1:0] core_step, core_dir;
wire [2*N-1:0] pin_in;
genvar gp;
generate
    for (gp = 0; gp < N; gp = gp + 1) begin : g_pins
        SB_IO #(.PIN_TYPE(STEP_POL_RESET ? 6'b0101_01 : 6'b0111_01)) u_step (
            .PACKAGE_PIN(step_o[gp]), .CLOCK_ENABLE(1'b1), .OUTPUT_CLK(clk),
            .OUTPUT_ENABLE(1'b1), .D_OUT_0(core_step[gp] == STEP_POL_RESET),
            .D_IN_0(pin_in[2*gp]));
        SB_IO #(.PIN_TYPE(DIR_POL_RESET ? 6'b0101_01 : 6'b0111_01)) u_dir (
            .PACKAGE_PIN(dir_o[gp]), .CLOCK_ENABLE(1'b1), .OUTPUT_CLK(clk),
            .OUTPUT_ENABLE(1'b1), .D_OUT_0(core_dir[gp] == DIR_POL_RESET),
            .D_IN_0(pin_in[2*gp+1]));
    end
endgenerate
// The torch leaves through an IO register too, so that it keeps its place among
// the STEP edges (a clock after cp_core's pin); it powers up 0: off.
wire core_torch, torch_in;
SB_IO #(.PIN_TYPE(6'b0101_01)) u_torch (
    .PACKAGE_PIN(torch_o), .CLOCK_ENABLE(1'b1), .OUTPUT_CLK(clk),
    .OUTPUT_ENABLE(1'b1), .D_OUT_0(core_torch), .D_IN_0(torch_in));
wire unused_pads = &{1'b0, miso_in, pin_in, torch_in};

// ---------------------------------------------------------------- reset
// Reset for 2^8 clocks after the PLL locks and while the button is held.
reg [1:0] btn_q = 2'b00;
reg [8:0] por_q = 9'd0;
always @(posedge clk) begin
    btn_q <= {btn_q[0], btn_n};
    if (!pll_lock || !btn_q[1]) por_q <= 9'd0;
    else if (!por_q[8])         por_q <= por_q + 1'b1;
end
wire rst = !por_q[8];

wire enable, running, fault, stretched;
wire [7:0] err_code;
wire [N*32-1:0] position;
cp_card #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW),
          .CBUF_AW(CBUF_AW), .STEP_POL_RESET(STEP_POL_RESET),
          .DIR_POL_RESET(DIR_POL_RESET), .CLK_HZ(CLK_HZ), .BUILD_ID(BUILD_ID), .CONIC(CONIC),
          .CIW(CIW), .INPUTS(INPUTS), .FEED(FEED), .PTIMER(PTIMER)) u_card (
    .clk(clk), .rst(rst),
    .spi_sck_i(spi_sck_i), .spi_cs_n_i(spi_cs_n_i), .spi_mosi_i(spi_mosi_i),
    .spi_miso_o(miso), .spi_miso_oe_o(miso_oe),
    .estop_i(estop), .lim_min_i(lim_min_i), .lim_max_i(lim_max_i), .probe_i(probe_i),
    .step_o(core_step), .dir_o(core_dir), .torch_o(core_torch), .enable_o(enable),
    .running_o(running), .fault_o(fault),
    .err_code_o(err_code), .stretched_o(stretched), .position_o(position));
wire unused = &{1'b0, err_code, stretched, position};

assign enable_o = {N{enable == ENABLE_ACTIVE_HIGH}};

// Red blinks (about 3 Hz at 48 MHz) while the E-stop input is open.
reg [23:0] blink_q = 24'd0;
always @(posedge clk) blink_q <= blink_q + 1'b1;
assign led_run_n_o   = !running;
assign led_fault_n_o = !(fault && !(estop && blink_q[23]));

endmodule

`resetall
