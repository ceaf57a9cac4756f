// SPDX-License-Identifier: MIT
// cp_pulse — one axis's STEP/DIR pins, with the driver's timing enforced.
//
// The motion core asks for a pulse with step_i, only in a cycle where ready_o is
// 1; ready_o is exact: 1 in precisely the cycles a pulse may start without
// breaking step-high, step-low, DIR-setup or DIR-hold time. A pulse requested in
// cycle t is active on the pin in cycles t+1 .. t+step_high, and the position
// counter moves at the same edge the pin goes active.
//
// The rules are kept on the physical pins. Both pin levels are registers: the DIR
// pin moves (for a new direction or a new DIR polarity alike) only once the STEP
// pin has been inactive for dir_hold cycles (hold is measured from the trailing
// edge: conservative), and a step may start dir_setup cycles after the DIR pin
// last moved. A new STEP polarity moves the STEP pin (to the new inactive level)
// only when a pulse could start instead, and the step-low time restarts there.
//
// The readiness is registered for speed (it decides the motion core's fire): the
// step-low and DIR-setup thresholds are compared a cycle ahead, against the
// configuration of that cycle. In the cycle after a CONFIG write (cfg_new_i) no
// edge may start (ready_o and the STEP polarity edge wait one cycle): the core
// never fires then, since CONFIG is taken only while not running.
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

    // Configuration: changed by the core only while busy_o is low (STEP inactive).
    input  wire [TW-1:0] cfg_step_high_i,   // >= 1
    input  wire [TW-1:0] cfg_step_low_i,    // >= 1
    input  wire [TW-1:0] cfg_dir_setup_i,
    input  wire [TW-1:0] cfg_dir_hold_i,
    input  wire          cfg_step_pol_i,
    input  wire          cfg_dir_pol_i,
    input  wire          cfg_new_i,         // the configuration was written at the last edge

    // Requests from the core.
    input  wire          dir_i,             // 1 = positive
    input  wire          step_i,            // start a pulse now (only while ready_o)

    output wire          ready_o,
    output wire          step_o,
    output wire          dir_o,
    output wire [PW-1:0] position_o,
    output wire          busy_o             // the STEP pin is at its active level
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
reg [TW-1:0] low_cnt_q, low_cnt_d;      // cycles the STEP pin has been inactive (since its last edge)
reg          step_pol_q, step_pol_d;    // STEP polarity on the pin
reg          dir_pin_q, dir_pin_d;      // DIR pin level
reg [TW-1:0] setup_cnt_q, setup_cnt_d;  // cycles since the DIR pin changed
reg [PW-1:0] position_q, position_d;
// low_cnt >= step_low and setup_cnt >= dir_setup, compared a cycle ahead with the
// configuration of that cycle (exact while cfg_new_i is low).
reg          low_ok_q, setup_ok_q;

// Datapath (loaded when a pulse starts, no reset).
reg [TW-1:0] high_cnt_q, high_cnt_d;    // cycles of the pulse left, this one included

function [TW-1:0] sat_inc;
    input [TW-1:0] x;
    sat_inc = (x == SAT) ? x : x + 1'b1;
endfunction

// The DIR pin level dir_i asks for, in the DIR polarity in force.
wire want_dir = cfg_dir_pol_i ? dir_i : !dir_i;
// A STEP edge may happen now: inactive for step_low, DIR settled for dir_setup.
// Not in the cycle after a configuration write.
wire quiet = !cfg_new_i && !active_q && low_ok_q && dir_pin_q == want_dir && setup_ok_q;
wire ready = !rst && quiet && step_pol_q == cfg_step_pol_i;
wire start = step_i && ready;
// A new STEP polarity takes the pin to its inactive level where a pulse could start.
wire pol_change = quiet && step_pol_q != cfg_step_pol_i;
// low_cnt_q >= 1 whenever !active_q, so a DIR change never meets a STEP edge (a
// leading or polarity edge needs the DIR pin settled, a trailing edge is while active).
wire dir_change = !active_q && dir_pin_q != want_dir && low_cnt_q >= cfg_dir_hold_i;

