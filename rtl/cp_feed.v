// SPDX-License-Identifier: MIT
// cp_feed — feed hold, resume and feed override: the scale s of the move timer's
// time (docs/CORE.md "Feed hold and override").
//
// The runner's timer counts scaled time: each clock adds s (0 <= s <= 2) to it
// (rtl/cp_run.v), so every move keeps its place on the path and only time
// stretches; s = 0 holds. s follows its target — 0 while held, else the override —
// through two first-order stages in series, a critically damped second-order
// ramp: once per ramp tick (every max(T, 1) clocks, T from CONFIG field 9)
//     u += (target - u) / 2^10,   s += (u - s) / 2^10
// (arithmetic shifts; a stage within 2^10 units of its input takes it, so s
// arrives on its target exactly). With tau = 2^10 ticks, a change of the target by D
// moves s monotonically, without overshoot, at a rate of at most |D| / (e tau) and a
// rate of rate of at most |D| / tau^2, both starting from 0: the host picks T from the
// machine's limits (docs/CORE.md). Writing field 9 (CONFIG is refused while the run
// is on) sets s and u to the target.
//
// s and u are kept in Q2.30; the timer takes s's top 18 bits (Q2.16).
//
// Out of band (URGENT, docs/PROTOCOL.md): HOLD (target 0), RESUME (target the
// override), OVERRIDE (the override in Q2.14, 0x4000 = 100 %; above 0x8000 taken
// as 0x8000). After reset: s = u = 1, the override 1, not held.
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_feed.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_feed (
    input  wire          clk,
    input  wire          rst,
    // CONFIG (cp_cmd): written now, the word.
    input  wire          cfg_write_i,
    input  wire [31:0]   cfg_word_i,
    // URGENT bits, in the cycle of the frame's CS rise, and the override value.
    input  wire          hold_i,
    input  wire          resume_i,
    input  wire          ovr_i,
    input  wire [15:0]   ovr_val_i,
    // The timer's scale, Q2.16 (0x10000 = 1).
    output wire [17:0]   scale_o,
    // READ 0x29: {held, settled, 14'b0, s in Q2.14}; READ 0x2A: the override.
    output wire [31:0]   feed_o,
    output wire [15:0]   override_o
);

localparam [31:0] ONE = 32'h4000_0000;    // 1.0 in Q2.30
localparam integer KS = 10;                  // each stage moves 2^-KS of its distance a tick

reg [15:0]  period_q;                        // T
reg [15:0]  cnt_q, cnt_d;                    // clocks to the next ramp tick
reg [15:0]  ovr_q;                           // the override, Q2.14
reg         held_q;
reg [31:0]  u_q, u_d;                        // the first stage, Q2.30
reg [31:0]  s_q, s_d;                        // the scale, Q2.30

wire        tick = cnt_q == 16'd0;
wire        cfg_period = cfg_write_i && cfg_word_i[23:20] == 4'd9;
wire [15:0] ovr_clamped = (ovr_val_i > 16'h8000) ? 16'h8000 : ovr_val_i;
wire [31:0] target = held_q ? 32'd0 : {ovr_q, 16'd0};

// Each stage's distance (33 bits, signed) and whether it is within 2^KS units.
wire [32:0] du = {1'b0, target} - {1'b0, u_q};
wire [32:0] ds = {1'b0, u_q} - {1'b0, s_q};
wire        du_near = &du[32:KS] || ~|du[32:KS];
wire        ds_near = &ds[32:KS] || ~|ds[32:KS];
wire [31:0] u_step = {{KS{du[32]}}, du[31:KS]};
wire [31:0] s_step = {{KS{ds[32]}}, ds[31:KS]};

always @* begin
    cnt_d = cnt_q - 1'b1;
    if (tick) cnt_d = (period_q == 16'd0) ? 16'd0 : period_q - 1'b1;
    if (cfg_period) cnt_d = 16'd0;
    u_d = u_q;  s_d = s_q;
    if (tick) begin
        u_d = du_near ? target : u_q + u_step;
        s_d = ds_near ? u_q : s_q + s_step;
    end
    // A new period (CONFIG is refused while the run is on): s takes its target.
    if (cfg_period) begin
        u_d = target;  s_d = target;
    end
end

always @(posedge clk) begin
    if (rst) begin
        period_q <= 16'd0;
        cnt_q    <= 16'd0;
        ovr_q    <= 16'h4000;
        held_q   <= 1'b0;
        u_q      <= ONE;
        s_q      <= ONE;
    end else begin
        cnt_q <= cnt_d;
        u_q   <= u_d;
        s_q   <= s_d;
        if (cfg_period) period_q <= cfg_word_i[15:0];
        if (ovr_i) ovr_q <= ovr_clamped;
        // HOLD and RESUME in one word: HOLD.
        if (resume_i) held_q <= 1'b0;
        if (hold_i) held_q <= 1'b1;
    end
end

wire unused = &{1'b0, cfg_word_i[31:24], cfg_word_i[19:16], s_q[13:0], du[KS-1:0], ds[KS-1:0]};
assign scale_o    = s_q[31:14];
assign feed_o     = {held_q, s_q == target && u_q == target, 14'd0, s_q[31:16]};
assign override_o = ovr_q;

endmodule

`resetall
