// SPDX-License-Identifier: MIT
// cp_conic — combined-step conic engine (seed 001, docs/CONIC.md).
//
// Walks the curve G(x, y) = A x^2 + B xy + C y^2 + D x + E y + F = 0 from a start
// node to an end node, one move (dx, dy), each in {-1, 0, 1}, per clock. At the
// current node P it keeps G(P) and the gradient (Gx, Gy) by additions only (the
// second differences 2A, B, 2C are constant); the move is chosen from the signs of
// 4G at the half-grid points L = P + (sx/2, sy) and M = P + (sx, sy/2) of the square
// ahead, (sx, sy) the quadrant of the direction of travel, itself the sign of the
// rotated gradient (docs/CONIC.md "The rule").
//
// Setup has no multiplier either: G and its gradient at the start and at the end
// node are evaluated bit-serially, most significant bit first, (x, y) <- (2x + bx,
// 2y + by): PW clocks per point (docs/CONIC.md "Setup").
//
// Valid/ready contract (docs/ENGINE.md): a transfer happens on a rising edge where
// valid && ready; valid never waits for ready; while valid && !ready the data holds.
//
// Not yet instantiated by cp_core / cp_card (issue 13): linting rtl/ all at once
// names it a second top level (MULTITOP); tb/lint lints it as its own top.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_conic #(
    // Signed width accepted for A, B and C (the port is 64 bits; wider values are refused).
    parameter integer QW = 16,
    // Signed width accepted for D and E.
    parameter integer LW = 32,
    // Signed width accepted for F.
    parameter integer FW = 48,
    // Signed width accepted for the start and end coordinates (the port is 32 bits).
    parameter integer PW = 20,
    // Most moves of one request; a walk that has not reached the end by then stops
    // with ERR_END_MISSED.
    parameter integer NMAX = 1048575
) (
    input  wire          clk,
    input  wire          rst,

    // Request: the conic, the start and end node, the direction.
    input  wire          in_valid_i,
    output wire          in_ready_o,
    input  wire [63:0]   in_a_i,
    input  wire [63:0]   in_b_i,
    input  wire [63:0]   in_c_i,
    input  wire [63:0]   in_d_i,
    input  wire [63:0]   in_e_i,
    input  wire [63:0]   in_f_i,
    input  wire [31:0]   in_x0_i,
    input  wire [31:0]   in_y0_i,
    input  wire [31:0]   in_x1_i,
    input  wire [31:0]   in_y1_i,
    // 1: clockwise (G > 0 on the left of travel); 0: counter-clockwise.
    input  wire          in_cw_i,

    // A refused request: one-clock pulse with the reason (ERR_* below).
    output wire          err_o,
    output wire [2:0]    err_code_o,

    // Move stream: dx, dy in two's complement (2'b01 = +1, 2'b11 = -1), and the node
    // the move arrives at. All zero while not valid.
    output wire          move_valid_o,
    input  wire          move_ready_i,
    output wire [1:0]    move_dx_o,
    output wire [1:0]    move_dy_o,
    output wire          move_last_o,
    output wire [XW-1:0] move_x_o,
    output wire [XW-1:0] move_y_o
);

// Width of the move counter.
localparam integer NW = $clog2(NMAX + 1);
// Width of the walk's position: |x| <= 2^(PW-1) + NMAX.
localparam integer XW = ((PW > NW + 1) ? PW : NW + 1) + 1;
// Width of G, its gradient and the half-grid evaluations: bounds in docs/CONIC.md "Widths".
localparam integer IW0 = (FW > LW + XW) ? FW : LW + XW;
localparam integer IW = ((IW0 > QW + 2 * XW) ? IW0 : QW + 2 * XW) + 6;
// Width of the serial evaluation's bit index.
localparam integer BW = $clog2(PW);

localparam [NW-1:0] NMAX_N = NMAX[NW-1:0];

