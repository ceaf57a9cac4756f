// SPDX-License-Identifier: MIT
// cp_conic_serial — the conic walk of seed 001, bit-serial: the motion core's
// walker for conic segments (docs/CONIC.md "The walk, bit-serial").
//
// Same rule, same moves as rtl/cp_conic_walk.v (docs/CONIC.md "The rule"), in a
// fraction of its logic: G and its gradient at the current node live in three
// IW-bit shift registers that turn once a pass, least significant bit first. A pass
// applies the move decided by the previous pass (none after a load) with three
// serial adders and, from the new bits as they appear, evaluates 4G at the two
// half-grid points L and M of the square ahead for all four quadrants at once
// (eight serial adders); at its last bit the signs of the new gradient pick the
// quadrant, and the signs of its two evaluations the move. A move is therefore
// decided every IW + 1 clocks at most (docs/CONIC.md "The walk, bit-serial").
//
// The walker is told where the walk ends (the end node minus the start node) and
// marks the move that arrives there; after it, it stops. It does not check that
// the start node is on the curve or that the end is reached: the core counts the
// segment's moves and checks the mark (docs/CORE.md). Arithmetic is modulo 2^IW;
// the host keeps every value of the walk within IW bits (it runs the same walk).
//
// Valid/ready contract on the moves (docs/ENGINE.md): valid never waits for ready;
// while valid && !ready the move holds.
//
// With LEN = 1 (a phase-timer core's walker, docs/CORE.md "Phase-timer builds") it
// also gives each move's length by the conic length rule (docs/CONIC.md "The length
// rule"): q = floor(K 2^S / m), m = max(|Gx|, |Gy|) at the node the move leaves,
// {S[31:27], K[26:0]} on len_k_i (the CONIC segment's L word, which the core holds
// while the segment is loaded, len_go_i), saturated to 2^32 - 1 (rtl/cp_div.v). A
// pass compares the two magnitudes of the node it computes serially as its bits
// appear (for all four sign cases; the signs at its last bit pick one); once the move
// it decides can be presented (nothing presented, or the presented move taken) and
// its segment is loaded, the divider divides by m from the shift registers, which
// hold still until that move is presented, and the move is presented in the clock
// the division is done: a presented move's length is len_o (the next division
// starts only once it is taken).
//
// cp_run instantiates it in a core built with CONIC = 1 (docs/CORE.md "CONIC").
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_conic_serial #(
    // Signed width of A, B and C.
    parameter integer QW = 16,
    // Width of G, its gradient and the evaluations (two's complement, modulo 2^IW).
    parameter integer IW = 40,
    // Signed width of the end node's offset from the start node.
    parameter integer XW = 24,
    // 1: each move's length by the conic length rule (word 7, len_o).
    parameter integer LEN = 0
) (
    input  wire          clk,
    input  wire          rst,

    // Drop the walk and any move waiting; idle.
    input  wire          clear_i,
    // The conic, one word a clock, as a CONIC segment carries it (docs/CORE.md):
    // 0: B [31:16], A [15:0]; 1: clockwise [31], C [15:0]; 2, 3, 4: G, dG/dx, dG/dy at
    // the start node (32 bits, sign-extended to IW); 5, 6: the end node minus the start
    // node in x and in y ([23:0], sign-extended to XW). Taken only while not busy.
    input  wire          wr_i,
    input  wire [2:0]    wr_sel_i,
    input  wire [31:0]   wr_data_i,
    // Start walking from the words written (wins over clear; a move waiting is
    // dropped). A write in the same clock is taken first. With cont_i the walk goes
    // on from where the last one ended: its first pass applies that walk's last
    // move (kept since), so only the new end (words 5, 6, from that end node)
    // need be written.
    input  wire          start_i,
    input  wire          cont_i,

    // Walking: a pass under way or a decided move not yet presented.
    output wire          busy_o,

    // Moves: dx, dy in two's complement (01 = +1, 11 = -1, 00 = 0), and whether
    // the move arrives at the end node. All zero while not valid.
    output wire          move_valid_o,
    input  wire          move_ready_i,
    output wire [1:0]    move_dx_o,
    output wire [1:0]    move_dy_o,
    output wire          move_end_o,

    // LEN: the walk's length rule {S, K}, held while len_go_i says its segment is
    // loaded (a division starts only then); the presented move's length (Q2.30; 0
    // with LEN = 0).
    input  wire [31:0]   len_k_i,
    input  wire          len_go_i,
    output wire [31:0]   len_o
);

