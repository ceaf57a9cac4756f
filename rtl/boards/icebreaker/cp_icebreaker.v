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
    // PMOD 1B upper row: the host's SPI.
    input  wire         SPI_SCK,
    input  wire         SPI_CS_N,
    input  wire         SPI_MOSI,
    inout  wire         SPI_MISO,
    // PMOD 2 pin 10: E-stop loop, a normally closed switch to ground (pulled up:
    // open, pressed or cut reads as E-stop).
    input  wire         ESTOP_LOOP
);

// ---------------------------------------------------------------- clock and reset
wire clk, pll_lock;
SB_PLL40_PAD #(
    .FEEDBACK_PATH("SIMPLE"),
    .DIVR(PLL_DIVR), .DIVF(PLL_DIVF), .DIVQ(PLL_DIVQ), .FILTER_RANGE(PLL_FILTER)
) u_pll (
    .PACKAGEPIN(CLK), .PLLOUTGLOBAL(clk), .LOCK(pll_lock),
    .RESETB(1'b1), .BYPASS(1'b0),
    .EXTFEEDBACK(1'b0), .DYNAMICDELAY(8'd0), .LATCHINPUTVALUE(1'b0),
    .SDI(1'b0), .SCLK(1'b0));

// ---------------------------------------------------------------- pads
wire miso, miso_oe, estop_pad;
SB_IO #(.PIN_TYPE(6'b1010_01)) u_miso (
    .PACKAGE_PIN(SPI_MISO), .OUTPUT_ENABLE(miso_oe), .D_OUT_0(miso));
SB_IO #(.PIN_TYPE(6'b0000_01), .PULLUP(1'b1)) u_estop (
    .PACKAGE_PIN(ESTOP_LOOP), .D_IN_0(estop_pad));

// ---------------------------------------------------------------- the card
cp_board #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW),
           .ENABLE_ACTIVE_HIGH(ENABLE_ACTIVE_HIGH)) u_board (
    .clk(clk), .pll_lock(pll_lock), .btn_n(BTN_N),
    .spi_sck_i(SPI_SCK), .spi_cs_n_i(SPI_CS_N), .spi_mosi_i(SPI_MOSI),
    .spi_miso_o(miso), .spi_miso_oe_o(miso_oe), .estop_i(estop_pad),
    .step_o(STEP), .dir_o(DIR), .enable_o(ENABLE),
    .led_run_n_o(LEDG_N), .led_fault_n_o(LEDR_N));

endmodule

`resetall
