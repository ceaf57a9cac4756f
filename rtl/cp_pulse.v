// cp_pulse — one axis's STEP/DIR pins, with the driver's timing enforced.
//
// The motion core asks for a pulse with step_i, only in a cycle where ready_o is
// 1; ready_o is exact: 1 in precisely the cycles a pulse may start without
// breaking step-high, step-low, DIR-setup or DIR-hold time. A pulse requested in
// cycle t is active on the pin in cycles t+1 .. t+step_high, and the position
// counter moves at the same edge the pin goes active. DIR follows dir_i once the
// STEP pin has been inactive for dir_hold cycles (hold is measured from the
// trailing edge: conservative), and a step may start dir_setup cycles after.
//
// Contract, cycle by cycle: docs/PULSE.md.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_pulse #(
    // Width of the timing fields (step high/low, DIR setup/hold), in bits.
    parameter integer TW = 16,
    // Width of the signed position counter, in bits (it wraps mod 2^PW).
    parameter integer PW = 32,
    // STEP polarity the pins use while rst is high (1: active high).
    parameter [0:0] STEP_POL_RESET = 1'b1,
    // DIR polarity the pins use while rst is high (1: pin high = positive).
    parameter [0:0] DIR_POL_RESET = 1'b1
) (
    input  wire          clk,
    input  wire          rst,

    // Configuration: changed by the core only while the axis is idle.
    input  wire [TW-1:0] cfg_step_high_i,   // >= 1
    input  wire [TW-1:0] cfg_step_low_i,    // >= 1
    input  wire [TW-1:0] cfg_dir_setup_i,
    input  wire [TW-1:0] cfg_dir_hold_i,
    input  wire          cfg_step_pol_i,
    input  wire          cfg_dir_pol_i,

    // Requests from the core.
    input  wire          dir_i,             // 1 = positive
    input  wire          step_i,            // start a pulse now (only while ready_o)

    output wire          ready_o,
    output wire          step_o,
    output wire          dir_o,
    output wire [PW-1:0] position_o,
    output wire          busy_o
);

// Elaboration-time parameter checks: an illegal value instantiates a module
// that does not exist, which both Verilator and yosys report by name.
generate
    if (TW < 1 || TW > 32) begin : g_check_tw
        cp_pulse_parameter_TW_must_be_1_to_32 u_bad ();
    end
    if (PW < 1 || PW > 64) begin : g_check_pw
        cp_pulse_parameter_PW_must_be_1_to_64 u_bad ();
    end
endgenerate

localparam [TW-1:0] SAT = {TW{1'b1}};
localparam [TW-1:0] ONE = 1;

// ---------------------------------------------------------------- state
// Control state (reset).
reg          active_q, active_d;        // STEP pin at its active level
reg [TW-1:0] low_cnt_q, low_cnt_d;      // cycles inactive, this one included
reg          dir_q, dir_d;              // logical direction on the DIR pin
reg [TW-1:0] setup_cnt_q, setup_cnt_d;  // cycles since the DIR pin changed
reg [PW-1:0] position_q, position_d;

// Datapath (loaded when a pulse starts, no reset).
reg [TW-1:0] high_cnt_q, high_cnt_d;    // cycles of the pulse left, this one included

function [TW-1:0] sat_inc;
    input [TW-1:0] x;
    sat_inc = (x == SAT) ? x : x + 1'b1;
endfunction

wire ready = !rst && !active_q && low_cnt_q >= cfg_step_low_i
             && dir_q == dir_i && setup_cnt_q >= cfg_dir_setup_i;
wire start = step_i && ready;
// low_cnt_q >= 1 whenever !active_q, so a DIR change never meets a trailing edge.
wire dir_change = !active_q && dir_q != dir_i && low_cnt_q >= cfg_dir_hold_i;

always @* begin
    active_d    = active_q && (high_cnt_q & ~ONE) != {TW{1'b0}};  // high_cnt > 1
    high_cnt_d  = high_cnt_q - 1'b1;
    dir_d       = dir_q;
    setup_cnt_d = sat_inc(setup_cnt_q);
    position_d  = position_q;

    if (start) begin
        active_d   = 1'b1;
        high_cnt_d = cfg_step_high_i;
        position_d = dir_q ? position_q + 1'b1 : position_q - 1'b1;
    end
    if (dir_change) begin
        dir_d       = dir_i;
        setup_cnt_d = ONE;
    end

    low_cnt_d = active_d ? {TW{1'b0}} : sat_inc(low_cnt_q);
end

always @(posedge clk) begin
    if (rst) begin
        active_q    <= 1'b0;
        low_cnt_q   <= SAT;
        dir_q       <= 1'b0;
        setup_cnt_q <= SAT;
        position_q  <= {PW{1'b0}};
    end else begin
        active_q    <= active_d;
        low_cnt_q   <= low_cnt_d;
        dir_q       <= dir_d;
        setup_cnt_q <= setup_cnt_d;
        position_q  <= position_d;
    end
    high_cnt_q <= high_cnt_d;
end

// ---------------------------------------------------------------- outputs
// In reset the pins sit at the parameter idle levels, whatever the state and the
// polarity inputs: no pulse before the configuration has arrived.
assign ready_o    = ready;
assign step_o     = rst ? !STEP_POL_RESET : (cfg_step_pol_i ? active_q : !active_q);
assign dir_o      = rst ? !DIR_POL_RESET : (cfg_dir_pol_i ? dir_q : !dir_q);
assign position_o = position_q;
assign busy_o     = active_q || dir_q != dir_i;

endmodule

`resetall