always @* begin
    active_d    = active_q && (high_cnt_q & ~ONE) != {TW{1'b0}};  // high_cnt > 1
    high_cnt_d  = high_cnt_q - 1'b1;
    step_pol_d  = step_pol_q;
    dir_pin_d   = dir_pin_q;
    setup_cnt_d = sat_inc(setup_cnt_q);
    position_d  = position_q;

    if (start) begin
        active_d   = 1'b1;
        high_cnt_d = cfg_step_high_i;
        position_d = dir_i ? position_q + 1'b1 : position_q - 1'b1;
    end
    if (pol_change) begin
        step_pol_d = cfg_step_pol_i;
    end
    if (dir_change) begin
        dir_pin_d   = want_dir;
        setup_cnt_d = ONE;
    end

    low_cnt_d = active_d ? {TW{1'b0}} : pol_change ? ONE : sat_inc(low_cnt_q);
end

// low_cnt_d >= step_low, with the compares made beside the start decision (the
// core's fire) rather than after it: low_cnt_d is 0, 1 or the incremented count.
wire low_inc_ok  = sat_inc(low_cnt_q) >= cfg_step_low_i;
wire low_one_ok  = cfg_step_low_i <= ONE;
wire low_zero_ok = cfg_step_low_i == {TW{1'b0}};
wire low_ok_d    = active_d ? low_zero_ok : pol_change ? low_one_ok : low_inc_ok;

always @(posedge clk) begin
    if (rst) begin
        active_q    <= 1'b0;
        low_cnt_q   <= SAT;
        step_pol_q  <= STEP_POL_RESET;
        dir_pin_q   <= !DIR_POL_RESET;
        setup_cnt_q <= SAT;
        position_q  <= {PW{1'b0}};
        low_ok_q    <= 1'b1;  // SAT >= any threshold
        setup_ok_q  <= 1'b1;
    end else begin
        active_q    <= active_d;
        low_cnt_q   <= low_cnt_d;
        step_pol_q  <= step_pol_d;
        dir_pin_q   <= dir_pin_d;
        setup_cnt_q <= setup_cnt_d;
        position_q  <= position_d;
        low_ok_q    <= low_ok_d;
        setup_ok_q  <= setup_cnt_d >= cfg_dir_setup_i;
    end
    high_cnt_q <= high_cnt_d;
end

// ---------------------------------------------------------------- outputs
// In reset the pins sit at the parameter idle levels, whatever the state; the
// reset state holds them there after it (STEP polarity and DIR pin from the
// parameters): no pulse and no DIR edge before the configuration has arrived.
assign ready_o    = ready;
assign step_o     = rst ? !STEP_POL_RESET : (step_pol_q ? active_q : !active_q);
assign dir_o      = rst ? !DIR_POL_RESET : dir_pin_q;
assign position_o = position_q;
assign busy_o     = active_q;

`ifdef FORMAL
// ---------------------------------------------------------------- formal properties
// The pin rules of docs/PULSE.md, proved (bounded and by k-induction) with yosys +
// yosys-smtbmc (formal/proofs.tsv, row "pulse"). A monitor watches the raw pins the
// way tb/pulse/pin_checker.h does: every pin change is an edge, whatever its cause;
// a STEP level run is classified where it begins, with the STEP polarity in force
// at that edge (the configuration of the cycle before the pin changed): a run at
// the active level is a pulse, any other run a gap.

reg f_past_valid = 1'b0;
always @(posedge clk) f_past_valid <= 1'b1;

// ---- assumptions: what cp_core guarantees
// The first cycle is in reset.
always @* if (!f_past_valid) assume (rst);
// cp_core validates step_high and step_low >= 1 (CONFIG_VALUE).
always @* assume (cfg_step_high_i != {TW{1'b0}} && cfg_step_low_i != {TW{1'b0}});
// cp_core takes CONFIG only while not running (the only time it asserts step_i) and
// while every STEP pin is inactive (busy_o low): the configuration changes only at
// an edge after a cycle with rst, or with busy_o and step_i both low.
reg [TW-1:0] f_high_p, f_low_p, f_setup_p, f_hold_p;  // the configuration of the previous cycle
reg          f_spol_p, f_dpol_p;
reg          f_cfg_may_change;
always @(posedge clk) begin
    f_high_p  <= cfg_step_high_i;
    f_low_p   <= cfg_step_low_i;
    f_setup_p <= cfg_dir_setup_i;
    f_hold_p  <= cfg_dir_hold_i;
    f_spol_p  <= cfg_step_pol_i;
    f_dpol_p  <= cfg_dir_pol_i;
    f_cfg_may_change <= rst || (!busy_o && !step_i);
end
wire f_cfg_same = cfg_step_high_i == f_high_p && cfg_step_low_i == f_low_p && cfg_dir_setup_i == f_setup_p
                  && cfg_dir_hold_i == f_hold_p && cfg_step_pol_i == f_spol_p && cfg_dir_pol_i == f_dpol_p;
always @* if (f_past_valid && !f_cfg_may_change) assume (f_cfg_same);
// cp_core raises cfg_new_i in the cycle after every CONFIG write (it may also raise
// it without one).
always @* if (f_past_valid && !f_cfg_same) assume (cfg_new_i);

// ---- the pin monitor (reads only pins, rst and the configuration)
reg          f_step_q, f_dir_q;           // the pins in the previous cycle
reg [TW-1:0] f_step_len_q, f_dir_len_q;   // cycles they had held their level by then (saturating)
reg          f_pulse_q;                   // the STEP run then was a pulse
reg [TW-1:0] f_want_q;                    // step_high in force at that pulse's leading edge
reg [PW-1:0] f_pos_q;                     // signed count of leading edges
wire         f_step_edge = step_o != f_step_q;
wire         f_dir_edge  = dir_o != f_dir_q;
// Cycles each pin has shown its level, this cycle included (saturating like the counters).
wire [TW-1:0] f_step_len = f_step_edge ? ONE : sat_inc(f_step_len_q);
wire [TW-1:0] f_dir_len  = f_dir_edge ? ONE : sat_inc(f_dir_len_q);
wire         f_pulse = f_step_edge ? step_o == f_spol_p : f_pulse_q;
wire         f_lead  = f_step_edge && f_pulse;   // a gap ends at the active level
wire [TW-1:0] f_want = f_lead ? f_high_p : f_want_q;
wire [PW-1:0] f_pos  = f_lead ? (dir_o == f_dpol_p ? f_pos_q + 1'b1 : f_pos_q - 1'b1) : f_pos_q;
always @(posedge clk) begin
    if (rst) begin  // the reset levels, long ago
        f_step_q     <= !STEP_POL_RESET;
        f_dir_q      <= !DIR_POL_RESET;
        f_step_len_q <= SAT;
        f_dir_len_q  <= SAT;
        f_pulse_q    <= 1'b0;
        f_pos_q      <= {PW{1'b0}};
    end else begin
        f_step_q     <= step_o;
        f_dir_q      <= dir_o;
        f_step_len_q <= f_step_len;
        f_dir_len_q  <= f_dir_len;
        f_pulse_q    <= f_pulse;
        f_pos_q      <= f_pos;
    end
    f_want_q <= f_want;
end

always @* begin
    if (rst) begin
        // In reset the pins sit at the parameter idle levels; no pulse may start.
        assert (step_o == !STEP_POL_RESET && dir_o == !DIR_POL_RESET && !ready_o);
    end else if (f_past_valid) begin
        // STEP high: a pulse lasts exactly step_high (in force at its leading edge) ...
        if (f_pulse) assert (f_step_len <= f_want);
        if (f_step_edge && f_pulse_q) begin
            assert (f_step_len_q == f_want_q);
            // ... and ends at the inactive level: a polarity change makes no runt.
            assert (!f_pulse);
        end
        // STEP low and DIR setup: a gap ends (leading edge or STEP polarity edge) only
        // after step_low, with DIR stable for dir_setup and not moving at that edge.
        if (f_step_edge && !f_pulse_q)
            assert (f_step_len_q >= f_low_p && !f_dir_edge && f_dir_len_q >= f_setup_p);
        // DIR hold: the DIR pin moves (new direction or new polarity alike) only in a
        // gap, dir_hold after the STEP pin's last edge, and never at a STEP edge.
        if (f_dir_edge)
            assert (!f_pulse_q && !f_step_edge && f_step_len_q >= f_hold_p);
        // ready_o is exact: 1 precisely when a leading edge at the next clock edge
        // keeps every rule above (and would be one: the STEP pin sits at the inactive
        // level of the polarity in force, DIR shows dir_i in the polarity in force).
        // (No edge starts in the cycle after a configuration write.)
        assert (ready_o == (!cfg_new_i && !f_pulse && f_step_len >= cfg_step_low_i
                            && f_dir_len >= cfg_dir_setup_i && step_o == !cfg_step_pol_i
                            && dir_o == (cfg_dir_pol_i ? dir_i : !dir_i)));
        // busy_o is "a pulse is on the pin"; position_o counts the leading edges.
        assert (busy_o == f_pulse);
        assert (position_o == f_pos);
        // Invariants tying the state to the monitor (they make k-induction go through).
        assert (active_q == f_pulse);
        assert (setup_cnt_q == f_dir_len);
        // The registered thresholds, compared with the previous cycle's configuration.
        assert (low_ok_q == (low_cnt_q >= f_low_p) && setup_ok_q == (setup_cnt_q >= f_setup_p));
        if (active_q) begin
            assert (low_cnt_q == {TW{1'b0}} && high_cnt_q != {TW{1'b0}});
            assert ({1'b0, f_step_len} + {1'b0, high_cnt_q} == {1'b0, f_want} + 1'b1);
        end else begin
            assert (low_cnt_q == f_step_len);
        end
    end
end
`endif

endmodule

`resetall