// Refusal reasons, checked in this order.
localparam [2:0] ERR_NONE        = 3'd0;
localparam [2:0] ERR_COEF_RANGE  = 3'd1;
localparam [2:0] ERR_POINT_RANGE = 3'd2;
localparam [2:0] ERR_DEGENERATE  = 3'd3;
localparam [2:0] ERR_START_OFF   = 3'd4;
localparam [2:0] ERR_END_OFF     = 3'd5;
localparam [2:0] ERR_END_MISSED  = 3'd6;

localparam [2:0] S_IDLE   = 3'd0;
localparam [2:0] S_EVAL0  = 3'd1;
localparam [2:0] S_EVAL1  = 3'd2;
localparam [2:0] S_CHECK  = 3'd3;
localparam [2:0] S_WALK   = 3'd4;

localparam [1:0] P1 = 2'b01;
localparam [1:0] M1 = 2'b11;
localparam [1:0] Z0 = 2'b00;

generate
    if (QW < 2 || QW > 32) begin : g_check_qw
        cp_conic_parameter_QW_must_be_2_to_32 u_bad ();
    end
    if (LW < 2 || LW > 48) begin : g_check_lw
        cp_conic_parameter_LW_must_be_2_to_48 u_bad ();
    end
    if (FW < 2 || FW > 64) begin : g_check_fw
        cp_conic_parameter_FW_must_be_2_to_64 u_bad ();
    end
    if (PW < 2 || PW > 30) begin : g_check_pw
        cp_conic_parameter_PW_must_be_2_to_30 u_bad ();
    end
    if (NMAX < 1 || NMAX > 1073741824) begin : g_check_nmax
        cp_conic_parameter_NMAX_must_be_1_to_2_pow_30 u_bad ();
    end
    if (IW > 120) begin : g_check_iw
        cp_conic_parameters_make_internal_width_over_120 u_bad ();
    end
endgenerate