localparam integer BW = $clog2(IW);
localparam integer IW1 = IW - 1;
localparam [BW-1:0] LAST = IW1[BW-1:0];

generate
    if (QW < 2 || QW > 16) begin : g_check_qw
        cp_conic_serial_parameter_QW_must_be_2_to_16 u_bad ();
    end
    if (IW < QW + 4 || IW > 128) begin : g_check_iw
        cp_conic_serial_parameter_IW_must_be_QW_plus_4_to_128 u_bad ();
    end
    if (XW < 2 || XW > 24) begin : g_check_xw
        cp_conic_serial_parameter_XW_must_be_2_to_24 u_bad ();
    end
    if (LEN != 0 && (IW < 26 || IW > 61)) begin : g_check_len
        cp_conic_serial_parameter_IW_must_be_26_to_61_with_LEN u_bad ();
    end
endgenerate

// ---------------------------------------------------------------- state
// Control (reset).
reg          pass_q;        // a pass is running (bit i_q of it this cycle)
reg          pend_q;        // a decided move waits to be presented
reg          ov_q;          // a move is presented
// Datapath.
reg [BW-1:0] i_q;
reg [IW-1:0] sg_q, sgx_q, sgy_q;   // G, Gx, Gy: bit i_q at [0] during a pass
reg [QW-1:0] a_q, b_q, c_q;
reg          cw_q;
reg [XW-1:0] du_q, dv_q;           // the end node minus the current node
// The move this pass applies (from the previous pass's decision): which axes step
// and the quadrant's signs (1: -1).
reg          mx_q, my_q, qx_q, qy_q;
// Serial state of the pass: delayed bits of the new values and of the constants,
// carries, "some bit was 1".
reg          g1_q, g2_q, x1_q, x2_q, y1_q, y2_q;
reg          a1_q, a2_q, b1_q, c1_q, c2_q;
reg [2:0]    cg_q;
reg [1:0]    cx_q, cy_q;
reg          nzx_q, nzy_q;
// The presented move.
reg [1:0]    odx_q, ody_q;
reg          oend_q;

