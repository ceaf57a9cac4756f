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
// The seek (CONFIG field 10, bits [1:0]; docs/CORE.md "Seek: homing and probing"): a
// run that ends when an input trips. Mode 1 trips when the probe is active, 2 when it
// is not (contact lost), 3 when the runner hits a limit it moves toward (which is then
// no LIMIT fault). A trip while the run is on stops it in that cycle as STOP does (no
// move fires from it on, so the position counters hold the position at the trip, the
// pulse count), sets `tripped` and disarms (mode 0); what is queued stays for the
// host's FLUSH. Armed in modes 1-2 with the probe already tripping, the run is held
// off (a START does not start it) and nothing trips. Writing field 10 clears
// `tripped`. READ 0x27 [18:17] the mode, [19] tripped.
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
    // The run is on (cp_run); the runner hits an active limit (cp_run's lim_hit).
    input  wire          running_i,
    input  wire          lim_hit_i,
    // Active, filtered.
    output wire [N-1:0]  lim_min_o,
    output wire [N-1:0]  lim_max_o,
    output wire          probe_o,
    // The seek: the run stops now (modes 1-2: armed and the probe trips); a limit hit
    // is a trip, not LIMIT (mode 3); {tripped, mode} for READ 0x27.
    output wire          seek_stop_o,
    output wire          seek_lim_o,
    output wire [2:0]    seek_o
);

localparam integer NI = 2 * N + 1;   // inputs: min[N], max[N], probe

reg [15:0]   filter_q;               // the sample period P
reg [15:0]   cnt_q, cnt_d;           // clocks to the next sample tick
reg [NI-1:0] s1_q, s2_q, lvl_q;      // the last two samples, the filtered level
reg [N-1:0]  min_hi_q, max_hi_q, min_en_q, max_en_q;
reg          probe_hi_q;
reg [1:0]    seek_q;                 // the seek's mode (0: off)
reg          tripped_q;

wire [NI-1:0] pins = {probe_i, lim_max_i, lim_min_i};
wire          tick = cnt_q == 16'd0;
wire          cfg_filter = cfg_write_i && cfg_word_i[23:20] == 4'd6;
wire          probe_on = ~(lvl_q[2*N] ^ probe_hi_q);
// Modes 1 and 2: the probe's level trips; mode 3: a limit hit.
wire          probe_trips = seek_q[1] ? (!seek_q[0] && !probe_on) : (seek_q[0] && probe_on);
wire          trip = (running_i && probe_trips) || (seek_q == 2'd3 && lim_hit_i);

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
        seek_q     <= 2'd0;
        tripped_q  <= 1'b0;
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
        if (trip) begin
            seek_q    <= 2'd0;
            tripped_q <= 1'b1;
        end
        if (cfg_write_i && cfg_word_i[23:20] == 4'd10) begin
            seek_q    <= cfg_word_i[1:0];
            tripped_q <= 1'b0;
        end
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
assign probe_o   = probe_on;
assign seek_stop_o = probe_trips;
assign seek_lim_o  = seek_q == 2'd3;
assign seek_o      = {tripped_q, seek_q};

`ifdef FORMAL
// ---------------------------------------------------------------- formal properties
// The seek's rules of docs/CORE.md "Seek: homing and probing", proved (bounded and by
// k-induction) with yosys + yosys-smtbmc (formal/proofs.tsv, row "inputs").
reg f_past_valid = 1'b0;
always @(posedge clk) f_past_valid <= 1'b1;
// ---- assumptions: what cp_core guarantees
always @* if (!f_past_valid) assume (rst);
// cp_cmd refuses CONFIG while the run is on; a limit hit is the runner's, while it runs.
always @* assume (!(cfg_write_i && running_i));
always @* assume (!lim_hit_i || running_i);
wire f_cfg10 = cfg_write_i && cfg_word_i[23:20] == 4'd10;
always @(posedge clk) begin
    if (f_past_valid && !$past(rst)) begin
        // A trip disarms the seek and latches `tripped`.
        if ($past(trip)) begin
            assert (seek_q == 2'd0);
            assert (tripped_q);
        end
        // `tripped` rises only at a trip, falls only at a field-10 write.
        if (tripped_q && !$past(tripped_q)) assert ($past(trip));
        if (!tripped_q && $past(tripped_q)) assert ($past(f_cfg10));
        // The mode changes only by a trip or a field-10 write.
        if (seek_q != $past(seek_q)) assert ($past(trip) || $past(f_cfg10));
        // Armed for the probe and tripping while the run was on: it trips.
        if ($past(running_i) && $past(seek_stop_o)) assert (tripped_q && seek_q == 2'd0);
    end
    if (f_past_valid && $past(rst)) assert (seek_q == 2'd0 && !tripped_q);
end
always @* begin
    // The runner is stopped only by an armed probe mode, and a limit hit is a trip
    // only in mode 3.
    if (seek_stop_o) assert (seek_q == 2'd1 || seek_q == 2'd2);
    assert (seek_lim_o == (seek_q == 2'd3));
end
`endif

endmodule

`resetall
