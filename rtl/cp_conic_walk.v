// SPDX-License-Identifier: MIT
// cp_conic_walk — the walking half of the conic engine (seed 001, docs/CONIC.md
// "The rule"): G and its gradient at the current node, the move the rule makes
// from there, and the node after it, by additions only.
//
// Shared by rtl/cp_conic.v (the engine on its own, which reaches the start node's
// values by serial evaluation) and by the motion core's conic segments (whose host
// sends them: docs/CONIC.md "On the card"). It holds no control state: `load_i`
// takes a node's values, `adv_i` moves to the node after `mv_dx_o`, `mv_dy_o`
// (load wins). The move is combinational in the registers.
//
// Area (docs/CONIC.md "Widths and area"): the signs sx, sy are never 0 in the rule,
// so s·v is v or its one's complement plus one; the ones are gathered with the
// narrow coefficient terms, and every wide sum is three wide additions at most.
// Results are taken modulo 2^IW: the users size IW so that nothing wraps (cp_conic
// by its parameters, the core by the host's check of every node of the walk).
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_conic_walk #(
    // Signed width of A, B and C.
    parameter integer QW = 16,
    // Width of G, its gradient and the half-grid evaluations.
    parameter integer IW = 40
) (
    input  wire          clk,

    input  wire          load_i,
    input  wire [QW-1:0] a_i,
    input  wire [QW-1:0] b_i,
    input  wire [QW-1:0] c_i,
    input  wire [IW-1:0] g_i,
    input  wire [IW-1:0] gx_i,
    input  wire [IW-1:0] gy_i,
    // 1: clockwise (G > 0 on the left of travel); 0: counter-clockwise.
    input  wire          cw_i,

    input  wire          adv_i,

    // The move from the current node, two's complement: 01 = +1, 11 = -1, 00 = 0.
    output wire [1:0]    mv_dx_o,
    output wire [1:0]    mv_dy_o,
    // The current node's values and the conic (for the users' checks).
    output wire [IW-1:0] g_o,
    output wire [IW-1:0] gx_o,
    output wire [IW-1:0] gy_o,
    output wire [QW-1:0] a_o,
    output wire [QW-1:0] b_o,
    output wire [QW-1:0] c_o,
    output wire          cw_o
);

localparam integer KW = QW + 4;  // the narrow terms: |K| < 2^(QW+3) + 8

generate
    if (QW < 2 || QW > 32) begin : g_check_qw
        cp_conic_walk_parameter_QW_must_be_2_to_32 u_bad ();
    end
    if (IW < KW + 2 || IW > 120) begin : g_check_iw
        cp_conic_walk_parameter_IW_must_be_QW_plus_6_to_120 u_bad ();
    end
endgenerate

reg signed [QW-1:0] a_q, b_q, c_q;
reg signed [IW-1:0] g_q, gx_q, gy_q;
reg                 cw_q;

