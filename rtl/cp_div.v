// SPDX-License-Identifier: MIT
// cp_div — a serial divider: q = floor(k / d), one quotient bit a clock (issue 13:
// the conic length rule's division, a conic move's length K / D_n, docs/PROTOCOL.md
// "Toward a compact wire"; a unit on its own, not yet part of cp_core).
//
// start_i while idle (busy_o low) takes k_i and d_i. A quotient that does not fit
// QW bits (k >> QW >= d) or d = 0 is refused: done_o the next clock with err_o
// set and q_o = 0. Otherwise the partial remainder starts as k >> QW (< d) and each
// of the next QW clocks shifts in one bit of k's low QW bits, subtracts d where it
// fits and shifts the quotient bit in where that bit was (restoring division); the
// clock after the last, done_o pulses with q_o, which holds until the next start.
// A start while busy is ignored.
//
// Model twin model/cp_div.*, bench tb/core/test_div.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_div #(
    parameter integer KW = 64,    // dividend
    parameter integer DW = 42,    // divisor
    parameter integer QW = 32     // quotient (QW < KW, KW - QW <= DW)
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          start_i,
    input  wire [KW-1:0] k_i,
    input  wire [DW-1:0] d_i,
    output wire          busy_o,
    output wire          done_o,
    output wire          err_o,
    output wire [QW-1:0] q_o
);

localparam integer CW = 6;          // the count (QW < 64)

reg           busy_q, done_q, err_q;
reg  [CW-1:0] left_q;
reg  [DW-1:0] rem_q, d_q;
reg  [QW-1:0] sr_q;                 // k's low bits shifting out, the quotient's shifting in

// The start: the quotient fits iff k's high part is below d.
wire [DW-1:0] k_hi  = {{(DW-(KW-QW)){1'b0}}, k_i[KW-1:QW]};
wire          bad   = d_i == {DW{1'b0}} || k_hi >= d_i;
// One step: the remainder with k's next bit, less d where it fits.
wire [DW:0]   t     = {rem_q, sr_q[QW-1]};
wire [DW:0]   t_sub = t - {1'b0, d_q};
wire          fits  = !t_sub[DW];   // t >= d

assign busy_o = busy_q;
assign done_o = done_q;
assign err_o  = err_q;
assign q_o    = sr_q;

always @(posedge clk) begin
    if (rst) begin
        busy_q <= 1'b0;
        done_q <= 1'b0;
        err_q  <= 1'b0;
        left_q <= {CW{1'b0}};
        rem_q  <= {DW{1'b0}};
        d_q    <= {DW{1'b0}};
        sr_q   <= {QW{1'b0}};
    end else begin
        done_q <= 1'b0;
        if (busy_q) begin
            rem_q  <= fits ? t_sub[DW-1:0] : t[DW-1:0];
            sr_q   <= {sr_q[QW-2:0], fits};
            left_q <= left_q - 1'b1;
            if (left_q == {{(CW-1){1'b0}}, 1'b1}) begin
                busy_q <= 1'b0;
                done_q <= 1'b1;
            end
        end else if (start_i) begin
            err_q <= bad;
            d_q   <= d_i;
            if (bad) begin
                done_q <= 1'b1;
                sr_q   <= {QW{1'b0}};
            end else begin
                busy_q <= 1'b1;
                left_q <= QW[CW-1:0];
                rem_q  <= k_hi;
                sr_q   <= k_i[QW-1:0];
            end
        end
    end
end

endmodule
`resetall
