// SPDX-License-Identifier: MIT
// cp_cmd — the motion core's command parser and chunk check.
//
// Takes the command words (docs/CORE.md "Command port"), one a clock, and
// validates every segment whole: its header and v_i go into the segment queue
// and its chunks into the chunk queue uncommitted; after its last chunk both are
// committed together, or both rolled back when any check failed. Each chunk's
// last delay is checked with a multiplier (bit-serial, or the hard one with
// MUL_DSP). CONFIG, CONTROL and READ become one-cycle requests to cp_status and
// cp_run; a refusal is a fault request with its code (cp_status decides).
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_cmd.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_cmd #(
    parameter integer N = 4,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer TW = 16,
    parameter integer MUL_DSP = 0
) (
    input  wire          clk,
    input  wire          rst,

    input  wire          cmd_valid_i,
    output wire          cmd_ready_o,
    input  wire [31:0]   cmd_data_i,
    output wire          rsp_valid_o,
    input  wire          rsp_ready_i,
    output wire [31:0]   rsp_data_o,
    output wire [7:0]    rsp_addr_o,
    // The register cmd_data_i[7:0] names, now (cp_status's first read port).
    input  wire [31:0]   read_data_i,

    input  wire          fault_i,          // a fault is latched
    input  wire          running_i,
    input  wire          pulse_busy_i,     // some STEP pin is at its active level

    // Segment queue (words of the segment being read) and chunk queue.
    input  wire          seg_full_i,
    output reg           seg_wr_o,
    output reg  [28+N:0] seg_wdata_o,
    output reg           seg_commit_o,
    output reg           seg_rollback_o,
    input  wire          ch_full_i,
    output reg           ch_wr_o,
    output wire [80:0]   ch_wdata_o,
    output reg           ch_commit_o,
    output reg           ch_rollback_o,

    // One-cycle requests of the word taken now.
    output reg           start_o,
    output reg           abort_o,
    output reg           clear_o,
    output reg           drivers_on_o,
    output reg           drivers_off_o,
    output reg           cfg_write_o,      // CONFIG accepted: cmd_data_i is the word
    output reg           fault_o,          // a refusal, with its code
    output reg  [7:0]    fault_code_o
);

localparam integer SWW = 29 + N;
localparam [3:0] OP_SEGMENT = 4'h1;
localparam [3:0] OP_CONFIG  = 4'h2;
localparam [3:0] OP_CONTROL = 4'h3;
localparam [3:0] OP_READ    = 4'h4;

localparam [7:0] E_NONE           = 8'd0;
localparam [7:0] E_SEG_U          = 8'd1;
localparam [7:0] E_SEG_V_GT_U     = 8'd2;
localparam [7:0] E_SEG_K          = 8'd3;
localparam [7:0] E_SEG_CHUNKS     = 8'd4;
localparam [7:0] E_SEG_CHUNK_ZERO = 8'd5;
localparam [7:0] E_SEG_DELAY      = 8'd6;
localparam [7:0] E_SEG_COUNT_SUM  = 8'd7;
localparam [7:0] E_BAD_OPCODE     = 8'd12;
localparam [7:0] E_CONFIG_BUSY    = 8'd13;
localparam [7:0] E_CONFIG_VALUE   = 8'd14;
localparam [7:0] E_SEG_ADD2       = 8'd15;
// The bits of a 16-bit CONFIG value that a TW-bit timing field holds.
localparam [15:0] TMASK = (TW >= 16) ? 16'hFFFF : ((16'd1 << TW) - 16'd1);

localparam [3:0] P_CMD  = 4'd0;   // first word of a command
localparam [3:0] P_H1   = 4'd1;   // segment: dir and U
localparam [3:0] P_V    = 4'd2;   // segment: v_i
localparam [3:0] P_C0   = 4'd3;   // chunk: interval
localparam [3:0] P_C1   = 4'd4;   // chunk: add and count
localparam [3:0] P_MUL  = 4'd5;   // chunk: checking its last delay
localparam [3:0] P_RSP  = 4'd6;   // a reply waits to be taken
localparam [3:0] P_C2   = 4'd7;   // chunk: add2 (segments whose chunks carry it)
localparam [3:0] P_INC  = 4'd8;   // chunk: its last increment add + (count-2)*add2
// Width of the products: |(count-1)*(add + last increment)| < 2^47.
localparam integer MW = 49;