wire signed [KW-1:0] ka = {{(KW-QW){a_q[QW-1]}}, a_q};
wire signed [KW-1:0] kb = {{(KW-QW){b_q[QW-1]}}, b_q};
wire signed [KW-1:0] kc = {{(KW-QW){c_q[QW-1]}}, c_q};
wire signed [IW-1:0] zero = {IW{1'b0}};

// ---------------------------------------------------------------- the quadrant
// Direction of travel T: clockwise (gy, -gx), counter-clockwise (-gy, gx). A zero
// component is a quadrant change: the curve turns to its concave side.
wire gx_zero = gx_q == zero;
wire gy_zero = gy_q == zero;
wire gx_pos  = !gx_q[IW-1] && !gx_zero;
wire gy_pos  = !gy_q[IW-1] && !gy_zero;
wire a_pos   = !a_q[QW-1] && a_q != {QW{1'b0}};
wire c_pos   = !c_q[QW-1] && c_q != {QW{1'b0}};
// nsx: sx = -1. Tx = +-gy: negative when gy > 0 clockwise, gy < 0 counter-clockwise.
wire nsx = gy_zero ? (c_pos == gx_pos) : (cw_q ? gy_q[IW-1] : gy_pos);
wire nsy = gx_zero ? (a_pos == gy_pos) : (cw_q ? gx_pos : gx_q[IW-1]);
wire same = nsx == nsy;

// s·v = (v ^ {IW{ns}}) + ns.
wire signed [IW-1:0] gxs = gx_q ^ {IW{nsx}};
wire signed [IW-1:0] gys = gy_q ^ {IW{nsy}};
wire signed [KW-1:0] sb  = same ? kb : -kb;

// ---------------------------------------------------------------- the choice
// eL = 4g + 2 sx gx + 4 sy gy + A + 2 sx sy B + 4C at L = P + (sx/2, sy);
// eM = 4g + 4 sx gx + 2 sy gy + 4A + 2 sx sy B + C at M = P + (sx, sy/2).
wire signed [KW-1:0] kl = ka + (sb <<< 1) + (kc <<< 2) + {{(KW-3){1'b0}}, nsy, nsx, 1'b0};
wire signed [KW-1:0] km = (ka <<< 2) + (sb <<< 1) + kc + {{(KW-3){1'b0}}, nsx, nsy, 1'b0};
wire signed [IW-1:0] e_l = (g_q <<< 2) + (gxs <<< 1) + (gys <<< 2) + {{(IW-KW){kl[KW-1]}}, kl};
wire signed [IW-1:0] e_m = (g_q <<< 2) + (gxs <<< 2) + (gys <<< 1) + {{(IW-KW){km[KW-1]}}, km};
// A half-grid point is on the left of travel when 4G > 0 there (clockwise) or < 0.
wire left_l = cw_q ? (!e_l[IW-1] && e_l != zero) : e_l[IW-1];
wire left_m = cw_q ? (!e_m[IW-1] && e_m != zero) : e_m[IW-1];
// The far boundary from its left end: Y, L, corner, M, X when sx sy > 0; X, M,
// corner, L, Y otherwise. First midpoint on the right: the left end; the first
// only on the left: the corner; both: the right end.
wire first  = same ? left_l : left_m;
wire second = same ? left_m : left_l;
wire step_x = first && (!second || same) || !first && !same;
wire step_y = first && (!second || !same) || !first && same;

// ---------------------------------------------------------------- the next node
// g  <- g + dx gx + dy gy + A dx^2 + B dx dy + C dy^2
// gx <- gx + 2A dx + B dy
// gy <- gy + B dx + 2C dy
wire signed [IW-1:0] tgx = step_x ? gxs : zero;
wire signed [IW-1:0] tgy = step_y ? gys : zero;
wire signed [KW-1:0] kg = (step_x ? ka + {{(KW-1){1'b0}}, nsx} : {KW{1'b0}})
                        + (step_y ? kc + {{(KW-1){1'b0}}, nsy} : {KW{1'b0}})
                        + ((step_x && step_y) ? sb : {KW{1'b0}});
wire signed [KW-1:0] a2s = nsx ? -(ka <<< 1) : (ka <<< 1);
wire signed [KW-1:0] c2s = nsy ? -(kc <<< 1) : (kc <<< 1);
wire signed [KW-1:0] bx  = nsx ? -kb : kb;
wire signed [KW-1:0] by  = nsy ? -kb : kb;
wire signed [KW-1:0] kgx = (step_x ? a2s : {KW{1'b0}}) + (step_y ? by : {KW{1'b0}});
wire signed [KW-1:0] kgy = (step_x ? bx : {KW{1'b0}}) + (step_y ? c2s : {KW{1'b0}});
wire signed [IW-1:0] nx_g  = g_q + tgx + tgy + {{(IW-KW){kg[KW-1]}}, kg};
wire signed [IW-1:0] nx_gx = gx_q + {{(IW-KW){kgx[KW-1]}}, kgx};
wire signed [IW-1:0] nx_gy = gy_q + {{(IW-KW){kgy[KW-1]}}, kgy};

always @(posedge clk) begin
    if (load_i) begin
        a_q  <= a_i;
        b_q  <= b_i;
        c_q  <= c_i;
        g_q  <= g_i;
        gx_q <= gx_i;
        gy_q <= gy_i;
        cw_q <= cw_i;
    end else if (adv_i) begin
        g_q  <= nx_g;
        gx_q <= nx_gx;
        gy_q <= nx_gy;
    end
end

assign mv_dx_o = !step_x ? 2'b00 : nsx ? 2'b11 : 2'b01;
assign mv_dy_o = !step_y ? 2'b00 : nsy ? 2'b11 : 2'b01;
assign g_o  = g_q;
assign gx_o = gx_q;
assign gy_o = gy_q;
assign a_o  = a_q;
assign b_o  = b_q;
assign c_o  = c_q;
assign cw_o = cw_q;

endmodule

`resetall