// ---------------------------------------------------------------- one bit of a pass
wire first_bit = i_q == {BW{1'b0}};
wire v1 = !first_bit;                          // i >= 1
wire v2 = v1 && i_q != {{(BW-1){1'b0}}, 1'b1}; // i >= 2

// Bit i of A, B and C, sign-extended.
wire [IW-1:0] a_x = {{(IW-QW){a_q[QW-1]}}, a_q};
wire [IW-1:0] b_x = {{(IW-QW){b_q[QW-1]}}, b_q};
wire [IW-1:0] c_x = {{(IW-QW){c_q[QW-1]}}, c_q};
wire ai = a_x[i_q], bi = b_x[i_q], ci = c_x[i_q];
wire a1 = v1 && a1_q, a2 = v2 && a2_q, b1 = v1 && b1_q, c1 = v1 && c1_q, c2 = v2 && c2_q;

// The move applied: g' = g + mx (sx gx) + my (sy gy) + mx A + my C + mx my (sx sy B),
// gx' = gx + mx 2 sx A + my sy B, gy' = gy + mx sx B + my 2 sy C, with s v = (v ^ ns) + ns.
wire qb = qx_q ^ qy_q;
wire [2:0] ig = {2'b00, mx_q && qx_q} + {2'b00, my_q && qy_q} + {2'b00, mx_q && my_q && qb};
wire [1:0] ix = {mx_q && qx_q, my_q && qy_q};   // 2 mx qx + my qy
wire [1:0] iy = {my_q && qy_q, mx_q && qx_q};   // mx qx + 2 my qy
wire [2:0] kg = first_bit ? ig : cg_q;
wire [1:0] kx = first_bit ? ix : cx_q;
wire [1:0] ky = first_bit ? iy : cy_q;
wire [3:0] colg = {1'b0, kg} + {3'b000, sg_q[0]} + {3'b000, mx_q && (sgx_q[0] ^ qx_q)}
                + {3'b000, my_q && (sgy_q[0] ^ qy_q)} + {3'b000, mx_q && ai} + {3'b000, my_q && ci}
                + {3'b000, mx_q && my_q && (bi ^ qb)};
wire [2:0] colx = {1'b0, kx} + {2'b00, sgx_q[0]} + {2'b00, mx_q && v1 && (a1_q ^ qx_q)}
                + {2'b00, my_q && (bi ^ qy_q)};
wire [2:0] coly = {1'b0, ky} + {2'b00, sgy_q[0]} + {2'b00, mx_q && (bi ^ qx_q)}
                + {2'b00, my_q && v1 && (c1_q ^ qy_q)};
wire ng = colg[0], nx = colx[0], ny = coly[0];   // bit i of G', Gx', Gy'
wire g2 = v2 && g2_q, x1 = v1 && x1_q, x2 = v2 && x2_q, y1 = v1 && y1_q, y2 = v2 && y2_q;

// The eight evaluations of the new node, evaluator 2q + m for quadrant q = {nsx, nsy}
// and point m (0: L, 1: M):
//   eL = 4g + 2 sx gx + 4 sy gy + A + 2 sx sy B + 4C
//   eM = 4g + 4 sx gx + 2 sy gy + 4A + 2 sx sy B + C
// each s v as (v ^ ns) + ns, the ones gathered into the first bit's carry.
// Evaluator q's bit i this cycle, and whether an earlier bit of it was 1.
wire [7:0] eb, enz;
genvar q;
generate
    for (q = 0; q < 8; q = q + 1) begin : g_eval
        localparam integer NSX = (q >> 2) & 1;
        localparam integer NSY = (q >> 1) & 1;
        localparam integer PM  = q & 1;
        localparam integer NB  = NSX ^ NSY;
        localparam integer INIT = (PM != 0) ? 4 * NSX + 2 * NSY + 2 * NB : 2 * NSX + 4 * NSY + 2 * NB;
        localparam [2:0] INIT3 = INIT[2:0];
        reg  [2:0] ec_q;
        reg        ez_q;
        wire tx = (PM != 0) ? (x2 ^ (v2 && NSX != 0)) : (x1 ^ (v1 && NSX != 0));
        wire ty = (PM != 0) ? (y1 ^ (v1 && NSY != 0)) : (y2 ^ (v2 && NSY != 0));
        wire ta = (PM != 0) ? a2 : ai;
        wire tc = (PM != 0) ? ci : c2;
        wire tb = b1 ^ (v1 && NB != 0);
        wire [2:0] k = first_bit ? INIT3 : ec_q;
        wire [3:0] col = {1'b0, k} + {3'b000, g2} + {3'b000, tx} + {3'b000, ty}
                       + {3'b000, ta} + {3'b000, tb} + {3'b000, tc};
        always @(posedge clk) begin
            ec_q <= col[3:1];
            ez_q <= !first_bit && ez_q || col[0];
        end
        assign eb[q]  = col[0];
        assign enz[q] = !first_bit && ez_q;
    end
endgenerate

// ---------------------------------------------------------------- the decision (last bit)
wire nz_x   = nzx_q || nx;
wire nz_y   = nzy_q || ny;
wire gx_pos = !nx && nz_x;   // at the last bit, nx is the sign of Gx'
wire gy_pos = !ny && nz_y;
wire a_pos  = !a_q[QW-1] && a_q != {QW{1'b0}};
wire c_pos  = !c_q[QW-1] && c_q != {QW{1'b0}};
// Direction of travel T: clockwise (gy, -gx), counter-clockwise (-gy, gx); a zero
// component is a quadrant change, to the concave side.
wire nsx  = !nz_y ? (c_pos == gx_pos) : (cw_q ? ny : gy_pos);
wire nsy  = !nz_x ? (a_pos == gy_pos) : (cw_q ? gx_pos : nx);
wire same = nsx == nsy;
wire [2:0] qsel = {nsx, nsy, 1'b0};
wire sign_l = eb[qsel];
wire sign_m = eb[qsel | 3'd1];
wire nz_l   = enz[qsel] || sign_l;
wire nz_m   = enz[qsel | 3'd1] || sign_m;
// A half-grid point is on the left of travel when 4G > 0 there (clockwise) or < 0.
wire left_l = cw_q ? (!sign_l && nz_l) : sign_l;
wire left_m = cw_q ? (!sign_m && nz_m) : sign_m;
wire first  = same ? left_l : left_m;
wire second = same ? left_m : left_l;
wire step_x = first && (!second || same) || !first && !same;
wire step_y = first && (!second || !same) || !first && same;

// ---------------------------------------------------------------- the move's length (LEN)
// The division for the decided move starts once it could be presented; the move is
// presented when the division is done (len_have).
wire out_free = !ov_q || move_ready_i;
wire len_have;

// ---------------------------------------------------------------- presenting a move
wire issue    = pend_q && out_free && len_have;
wire [1:0] dx = !mx_q ? 2'b00 : qx_q ? 2'b11 : 2'b01;
wire [1:0] dy = !my_q ? 2'b00 : qy_q ? 2'b11 : 2'b01;
wire [XW-1:0] du_n = du_q - {{(XW-2){dx[1]}}, dx};
wire [XW-1:0] dv_n = dv_q - {{(XW-2){dy[1]}}, dy};
wire at_end = du_n == {XW{1'b0}} && dv_n == {XW{1'b0}};
wire last_bit = pass_q && i_q == LAST;

// A written word, sign-extended.
wire [127:0] wr_s32 = {{96{wr_data_i[31]}}, wr_data_i};
wire [31:0]  wr_s16 = {{16{wr_data_i[15]}}, wr_data_i[15:0]};
wire [31:0]  wr_s16h = {{16{wr_data_i[31]}}, wr_data_i[31:16]};
wire [31:0]  wr_s24 = {{8{wr_data_i[23]}}, wr_data_i[23:0]};
wire         take_wr = wr_i && !busy_o;
wire unused_wr = &{1'b0, wr_s32[127:IW], wr_s16[31:QW], wr_s16h[31:QW], wr_s24[31:XW]};

generate
    if (LEN != 0) begin : g_len
        // Serial negations of Gx' and Gy' (carry in 1 at the first bit), and the four
        // comparisons |Gy'| > |Gx'| for each pair of signs {Gx' < 0, Gy' < 0}: the
        // later bit decides, equal bits keep the earlier answer.
        reg        cnx_q, cny_q, sel_q, neg_q;
        reg [3:0]  gt_q;
        wire       cnx = first_bit || cnx_q;
        wire       cny = first_bit || cny_q;
        wire       mx  = !nx ^ cnx, my = !ny ^ cny;        // bit i of -Gx', -Gy'
        wire [3:0] gt;
        genvar c;
        for (c = 0; c < 4; c = c + 1) begin : g_cmp
            wire ab = ((c >> 1) & 1) != 0 ? mx : nx;      // |Gx'| with Gx' < 0 assumed or not
            wire bb = (c & 1) != 0 ? my : ny;
            assign gt[c] = bb && !ab || !(ab ^ bb) && !first_bit && gt_q[c];
        end
        wire [1:0] sgn = {nx, ny};                         // at the last bit: the signs
        wire       sel = gt[sgn];
        wire       div_busy, div_done, len_start;
        wire [31:0] div_q;
        cp_div #(.DW(IW), .KW(27), .SW(5), .QW(32)) u_div (
            .clk(clk), .rst(rst || clear_i), .start_i(len_start), .k_i(len_k_i[26:0]), .s_i(len_k_i[31:27]),
            .d_i((sel_q ? sgy_q : sgx_q) ^ {IW{neg_q}}), .d_inc_i(neg_q),
            .busy_o(div_busy), .done_o(div_done), .q_o(div_q));
        // Nothing is presented while the division runs (it starts only when the output
        // is free), so the move is presented in the clock its division is done.
        assign len_have  = div_done;
        assign len_start = pend_q && !div_busy && !div_done && out_free && len_go_i;
        always @(posedge clk) begin
            if (pass_q) begin
                cnx_q <= !nx && cnx;
                cny_q <= !ny && cny;
                gt_q  <= gt;
                if (last_bit) begin
                    sel_q <= sel;
                    neg_q <= sel ? ny : nx;
                end
            end
        end
        assign len_o     = div_q;
    end else begin : g_no_len
        assign len_have  = 1'b1;
        assign len_o     = 32'd0;
        wire unused_len = &{1'b0, len_k_i, len_go_i};
    end
endgenerate

always @(posedge clk) begin
    if (rst || clear_i && !start_i) begin
        pass_q <= 1'b0;
        pend_q <= 1'b0;
        ov_q   <= 1'b0;
    end else if (start_i) begin
        pass_q <= 1'b1;
        pend_q <= 1'b0;
        ov_q   <= 1'b0;
    end else begin
        if (ov_q && move_ready_i) ov_q <= 1'b0;
        if (last_bit) begin
            pass_q <= 1'b0;
            pend_q <= 1'b1;
        end
        if (issue) begin
            pend_q <= 1'b0;
            ov_q   <= 1'b1;
            pass_q <= !at_end;   // the next pass applies this move
        end
    end

    if (take_wr) begin
        case (wr_sel_i)
        3'd0: begin a_q <= wr_s16[QW-1:0];  b_q <= wr_s16h[QW-1:0]; end
        3'd1: begin c_q <= wr_s16[QW-1:0];  cw_q <= wr_data_i[31]; end
        3'd2: sg_q  <= wr_s32[IW-1:0];
        3'd3: sgx_q <= wr_s32[IW-1:0];
        3'd4: sgy_q <= wr_s32[IW-1:0];
        3'd5: du_q  <= wr_s24[XW-1:0];
        3'd6: dv_q  <= wr_s24[XW-1:0];
        default: ;
        endcase
    end
    if (start_i) begin
        if (!cont_i) begin
            mx_q <= 1'b0;  my_q <= 1'b0;  qx_q <= 1'b0;  qy_q <= 1'b0;
        end
        i_q  <= {BW{1'b0}};
    end else if (pass_q) begin
        sg_q  <= {ng, sg_q[IW-1:1]};
        sgx_q <= {nx, sgx_q[IW-1:1]};
        sgy_q <= {ny, sgy_q[IW-1:1]};
        i_q   <= last_bit ? {BW{1'b0}} : i_q + 1'b1;
        if (last_bit) begin
            mx_q <= step_x;  my_q <= step_y;  qx_q <= nsx;  qy_q <= nsy;
        end
    end
    if (issue && !start_i) begin
        odx_q  <= dx;
        ody_q  <= dy;
        oend_q <= at_end;
        du_q   <= du_n;
        dv_q   <= dv_n;
    end

    // Serial state: the first bit of a pass starts from the initial carries and
    // zero delays (above); every bit moves the delays on.
    g1_q <= ng;  g2_q <= g1_q;  x1_q <= nx;  x2_q <= x1_q;  y1_q <= ny;  y2_q <= y1_q;
    a1_q <= ai;  a2_q <= a1;  b1_q <= bi;  c1_q <= ci;  c2_q <= c1;
    cg_q <= colg[3:1];
    cx_q <= colx[2:1];
    cy_q <= coly[2:1];
    nzx_q <= !first_bit && nzx_q || nx;
    nzy_q <= !first_bit && nzy_q || ny;
end

assign busy_o       = pass_q || pend_q;
assign move_valid_o = ov_q;
assign move_dx_o    = ov_q ? odx_q : 2'b00;
assign move_dy_o    = ov_q ? ody_q : 2'b00;
assign move_end_o   = ov_q && oend_q;

endmodule

`resetall
