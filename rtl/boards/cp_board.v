// cp_board — what every board top shares: the reset after the PLL locks, the
// card (cp_card), the drivers' ENABLE polarity and the two status LEDs. A board
// top (rtl/boards/<board>/) adds only its PLL and its pads.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_board #(
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer SAW = 2,
    parameter integer TW = 16,
    // ENABLE pins: 1 = high enables the drivers (TMC2209, A4988 and most others
    // want low: their EN/ENABLE input is active low).
    parameter [0:0] ENABLE_ACTIVE_HIGH = 1'b0
) (
    input  wire         clk,
    input  wire         pll_lock,
    input  wire         btn_n,          // reset button, active low (tie high if none)
    input  wire         spi_sck_i,
    input  wire         spi_cs_n_i,
    input  wire         spi_mosi_i,
    output wire         spi_miso_o,
    output wire         spi_miso_oe_o,
    input  wire         estop_i,        // high: E-stop (open loop)
    output wire [N-1:0] step_o,
    output wire [N-1:0] dir_o,
    output wire [N-1:0] enable_o,
    output wire         led_run_n_o,    // on (low) while running
    output wire         led_fault_n_o   // on while a fault is latched, blinking at E-stop
);

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
cp_card #(.N(N), .W(W), .UMAX(UMAX), .KMAX(KMAX), .CAW(CAW), .SAW(SAW), .TW(TW)) u_card (
    .clk(clk), .rst(rst),
    .spi_sck_i(spi_sck_i), .spi_cs_n_i(spi_cs_n_i), .spi_mosi_i(spi_mosi_i),
    .spi_miso_o(spi_miso_o), .spi_miso_oe_o(spi_miso_oe_o),
    .estop_i(estop_i),
    .step_o(step_o), .dir_o(dir_o), .enable_o(enable),
    .running_o(running), .fault_o(fault),
    .err_code_o(err_code), .stretched_o(stretched), .position_o(position));
wire unused = &{1'b0, err_code, stretched, position};

assign enable_o = {N{enable == ENABLE_ACTIVE_HIGH}};

// Red blinks (about 3 Hz at 48 MHz) while the E-stop input is open.
reg [23:0] blink_q = 24'd0;
always @(posedge clk) blink_q <= blink_q + 1'b1;
assign led_run_n_o   = !running;
assign led_fault_n_o = !(fault && !(estop_i && blink_q[23]));

endmodule

`resetall