// ---------------------------------------------------------------- state
reg [3:0]    p_state_q, p_state_d;       // reset
reg          discard_q, discard_d;       // the segment being read is dropped (reset)
reg          rsp_valid_q, rsp_valid_d;   // reset
reg          hdr_end_q, hdr_end_d;       // the segment being read: end flag, k, U
reg [3:0]    hdr_k_q, hdr_k_d;
reg [23:0]   seg_u_q, seg_u_d;
reg          seg_add2_q, seg_add2_d;     // its chunks carry add2 (three words)
reg [15:0]   nchunks_q, nchunks_d;       // chunks still to read
reg [2:0]    v_idx_q, v_idx_d;
reg [31:0]   interval_q, interval_d;
reg [15:0]   count_q, count_d;
reg [15:0]   add_q, add_d;
reg [15:0]   add2_q, add2_d;
reg [33:0]   sum_q, sum_d;               // chunk counts so far
reg [MW-1:0] prod_q, prod_d;             // a product, built bit by bit
reg [15:0]   mul_a_q, mul_a_d;           // multiplier bits left
reg [MW-1:0] mul_b_q, mul_b_d;           // multiplicand (shifted when bit-serial)
reg [15:0]   mul_a0_q, mul_a0_d;         // the multiplier whole (MUL_DSP)
reg [31:0]   rsp_data_q, rsp_data_d;
reg [7:0]    rsp_addr_q, rsp_addr_d;

