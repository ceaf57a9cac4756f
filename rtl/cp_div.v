// SPDX-License-Identifier: MIT
// cp_div — a serial divider for the conic length rule: q = floor(k * 2^s / D),
// D = d + d_inc, one quotient bit a clock (issue 13: a conic move's length on a
// phase-timer card, docs/CONIC.md "The length rule"; cp_conic_serial divides with it).
//
// start_i while idle (busy_o low) starts a division of the KW + s bits of k * 2^s,
// most significant first, one a clock: the partial remainder (from 0) takes the
// next bit and loses D where it fits (restoring division), and the bit that fits
// shifts into the quotient. k_i, s_i, d_i and d_inc_i are read every clock of it:
// the caller holds them from start_i until done_o. The divisor is given as d +
// d_inc so that a caller holding a signed v gives |v| without an adder: v ^ {sign}
// and the sign. A quotient bit that leaves the QW-bit quotient is remembered: the
// quotient does not fit, and q_o is 2^QW - 1 (saturated). (D = 0: every bit fits,
// the quotient is 2^(KW + s) - 1, saturated where that does not fit.) The clock
// after the last bit, done_o pulses; q_o holds until the next start. A start while
// busy is ignored.
//
// Model twin model/cp_div.*, bench tb/core/test_div.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_div #(
    parameter integer DW = 40,    // divisor (d_i; D = d + d_inc <= 2^DW)
    parameter integer KW = 27,    // dividend's significand
    parameter integer SW = 5,     // its shift
    parameter integer QW = 32     // quotient
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          start_i,
    input  wire [KW-1:0] k_i,
    input  wire [SW-1:0] s_i,
    input  wire [DW-1:0] d_i,
    input  wire          d_inc_i,
    output wire          busy_o,
    output wire          done_o,
    output wire [QW-1:0] q_o
);

localparam integer CW = 7;          // the count of dividend bits, KW + s < 2^(CW-1)
localparam integer KB = $clog2(KW); // an index into k

generate
    if (KW < 2 || SW > 5 || QW < 2 || QW > 62 || DW < 2 || DW > 62 || KW + (1 << SW) - 1 >= (1 << (CW - 1))) begin : g_check
        cp_div_parameters_out_of_range u_bad ();
    end
endgenerate

reg           busy_q, done_q, ovf_q;
reg  [CW-1:0] left_q;               // dividend bits still to take
reg  [DW-1:0] rem_q;
reg  [QW-1:0] q_q;

// The dividend's next bit: bit left - 1 of k * 2^s, k's bit left - 1 - s or a 0.
wire [CW-1:0] idx    = left_q - {{(CW-SW){1'b0}}, s_i} - 1'b1;
wire          kbit   = !idx[CW-1] && k_i[idx[KB-1:0]];   // (idx < KW where it is not negative)
wire unused_idx = &{1'b0, idx[CW-2:KB]};
// t - d - inc = t + ~d + !inc, the carry in added as a low bit of both operands.
wire [DW:0]   t      = {rem_q, kbit};
wire [DW+2:0] t_sub  = {1'b0, t, 1'b1} + {1'b1, ~{1'b0, d_i}, !d_inc_i};
wire          fits   = !t_sub[DW+2];   // t >= D
wire [DW-1:0] t_next = fits ? t_sub[DW:1] : t[DW-1:0];   // < D <= 2^DW

assign busy_o = busy_q;
assign done_o = done_q;
assign q_o    = ovf_q ? {QW{1'b1}} : q_q;

always @(posedge clk) begin
    if (rst) begin
        busy_q <= 1'b0;
        done_q <= 1'b0;
        left_q <= {CW{1'b0}};
    end else begin
        done_q <= 1'b0;
        if (busy_q) begin
            left_q <= left_q - 1'b1;
            if (left_q == {{(CW-1){1'b0}}, 1'b1}) begin
                busy_q <= 1'b0;
                done_q <= 1'b1;
            end
        end else if (start_i) begin
            busy_q <= 1'b1;
            left_q <= {{(CW-SW){1'b0}}, s_i} + KW[CW-1:0];
        end
    end
    if (busy_q) begin
        rem_q <= t_next;
        q_q   <= {q_q[QW-2:0], fits};
        ovf_q <= ovf_q || q_q[QW-1];
    end else if (start_i) begin
        rem_q <= {DW{1'b0}};
        q_q   <= {QW{1'b0}};
        ovf_q <= 1'b0;
    end
end

endmodule
`resetall
