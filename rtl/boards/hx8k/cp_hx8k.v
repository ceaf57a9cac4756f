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
    parameter [0:0] ENABLE_ACTIVE_HIGH = 1'b0
) (
    input  wire         CLK,
    output wire         LED0,
    output wire         LED1,
    output wire [N-1:0] STEP,
    output wire [N-1:0] DIR,
    output wire [N-1:0] ENABLE,
    input  wire         SPI_SCK,
    input  wire         SPI_CS_N,
    input  wire         SPI_MOSI,
    inout  wire         SPI_MISO,
    input  wire         ESTOP_LOOP
);

wire clk, pll_lock;
SB_PLL40_CORE #(
    .FEEDBACK_PATH("SIMPLE"),
    .DIVR(PLL_DIVR), .DIVF(PLL_DIVF), .DIVQ(PLL_DIVQ), .FILTER_RANGE(PLL_FILTER)
) u_pll (
    .REFERENCECLK(CLK), .PLLOUTGLOBAL(clk), .LOCK(pll_lock),
    .RESETB(1'b1), .BYPASS(1'b0),
    .EXTFEEDBACK(1'b0), .DYNAMICDELAY(8'd0), .LATCHINPUTVALUE(1'b0),
    .SDI(1'b0), .SCLK(1'b0));

wire miso, miso_oe, estop_pad, led_run_n, led_fault_n;
SB_IO #(.PIN_TYPE(6'b1010_01)) u_miso (
    .PACKAGE_PIN(SPI_MISO), .OUTPUT_ENABLE(miso_oe), .D_OUT_0(miso));
SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_estop (
    .PACKAGE_PIN(ESTOP_LOOP), .D_IN_0(estop_pad));

cp_board #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW),
           .ENABLE_ACTIVE_HIGH(ENABLE_ACTIVE_HIGH)) u_board (
    .clk(clk), .pll_lock(pll_lock), .btn_n(1'b1),
    .spi_sck_i(SPI_SCK), .spi_cs_n_i(SPI_CS_N), .spi_mosi_i(SPI_MOSI),
    .spi_miso_o(miso), .spi_miso_oe_o(miso_oe), .estop_i(estop_pad),
    .step_o(STEP), .dir_o(DIR), .enable_o(ENABLE),
    .led_run_n_o(led_run_n), .led_fault_n_o(led_fault_n));

// The breakout's LEDs light when their pin is high.
assign LED0 = !led_run_n;
assign LED1 = !led_fault_n;

endmodule

`resetall
