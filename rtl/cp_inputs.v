// SPDX-License-Identifier: MIT
// cp_inputs — the machine's inputs: each axis's limit switches (min and max) and
// the probe, filtered and made active by their configured polarity.
//
// The inputs come in synchronized (cp_card's two flip-flops). A shared sample tick
// comes every max(P, 1) clocks, P the filter of CONFIG field 6 (0 after reset: every
// clock); an input's filtered level takes a new value when three samples in a row
// agree on it (the sample now and the two before), so a change shorter than two
// sample periods never passes and one that stays passes after 2..3 periods. CONFIG
// field 7 (per axis): bit 0 min active high, bit 1 max active high, bit 2 min
// enabled, bit 3 max enabled (after reset: active high, disabled); field 8: bit 0 the
// probe active high (after reset: 1). A limit is active when enabled and at its
// active level; the probe when at its active level.
//
// Part of cp_core (docs/CORE.md "Inputs"); model twin model/cp_inputs.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_inputs #(
    parameter integer N = 4
) (
    input  wire          clk,
    input  wire          rst,
    // Synchronized pins.
    input  wire [N-1:0]  lim_min_i,
    input  wire [N-1:0]  lim_max_i,
    input  wire          probe_i,
    // CONFIG (cp_cmd): written now, the word.
    input  wire          cfg_write_i,
    input  wire [31:0]   cfg_word_i,
    // Active, filtered.
    output wire [N-1:0]  lim_min_o,
    output wire [N-1:0]  lim_max_o,
    output wire          probe_o
);

localparam integer NI = 2 * N + 1;   // inputs: min[N], max[N], probe

reg [15:0]   filter_q;               // the sample period P
reg [15:0]   cnt_q, cnt_d;           // clocks to the next sample tick
reg [NI-1:0] s1_q, s2_q, lvl_q;      // the last two samples, the filtered level
reg [N-1:0]  min_hi_q, max_hi_q, min_en_q, max_en_q;
reg          probe_hi_q;

wire [NI-1:0] pins = {probe_i, lim_max_i, lim_min_i};
wire          tick = cnt_q == 16'd0;
wire          cfg_filter = cfg_write_i && cfg_word_i[23:20] == 4'd6;

always @* begin
    cnt_d = cnt_q - 1'b1;
    if (tick) cnt_d = (filter_q == 16'd0) ? 16'd0 : filter_q - 1'b1;
    if (cfg_filter) cnt_d = 16'd0;
end

integer a;
always @(posedge clk) begin
    if (rst) begin
        filter_q   <= 16'd0;
        cnt_q      <= 16'd0;
        s1_q       <= {NI{1'b0}};
        s2_q       <= {NI{1'b0}};
        lvl_q      <= {NI{1'b0}};
        min_hi_q   <= {N{1'b1}};
        max_hi_q   <= {N{1'b1}};
        min_en_q   <= {N{1'b0}};
        max_en_q   <= {N{1'b0}};
        probe_hi_q <= 1'b1;
    end else begin
        cnt_q <= cnt_d;
        if (tick) begin
            s1_q  <= pins;
            s2_q  <= s1_q;
            // Three samples that agree: the level takes them.
            lvl_q <= (pins & s1_q & s2_q) | (lvl_q & (pins | s1_q | s2_q));
        end
        if (cfg_filter) filter_q <= cfg_word_i[15:0];
        if (cfg_write_i && cfg_word_i[23:20] == 4'd8) probe_hi_q <= cfg_word_i[0];
        if (cfg_write_i && cfg_word_i[23:20] == 4'd7) begin
            for (a = 0; a < N; a = a + 1) begin
                if (cfg_word_i[27:24] == a[3:0]) begin
                    min_hi_q[a] <= cfg_word_i[0];
                    max_hi_q[a] <= cfg_word_i[1];
                    min_en_q[a] <= cfg_word_i[2];
                    max_en_q[a] <= cfg_word_i[3];
                end
            end
        end
    end
end

wire unused = &{1'b0, cfg_word_i[31:28], cfg_word_i[19:16]};
assign lim_min_o = min_en_q & ~(lvl_q[N-1:0] ^ min_hi_q);
assign lim_max_o = max_en_q & ~(lvl_q[2*N-1:N] ^ max_hi_q);
assign probe_o   = ~(lvl_q[2*N] ^ probe_hi_q);

endmodule

`resetall
