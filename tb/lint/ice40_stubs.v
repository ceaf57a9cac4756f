// SPDX-License-Identifier: MIT
// iCE40 primitives the board tops instantiate, as port-exact stubs for
// `verilator --lint-only` of the tops (tb/lint/CMakeLists.txt). Only their
// interfaces matter here: the PLL passes its reference through, the IO cell
// drives its pad. Synthesis uses the real cells (yosys's ice40 library).
`resetall
`timescale 1ns / 1ps
`default_nettype none
// One file holds every primitive's stub, so no file is named after its module;
// the stubs take the cells' configuration and ignore it.
/* verilator lint_off DECLFILENAME */
/* verilator lint_off UNUSEDPARAM */

module SB_PLL40_PAD #(
    parameter FEEDBACK_PATH = "SIMPLE",
    parameter [3:0] DIVR = 4'd0,
    parameter [6:0] DIVF = 7'd0,
    parameter [2:0] DIVQ = 3'd0,
    parameter [2:0] FILTER_RANGE = 3'd0
) (
    input  wire       PACKAGEPIN,
    output wire       PLLOUTGLOBAL,
    output wire       LOCK,
    input  wire       RESETB,
    input  wire       BYPASS,
    input  wire       EXTFEEDBACK,
    input  wire [7:0] DYNAMICDELAY,
    input  wire       LATCHINPUTVALUE,
    input  wire       SDI,
    input  wire       SCLK
);
assign PLLOUTGLOBAL = PACKAGEPIN;
assign LOCK = RESETB;
wire unused = &{1'b0, BYPASS, EXTFEEDBACK, DYNAMICDELAY, LATCHINPUTVALUE, SDI, SCLK};
endmodule

module SB_PLL40_CORE #(
    parameter FEEDBACK_PATH = "SIMPLE",
    parameter [3:0] DIVR = 4'd0,
    parameter [6:0] DIVF = 7'd0,
    parameter [2:0] DIVQ = 3'd0,
    parameter [2:0] FILTER_RANGE = 3'd0
) (
    input  wire       REFERENCECLK,
    output wire       PLLOUTGLOBAL,
    output wire       LOCK,
    input  wire       RESETB,
    input  wire       BYPASS,
    input  wire       EXTFEEDBACK,
    input  wire [7:0] DYNAMICDELAY,
    input  wire       LATCHINPUTVALUE,
    input  wire       SDI,
    input  wire       SCLK
);
assign PLLOUTGLOBAL = REFERENCECLK;
assign LOCK = RESETB;
wire unused = &{1'b0, BYPASS, EXTFEEDBACK, DYNAMICDELAY, LATCHINPUTVALUE, SDI, SCLK};
endmodule

module SB_IO #(
    parameter [5:0] PIN_TYPE = 6'b000000,
    parameter [0:0] PULLUP = 1'b0
) (
    inout  wire PACKAGE_PIN,
    input  wire CLOCK_ENABLE,
    input  wire OUTPUT_CLK,
    input  wire OUTPUT_ENABLE,
    input  wire D_OUT_0,
    output wire D_IN_0
);
// PIN_TYPE[5:4]: the output driver off (00), on (01), on with OUTPUT_ENABLE (10).
// PIN_TYPE[3:2]: the output from D_OUT_0 (10), through the IO cell's register (01),
// inverted after it (11). (DDR and registered enables are not used.)
reg q = 1'b0;
always @(posedge OUTPUT_CLK) if (CLOCK_ENABLE) q <= D_OUT_0;
wire data = PIN_TYPE[3:2] == 2'b10 ? D_OUT_0 : PIN_TYPE[3:2] == 2'b11 ? !q : q;
generate
    if (PIN_TYPE[5:4] == 2'b01) begin : g_on
        assign PACKAGE_PIN = data;
        wire unused = &{1'b0, OUTPUT_ENABLE, PULLUP};
    end else if (PIN_TYPE[5:4] == 2'b10) begin : g_oe
        assign PACKAGE_PIN = OUTPUT_ENABLE ? data : 1'bz;
        wire unused = &{1'b0, PULLUP};
    end else begin : g_in
        wire unused = &{1'b0, OUTPUT_ENABLE, data, PULLUP};
    end
endgenerate
assign D_IN_0 = PACKAGE_PIN;
endmodule

`resetall