// ---------------------------------------------------------------- helpers
// v * s for s in {-1, 0, 1} (two's complement 2 bits): a negation or nothing.
function signed [IW-1:0] sel;
    input signed [IW-1:0] v;
    input [1:0] s;
    sel = (s == P1) ? v : (s == M1) ? -v : {IW{1'b0}};
endfunction

// s * t for s, t in {-1, 0, 1}.
function [1:0] sprod;
    input [1:0] s;
    input [1:0] t;
    sprod = (s == Z0 || t == Z0) ? Z0 : (s == t) ? P1 : M1;
endfunction

// The eight-point test (docs/CONIC.md "On the curve"): 4G at P + (i/2, j/2),
// i, j in {-1, 0, 1}, not (0, 0): the curve passes the unit square around P unless
// all eight are > 0 or all are < 0.
function on_curve;
    input signed [IW-1:0] g;
    input signed [IW-1:0] gx;
    input signed [IW-1:0] gy;
    input signed [IW-1:0] a;
    input signed [IW-1:0] b;
    input signed [IW-1:0] c;
    reg pos, neg;
    reg signed [IW-1:0] v;
    reg [1:0] si, sj;
    integer i, j;
    begin
        pos = 1'b0;
        neg = 1'b0;
        for (i = 0; i < 3; i = i + 1)
            for (j = 0; j < 3; j = j + 1)
                if (i != 1 || j != 1) begin
                    si = (i == 0) ? M1 : (i == 1) ? Z0 : P1;
                    sj = (j == 0) ? M1 : (j == 1) ? Z0 : P1;
                    v = (g <<< 2) + (sel(gx, si) <<< 1) + (sel(gy, sj) <<< 1)
                        + ((si != Z0) ? a : {IW{1'b0}}) + sel(b, sprod(si, sj))
                        + ((sj != Z0) ? c : {IW{1'b0}});
                    if (!v[IW-1]) pos = 1'b1;
                    if (v[IW-1] || v == {IW{1'b0}}) neg = 1'b1;
                end
        on_curve = pos && neg;
    end
endfunction

// Does a 64-bit word hold a signed value of w bits? (bits w-1 .. 63 all equal)
function fits64;
    input [63:0] v;
    input integer w;
    reg [63:0] top;
    begin
        top = v >> (w - 1);
        fits64 = top == {64{1'b0}} || (v | ({64{1'b1}} >> (65 - w))) == {64{1'b1}};
    end
endfunction

function fits32;
    input [31:0] v;
    input integer w;
    reg [31:0] top;
    begin
        top = v >> (w - 1);
        fits32 = top == {32{1'b0}} || (v | ({32{1'b1}} >> (33 - w))) == {32{1'b1}};
    end
endfunction

// ---------------------------------------------------------------- state
// Control state (reset).
reg [2:0]    state_q, state_d;
reg          out_valid_q, out_valid_d;
reg          err_q, err_d;

// Datapath (loaded on acceptance, no reset).
reg [2:0]    err_code_q, err_code_d;
reg signed [IW-1:0] a_q, a_d, b_q, b_d, c_q, c_d, d_q, d_d, e_q, e_d, f_q, f_d;
reg [PW-1:0] x0_q, x0_d, y0_q, y0_d, x1_q, x1_d, y1_q, y1_d;
reg          cw_q, cw_d;
reg [BW-1:0] bit_q, bit_d;
reg signed [IW-1:0] q_q, q_d, ux_q, ux_d, uy_q, uy_d, l_q, l_d;
reg signed [XW-1:0] x_q, x_d, y_q, y_d;
reg [NW-1:0] count_q, count_d;
reg [1:0]    out_dx_q, out_dx_d, out_dy_q, out_dy_d;
reg [XW-1:0] out_x_q, out_x_d, out_y_q, out_y_d;
reg          out_last_q, out_last_d, out_miss_q, out_miss_d;

wire accept = in_valid_i && in_ready_o;
wire issue  = state_q == S_WALK && (!out_valid_q || move_ready_i);

localparam integer PW1 = PW - 1;
localparam [BW-1:0] TOP_BIT = PW1[BW-1:0];

// ---------------------------------------------------------------- serial evaluation
// One bit of the coordinates: the sign bit weighs -2^(PW-1), so it steps by -1.
wire [PW-1:0] ev_px = (state_q == S_EVAL0) ? x0_q : x1_q;
wire [PW-1:0] ev_py = (state_q == S_EVAL0) ? y0_q : y1_q;
wire          ev_sign = bit_q == TOP_BIT;
wire [1:0]    ev_bx = !ev_px[bit_q] ? Z0 : ev_sign ? M1 : P1;
wire [1:0]    ev_by = !ev_py[bit_q] ? Z0 : ev_sign ? M1 : P1;
wire signed [IW-1:0] ev_q  = (q_q <<< 2) + (sel(ux_q, ev_bx) <<< 1) + (sel(uy_q, ev_by) <<< 1)
                           + ((ev_bx != Z0) ? a_q : {IW{1'b0}}) + sel(b_q, sprod(ev_bx, ev_by))
                           + ((ev_by != Z0) ? c_q : {IW{1'b0}});
wire signed [IW-1:0] ev_ux = (ux_q <<< 1) + (sel(a_q, ev_bx) <<< 1) + sel(b_q, ev_by);
wire signed [IW-1:0] ev_uy = (uy_q <<< 1) + sel(b_q, ev_bx) + (sel(c_q, ev_by) <<< 1);
wire signed [IW-1:0] ev_l  = (l_q <<< 1) + sel(d_q, ev_bx) + sel(e_q, ev_by);

// The end node's G and gradient once S_EVAL1 is done.
wire signed [IW-1:0] end_g  = q_q + l_q + f_q;
wire signed [IW-1:0] end_gx = ux_q + d_q;
wire signed [IW-1:0] end_gy = uy_q + e_q;

// ---------------------------------------------------------------- the rule
// The walk's G and gradient, the move from the current node and the node after it
// (rtl/cp_conic_walk.v): loaded with the start node's values when S_EVAL0 ends.
wire          walk_load = state_q == S_EVAL0 && bit_q == {BW{1'b0}};
wire [1:0]    mv_dx, mv_dy;
wire signed [IW-1:0] g_q, gx_q, gy_q;

cp_conic_walk #(.QW(QW), .IW(IW)) u_walk (
    .clk     (clk),
    .load_i  (walk_load),
    .a_i     (a_q[QW-1:0]),
    .b_i     (b_q[QW-1:0]),
    .c_i     (c_q[QW-1:0]),
    .g_i     (ev_q + ev_l + f_q),
    .gx_i    (ev_ux + d_q),
    .gy_i    (ev_uy + e_q),
    .cw_i    (cw_q),
    .adv_i   (issue),
    .mv_dx_o (mv_dx),
    .mv_dy_o (mv_dy),
    .g_o     (g_q),
    .gx_o    (gx_q),
    .gy_o    (gy_q),
    /* verilator lint_off PINCONNECTEMPTY */
    .a_o     (),
    .b_o     (),
    .c_o     (),
    .cw_o    ()
    /* verilator lint_on PINCONNECTEMPTY */
);

wire signed [XW-1:0] nx_x  = x_q + {{(XW-2){mv_dx[1]}}, mv_dx};
wire signed [XW-1:0] nx_y  = y_q + {{(XW-2){mv_dy[1]}}, mv_dy};
wire [NW-1:0]        nx_count = count_q + 1'b1;
wire at_end = nx_x == {{(XW-PW){x1_q[PW-1]}}, x1_q} && nx_y == {{(XW-PW){y1_q[PW-1]}}, y1_q};

wire coef_ok = fits64(in_a_i, QW) && fits64(in_b_i, QW) && fits64(in_c_i, QW)
            && fits64(in_d_i, LW) && fits64(in_e_i, LW) && fits64(in_f_i, FW);
wire point_ok = fits32(in_x0_i, PW) && fits32(in_y0_i, PW) && fits32(in_x1_i, PW)
             && fits32(in_y1_i, PW);

always @* begin
    state_d     = state_q;
    out_valid_d = out_valid_q;
    err_d       = 1'b0;
    err_code_d  = err_code_q;
    a_d = a_q;  b_d = b_q;  c_d = c_q;  d_d = d_q;  e_d = e_q;  f_d = f_q;
    x0_d = x0_q;  y0_d = y0_q;  x1_d = x1_q;  y1_d = y1_q;  cw_d = cw_q;
    bit_d = bit_q;
    q_d = q_q;  ux_d = ux_q;  uy_d = uy_q;  l_d = l_q;
    x_d = x_q;  y_d = y_q;
    count_d = count_q;
    out_dx_d = out_dx_q;  out_dy_d = out_dy_q;  out_x_d = out_x_q;  out_y_d = out_y_q;
    out_last_d = out_last_q;  out_miss_d = out_miss_q;

    if (out_valid_q && move_ready_i) begin
        out_valid_d = 1'b0;
        if (out_miss_q) begin
            err_d      = 1'b1;
            err_code_d = ERR_END_MISSED;
        end
    end

    case (state_q)
    S_IDLE: if (accept) begin
        if (!coef_ok) begin
            err_d = 1'b1;  err_code_d = ERR_COEF_RANGE;
        end else if (!point_ok) begin
            err_d = 1'b1;  err_code_d = ERR_POINT_RANGE;
        end else begin
            a_d = {{(IW-QW){in_a_i[QW-1]}}, in_a_i[QW-1:0]};
            b_d = {{(IW-QW){in_b_i[QW-1]}}, in_b_i[QW-1:0]};
            c_d = {{(IW-QW){in_c_i[QW-1]}}, in_c_i[QW-1:0]};
            d_d = {{(IW-LW){in_d_i[LW-1]}}, in_d_i[LW-1:0]};
            e_d = {{(IW-LW){in_e_i[LW-1]}}, in_e_i[LW-1:0]};
            f_d = {{(IW-FW){in_f_i[FW-1]}}, in_f_i[FW-1:0]};
            x0_d = in_x0_i[PW-1:0];  y0_d = in_y0_i[PW-1:0];
            x1_d = in_x1_i[PW-1:0];  y1_d = in_y1_i[PW-1:0];
            cw_d = in_cw_i;
            bit_d = TOP_BIT;
            q_d = {IW{1'b0}};  ux_d = {IW{1'b0}};  uy_d = {IW{1'b0}};  l_d = {IW{1'b0}};
            state_d = S_EVAL0;
        end
    end

    S_EVAL0: begin
        q_d = ev_q;  ux_d = ev_ux;  uy_d = ev_uy;  l_d = ev_l;
        bit_d = bit_q - 1'b1;
        if (bit_q == {BW{1'b0}}) begin
            x_d  = {{(XW-PW){x0_q[PW-1]}}, x0_q};
            y_d  = {{(XW-PW){y0_q[PW-1]}}, y0_q};
            bit_d = TOP_BIT;
            q_d = {IW{1'b0}};  ux_d = {IW{1'b0}};  uy_d = {IW{1'b0}};  l_d = {IW{1'b0}};
            state_d = S_EVAL1;
        end
    end

    S_EVAL1: begin
        q_d = ev_q;  ux_d = ev_ux;  uy_d = ev_uy;  l_d = ev_l;
        bit_d = bit_q - 1'b1;
        if (bit_q == {BW{1'b0}}) state_d = S_CHECK;
    end

    S_CHECK: begin
        if (gx_q == {IW{1'b0}} && gy_q == {IW{1'b0}}) begin
            err_d = 1'b1;  err_code_d = ERR_DEGENERATE;  state_d = S_IDLE;
        end else if (!on_curve(g_q, gx_q, gy_q, a_q, b_q, c_q)) begin
            err_d = 1'b1;  err_code_d = ERR_START_OFF;  state_d = S_IDLE;
        end else if (!on_curve(end_g, end_gx, end_gy, a_q, b_q, c_q)) begin
            err_d = 1'b1;  err_code_d = ERR_END_OFF;  state_d = S_IDLE;
        end else begin
            count_d = {NW{1'b0}};
            state_d = S_WALK;
        end
    end

    S_WALK: if (issue) begin
        x_d = nx_x;  y_d = nx_y;
        count_d = nx_count;
        out_valid_d = 1'b1;
        out_dx_d = mv_dx;  out_dy_d = mv_dy;
        out_x_d = nx_x;  out_y_d = nx_y;
        out_last_d = at_end || nx_count == NMAX_N;
        out_miss_d = !at_end && nx_count == NMAX_N;
        if (at_end || nx_count == NMAX_N) state_d = S_IDLE;
    end

    default: state_d = S_IDLE;
    endcase
end

always @(posedge clk) begin
    if (rst) begin
        state_q     <= S_IDLE;
        out_valid_q <= 1'b0;
        err_q       <= 1'b0;
    end else begin
        state_q     <= state_d;
        out_valid_q <= out_valid_d;
        err_q       <= err_d;
    end
    err_code_q <= err_code_d;
    a_q <= a_d;  b_q <= b_d;  c_q <= c_d;  d_q <= d_d;  e_q <= e_d;  f_q <= f_d;
    x0_q <= x0_d;  y0_q <= y0_d;  x1_q <= x1_d;  y1_q <= y1_d;  cw_q <= cw_d;
    bit_q <= bit_d;
    q_q <= q_d;  ux_q <= ux_d;  uy_q <= uy_d;  l_q <= l_d;
    x_q <= x_d;  y_q <= y_d;
    count_q <= count_d;
    out_dx_q <= out_dx_d;  out_dy_q <= out_dy_d;  out_x_q <= out_x_d;  out_y_q <= out_y_d;
    out_last_q <= out_last_d;  out_miss_q <= out_miss_d;
end

// ---------------------------------------------------------------- outputs
assign in_ready_o   = state_q == S_IDLE && !out_valid_q;
assign err_o        = err_q;
assign err_code_o   = err_q ? err_code_q : ERR_NONE;
assign move_valid_o = out_valid_q;
assign move_dx_o    = out_valid_q ? out_dx_q : Z0;
assign move_dy_o    = out_valid_q ? out_dy_q : Z0;
assign move_last_o  = out_valid_q && out_last_q;
assign move_x_o     = out_valid_q ? out_x_q : {XW{1'b0}};
assign move_y_o     = out_valid_q ? out_y_q : {XW{1'b0}};

endmodule

`resetall