// ---------------------------------------------------------------- word fields
wire [3:0]  op        = cmd_data_i[31:28];
wire        take      = cmd_valid_i && cmd_ready_o;
wire [15:0] c1_count  = cmd_data_i[15:0];
wire [15:0] c1_add    = cmd_data_i[31:16];
wire [15:0] c2_add2   = cmd_data_i[15:0];
wire [33:0] seg_moves = {10'd0, seg_u_q} << hdr_k_q;
wire        keep      = !discard_q && !fault_i;   // the segment being read is still good
// Pass 2 of a chunk's check: prod = (count-1)*(add + last increment), even, so the
// last delay is interval + prod/2.
wire [MW:0]   last_delay = {{(MW-31){1'b0}}, interval_q} + {{2{prod_q[MW-1]}}, prod_q[MW-1:1]};
wire [MW-1:0] add_sx   = {{(MW-16){add_q[15]}}, add_q};
// Pass 1: prod = (count-2)*add2; the last increment add + prod.
wire [MW-1:0] last_inc = add_sx + prod_q;
// MUL_DSP: the whole product at once. Every multiplicand fits 34 signed bits
// (2·add, add2, add + last increment: |.| < 2^32 + 2^16), the multiplier 16
// unsigned; the product is taken mod 2^MW like the bit-serial one.
wire signed [16:0] mul_sa   = {1'b0, mul_a0_q};
wire signed [33:0] mul_sb   = mul_b_q[33:0];
wire signed [50:0] mul_full = mul_sa * mul_sb;
wire [MW-1:0]      mul_prod = mul_full[MW-1:0];
wire unused_mul = &{1'b0, mul_full[50:MW]};
wire          inc_flip = (!add_q[15] && add_q != 16'd0 && last_inc[MW-1]) ||
                         (add_q[15] && !last_inc[MW-1] && last_inc != {MW{1'b0}});

// The chunk queue word: last chunk of its segment, add2, count, add, interval.
assign ch_wdata_o = {nchunks_q == 16'd1, add2_d, count_d, add_d, interval_q};

// ---------------------------------------------------------------- next state
reg refuse;          // a refusal of the parser's own this cycle
reg [7:0] refuse_code;

always @* begin
    p_state_d   = p_state_q;
    discard_d   = discard_q;
    rsp_valid_d = rsp_valid_q && !rsp_ready_i;
    rsp_data_d  = rsp_data_q;
    rsp_addr_d  = rsp_addr_q;
    hdr_end_d = hdr_end_q;  hdr_k_d = hdr_k_q;  seg_u_d = seg_u_q;
    nchunks_d = nchunks_q;  v_idx_d = v_idx_q;
    interval_d = interval_q;  count_d = count_q;  add_d = add_q;  add2_d = add2_q;  sum_d = sum_q;
    seg_add2_d = seg_add2_q;
    prod_d = prod_q;  mul_a_d = mul_a_q;  mul_b_d = mul_b_q;  mul_a0_d = mul_a0_q;

    seg_wr_o = 1'b0;  seg_wdata_o = {SWW{1'b0}};  seg_commit_o = 1'b0;  seg_rollback_o = 1'b0;
    ch_wr_o = 1'b0;  ch_commit_o = 1'b0;  ch_rollback_o = 1'b0;
    start_o = 1'b0;  abort_o = 1'b0;  clear_o = 1'b0;  drivers_on_o = 1'b0;  drivers_off_o = 1'b0;
    cfg_write_o = 1'b0;
    refuse = 1'b0;  refuse_code = E_NONE;

    case (p_state_q)
    P_CMD: if (take) begin
        case (op)
        OP_SEGMENT: begin
            hdr_end_d = cmd_data_i[27];
            hdr_k_d   = cmd_data_i[26:23];
            nchunks_d = cmd_data_i[15:0];
            seg_add2_d = cmd_data_i[22];
            sum_d     = 34'd0;
            discard_d = fault_i;
            if (!fault_i) begin
                if ({28'd0, cmd_data_i[26:23]} > KMAX) begin
                    refuse = 1'b1;  refuse_code = E_SEG_K;  discard_d = 1'b1;
                end else if (cmd_data_i[15:0] == 16'd0 || {16'd0, cmd_data_i[15:0]} > (32'd1 << CAW)) begin
                    refuse = 1'b1;  refuse_code = E_SEG_CHUNKS;  discard_d = 1'b1;
                end
            end
            p_state_d = P_H1;
        end
        OP_CONFIG: begin
            // Refused while running, and while a STEP pulse is still high (after ABORT,
            // E-stop or the run's last move): a polarity or timing write never cuts it.
            if (running_i || pulse_busy_i) begin
                refuse = 1'b1;  refuse_code = E_CONFIG_BUSY;
            end else if ({28'd0, cmd_data_i[27:24]} >= N || cmd_data_i[23:20] > 4'd4 ||
                         (cmd_data_i[23:20] <= 4'd1 && cmd_data_i[15:0] == 16'd0) ||
                         (cmd_data_i[23:20] <= 4'd3 && (cmd_data_i[15:0] & ~TMASK) != 16'd0)) begin
                refuse = 1'b1;  refuse_code = E_CONFIG_VALUE;
            end else begin
                cfg_write_o = 1'b1;
            end
        end
        OP_CONTROL: begin
            start_o       = cmd_data_i[0];
            abort_o       = cmd_data_i[1];
            clear_o       = cmd_data_i[2];
            drivers_on_o  = cmd_data_i[3];
            drivers_off_o = cmd_data_i[4];
        end
        OP_READ: begin
            rsp_valid_d = 1'b1;
            rsp_data_d  = read_data_i;
            rsp_addr_d  = cmd_data_i[7:0];
            p_state_d   = P_RSP;
        end
        default: begin
            refuse = 1'b1;  refuse_code = E_BAD_OPCODE;
        end
        endcase
    end

    P_H1: if (take) begin
        seg_u_d     = cmd_data_i[23:0];
        seg_wr_o    = keep;
        seg_wdata_o = {hdr_end_q, hdr_k_q, cmd_data_i[24 +: N], cmd_data_i[23:0]};
        if (keep && (cmd_data_i[23:0] == 24'd0 || {8'd0, cmd_data_i[23:0]} > UMAX)) begin
            refuse = 1'b1;  refuse_code = E_SEG_U;  discard_d = 1'b1;
        end
        v_idx_d   = 3'd0;
        p_state_d = P_V;
    end

    P_V: if (take) begin
        seg_wr_o    = keep;
        seg_wdata_o = {{(SWW-24){1'b0}}, cmd_data_i[23:0]};
        if (keep && cmd_data_i[23:0] > seg_u_q) begin
            refuse = 1'b1;  refuse_code = E_SEG_V_GT_U;  discard_d = 1'b1;
        end
        v_idx_d = v_idx_q + 1'b1;
        // A segment announced with no chunk was refused at its header; it ends here.
        if ({29'd0, v_idx_q} == N - 1) p_state_d = (nchunks_q == 16'd0) ? P_CMD : P_C0;
    end

    P_C0: if (take) begin
        interval_d = cmd_data_i;
        p_state_d  = P_C1;
    end

    P_C1: if (take) begin
        count_d = c1_count;
        add_d   = c1_add;
        sum_d   = sum_q + {18'd0, c1_count};
        if (keep && (interval_q == 32'd0 || c1_count == 16'd0)) begin
            refuse = 1'b1;  refuse_code = E_SEG_CHUNK_ZERO;  discard_d = 1'b1;
        end
        prod_d  = {MW{1'b0}};
        if (seg_add2_q) begin
            p_state_d = P_C2;
        end else begin
            // The chunk's last word: add2 = 0, straight to pass 2 with 2*add.
            add2_d  = 16'd0;
            ch_wr_o = keep;
            mul_a_d = c1_count - 1'b1;
            mul_b_d = {{(MW-17){c1_add[15]}}, c1_add, 1'b0};
            p_state_d = P_MUL;
        end
    end

    P_C2: if (take) begin
        add2_d  = c2_add2;
        ch_wr_o = keep;
        prod_d  = {MW{1'b0}};
        if (c2_add2 == 16'd0) begin
            mul_a_d = count_q - 1'b1;
            mul_b_d = {add_sx[MW-2:0], 1'b0};
            p_state_d = P_MUL;
        end else begin
            // Pass 1: (count-2)*add2, no multiplier bit when count < 2.
            mul_a_d = (count_q < 16'd2) ? 16'd0 : count_q - 16'd2;
            mul_b_d = {{(MW-16){c2_add2[15]}}, c2_add2};
            p_state_d = P_INC;
        end
    end

    P_INC: begin
        // (count-2) * add2 (the multiplier below); then the sign rule and pass 2.
        if (mul_a_q == 16'd0) begin
            if (keep && inc_flip) begin
                refuse = 1'b1;  refuse_code = E_SEG_ADD2;  discard_d = 1'b1;
            end
            prod_d  = {MW{1'b0}};
            mul_a_d = count_q - 1'b1;
            mul_b_d = add_sx + last_inc;
            p_state_d = P_MUL;
        end
    end

    P_MUL: begin
        // (count-1) * (add + last increment) (the multiplier below); then the last delay.
        if (mul_a_q == 16'd0) begin
            if (keep && (last_delay[MW] || last_delay[MW-1:32] != {(MW-32){1'b0}} ||
                         last_delay == {(MW+1){1'b0}})) begin
                refuse = 1'b1;  refuse_code = E_SEG_DELAY;  discard_d = 1'b1;
            end
            nchunks_d = nchunks_q - 1'b1;
            if (nchunks_q != 16'd1) begin
                p_state_d = P_C0;
            end else if (!keep || refuse) begin
                ch_rollback_o  = 1'b1;
                seg_rollback_o = 1'b1;
                p_state_d      = P_CMD;
            end else if (sum_q != seg_moves) begin
                refuse = 1'b1;  refuse_code = E_SEG_COUNT_SUM;
                ch_rollback_o  = 1'b1;
                seg_rollback_o = 1'b1;
                p_state_d      = P_CMD;
            end else begin
                // The whole segment passed: its words and its chunks appear together.
                seg_commit_o = 1'b1;
                ch_commit_o  = 1'b1;
                p_state_d    = P_CMD;
            end
        end
    end

    P_RSP: if (!rsp_valid_q || rsp_ready_i) p_state_d = P_CMD;

    default: p_state_d = P_CMD;
    endcase

    // The chunk check's multiplier: one bit of mul_a a cycle while any is left.
    // Bit-serial, the product grows by the shifted multiplicand; MUL_DSP, it is
    // the whole product of the operands, which hold still (a multiplier of 0
    // takes no cycle and leaves the product 0, as bit-serial).
    if ((p_state_q == P_INC || p_state_q == P_MUL) && mul_a_q != 16'd0) begin
        if (MUL_DSP != 0) begin
            prod_d = mul_prod;
        end else begin
            if (mul_a_q[0]) prod_d = prod_q + mul_b_q;
            mul_b_d = mul_b_q << 1;
        end
        mul_a_d = mul_a_q >> 1;
    end else begin
        mul_a0_d = mul_a_d;
    end

    fault_o      = refuse;
    fault_code_o = refuse_code;
end

// ---------------------------------------------------------------- registers
always @(posedge clk) begin
    if (rst) begin
        p_state_q   <= P_CMD;
        discard_q   <= 1'b0;
        rsp_valid_q <= 1'b0;
    end else begin
        p_state_q   <= p_state_d;
        discard_q   <= discard_d;
        rsp_valid_q <= rsp_valid_d;
    end
    hdr_end_q <= hdr_end_d;  hdr_k_q <= hdr_k_d;  seg_u_q <= seg_u_d;
    nchunks_q <= nchunks_d;  v_idx_q <= v_idx_d;
    interval_q <= interval_d;  count_q <= count_d;  add_q <= add_d;  add2_q <= add2_d;
    sum_q <= sum_d;  seg_add2_q <= seg_add2_d;
    prod_q <= prod_d;  mul_a_q <= mul_a_d;  mul_b_q <= mul_b_d;  mul_a0_q <= mul_a0_d;
    rsp_data_q <= rsp_data_d;  rsp_addr_q <= rsp_addr_d;
end

// ---------------------------------------------------------------- outputs
assign cmd_ready_o = (p_state_q == P_CMD) ||
                     ((p_state_q == P_H1 || p_state_q == P_V) && (!keep || !seg_full_i)) ||
                     (p_state_q == P_C0) ||
                     (p_state_q == P_C1 && (seg_add2_q || !keep || !ch_full_i)) ||
                     (p_state_q == P_C2 && (!keep || !ch_full_i));
assign rsp_valid_o = rsp_valid_q;
assign rsp_data_o  = rsp_valid_q ? rsp_data_q : 32'd0;
assign rsp_addr_o  = rsp_valid_q ? rsp_addr_q : 8'd0;

endmodule

`resetall
