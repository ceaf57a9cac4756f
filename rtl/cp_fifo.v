// SPDX-License-Identifier: MIT
// cp_fifo — first-word-fall-through FIFO on a block RAM, with commit/rollback.
//
// Writes are invisible to the reader until committed: a producer that validates
// a record word by word writes it, then commits it whole or rolls it back whole
// (the card's "a bad segment is rejected whole" rule). A writer that has nothing
// to validate ties commit_i high.
//
// Read side: out_valid_o/out_ready_i/out_data_o follow the valid/ready contract
// (docs/CORE.md). Storage reads are synchronous; the output is the RAM's read
// register, held while the head waits, so the FIFO maps to one block RAM.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_fifo #(
    // Word width.
    parameter integer DW = 64,
    // Address width: the FIFO holds up to 2^AW - 1 words in storage plus the head.
    parameter integer AW = 6
) (
    input  wire          clk,
    input  wire          rst,
    // Drop every word, committed or not.
    input  wire          clear_i,

    // Write side. wr_i writes wr_data_i when there is room (full_o low).
    input  wire          wr_i,
    input  wire [DW-1:0] wr_data_i,
    // commit_i: every word written so far (this cycle's included) becomes visible.
    input  wire          commit_i,
    // rollback_i: every uncommitted word is dropped (this cycle's write included).
    input  wire          rollback_i,
    output wire          full_o,
    // Words written and not yet read, committed or not (storage plus head).
    output wire [AW:0]   used_o,
    // Committed words not yet read (storage plus head).
    output wire [AW:0]   level_o,

    // Read side.
    output wire          out_valid_o,
    input  wire          out_ready_i,
    output wire [DW-1:0] out_data_o
`ifdef FORMAL
    ,
    // Formal only: the write side as this FIFO sees it, for a parent's properties
    // (docs/FORMAL.md: cp_spi checks what reaches the buffer, not what it meant to send).
    output wire          f_wr_o,
    output wire [DW-1:0] f_wr_data_o,
    output wire          f_commit_o,
    output wire          f_rollback_o
`endif
);

generate
    if (DW < 1) begin : g_check_dw
        cp_fifo_parameter_DW_must_be_positive u_bad ();
    end
    if (AW < 1 || AW > 16) begin : g_check_aw
        cp_fifo_parameter_AW_must_be_1_to_16 u_bad ();
    end
endgenerate

// A fetch never reads the word written in the same clock: the addresses meet only
// when wptr - rptr is 0 (then cptr = rptr: nothing to fetch) or 2^AW (full: no
// write). So no_rw_check: yosys needs no bypass registers to give a collision's
// old data, and ram_style puts even a shallow queue (the run queue: 2 words of
// 78 bits in a phase-timer build) into block RAM rather than flip-flops.
(* no_rw_check, ram_style = "block" *)
reg [DW-1:0] mem [0:(1<<AW)-1];
reg [DW-1:0] rdata_q;

// Pointers carry one extra bit so that full and empty differ.
reg [AW:0] wptr_q, wptr_d;   // next write
reg [AW:0] cptr_q, cptr_d;   // end of the committed words
reg [AW:0] rptr_q, rptr_d;   // next word to fetch into the head
reg        out_valid_q, out_valid_d;

wire [AW:0] stored = wptr_q - rptr_q;
assign full_o = stored[AW];          // 2^AW words in storage
wire wr_en = wr_i && !full_o && !clear_i;
wire pop   = out_valid_q && out_ready_i;
wire fetch = !clear_i && (cptr_q != rptr_q) && (!out_valid_q || pop);

always @* begin
    wptr_d      = wptr_q;
    cptr_d      = cptr_q;
    rptr_d      = rptr_q;
    out_valid_d = out_valid_q;
    if (pop) out_valid_d = 1'b0;
    if (fetch) begin
        rptr_d      = rptr_q + 1'b1;
        out_valid_d = 1'b1;
    end
    if (wr_en) wptr_d = wptr_q + 1'b1;
    if (rollback_i)    wptr_d = cptr_q;
    else if (commit_i) cptr_d = wptr_d;
    if (clear_i) begin
        wptr_d      = {(AW+1){1'b0}};
        cptr_d      = {(AW+1){1'b0}};
        rptr_d      = {(AW+1){1'b0}};
        out_valid_d = 1'b0;
    end
end

always @(posedge clk) begin
    if (wr_en) mem[wptr_q[AW-1:0]] <= wr_data_i;
    if (fetch) rdata_q <= mem[rptr_q[AW-1:0]];
    if (rst) begin
        wptr_q      <= {(AW+1){1'b0}};
        cptr_q      <= {(AW+1){1'b0}};
        rptr_q      <= {(AW+1){1'b0}};
        out_valid_q <= 1'b0;
    end else begin
        wptr_q      <= wptr_d;
        cptr_q      <= cptr_d;
        rptr_q      <= rptr_d;
        out_valid_q <= out_valid_d;
    end
end

assign out_valid_o = out_valid_q;
assign out_data_o  = out_valid_q ? rdata_q : {DW{1'b0}};
assign used_o      = stored + {{AW{1'b0}}, out_valid_q};
assign level_o     = (cptr_q - rptr_q) + {{AW{1'b0}}, out_valid_q};

`ifdef FORMAL
// ---------------------------------------------------------------- formal
// Properties for yosys-smtbmc (docs/FORMAL.md, scripts/formal, row `fifo` of
// formal/proofs.tsv). An abstract shadow, written from the port contract above
// and docs/CORE.md "cp_fifo contract", not from the pointers: counts of the
// committed and uncommitted words, and one tracked word picked at an arbitrary
// write. The environment is free: any input on any cycle, reset in the first.
reg f_past_valid = 1'b0;
always @(posedge clk) f_past_valid <= 1'b1;
always @* if (!f_past_valid) assume(rst);

assign f_wr_o       = wr_i;
assign f_wr_data_o  = wr_data_i;
assign f_commit_o   = commit_i;
assign f_rollback_o = rollback_i;

localparam [AW+1:0] F_DEPTH = 1 << AW;       // words in storage when full
wire f_wr  = wr_i && !full_o && !clear_i;    // a write the port contract accepts
wire f_pop = out_valid_o && out_ready_i;     // a transfer on the read side

// Shadow counts: committed unread words (head included) and uncommitted words.
reg [AW+1:0] f_ncom, f_nunc;
reg [AW+1:0] f_ncom_d, f_nunc_d;
always @* begin
    f_nunc_d = f_nunc + {{(AW+1){1'b0}}, f_wr};
    f_ncom_d = f_ncom - {{(AW+1){1'b0}}, f_pop};
    if (rollback_i) begin
        f_nunc_d = {(AW+2){1'b0}};
    end else if (commit_i) begin
        f_ncom_d = f_ncom_d + f_nunc_d;
        f_nunc_d = {(AW+2){1'b0}};
    end
end
always @(posedge clk) begin
    if (rst || clear_i) begin
        f_ncom <= {(AW+2){1'b0}};
        f_nunc <= {(AW+2){1'b0}};
    end else begin
        f_ncom <= f_ncom_d;
        f_nunc <= f_nunc_d;
    end
end

// The tracked word: any accepted write may be picked (f_pick, free each cycle)
// while none is tracked. f_ahead counts the words that must leave the head before
// it does: committed ones, then the uncommitted ones written before it.
(* anyseq *) wire f_pick;
localparam [1:0] F_NONE = 2'd0, F_UNCOMMITTED = 2'd1, F_COMMITTED = 2'd2;
reg [1:0]    f_trk = F_NONE;
reg [DW-1:0] f_data;
reg [AW+1:0] f_ahead;
always @(posedge clk) begin
    if (f_trk == F_NONE && f_wr && f_pick) begin
        f_trk   <= F_UNCOMMITTED;
        f_data  <= wr_data_i;
        f_ahead <= f_ncom + f_nunc - {{(AW+1){1'b0}}, f_pop};
    end else if (f_trk != F_NONE && f_pop) begin
        f_ahead <= f_ahead - 1'b1;
        if (f_ahead == {(AW+2){1'b0}}) f_trk <= F_NONE;   // it left the head
    end
    if (rollback_i) begin
        if (f_trk != F_COMMITTED) f_trk <= F_NONE;        // rolled back
    end else if (commit_i) begin
        if (f_trk == F_UNCOMMITTED || (f_trk == F_NONE && f_wr && f_pick))
            f_trk <= F_COMMITTED;
    end
    if (rst || clear_i) f_trk <= F_NONE;
end

// Where the shadow says the tracked word is: in storage, or the head.
wire [AW:0]   f_ahead_s = f_ahead[AW:0] - {{AW{1'b0}}, out_valid_q};   // storage words before it
wire [AW-1:0] f_slot    = rptr_q[AW-1:0] + f_ahead_s[AW-1:0];
wire [AW:0]   f_ncom_s  = f_ncom[AW:0] - {{AW{1'b0}}, out_valid_q};    // committed, in storage

always @* if (f_past_valid) begin
    // Level, used, full and empty are the shadow's counts.
    assert(level_o == f_ncom[AW:0]);
    assert(used_o == f_ncom[AW:0] + f_nunc[AW:0]);
    assert(f_ncom <= F_DEPTH + 1'b1 && f_nunc <= F_DEPTH && f_ncom + f_nunc <= F_DEPTH + 1'b1);
    assert(full_o == (f_ncom + f_nunc - {{(AW+1){1'b0}}, out_valid_o} == F_DEPTH));
    // No output without a committed word; a read only from committed storage.
    if (out_valid_o) assert(f_ncom != {(AW+2){1'b0}});
    if (fetch) assert(f_ncom > {{(AW+1){1'b0}}, out_valid_q});
    if (!out_valid_o) assert(out_data_o == {DW{1'b0}});

    // The tracked word: behind every committed word while uncommitted, among the
    // committed ones once committed, and it is the head's data when it gets there.
    if (f_trk != F_NONE) assert(f_ahead < f_ncom + f_nunc);
    if (f_trk == F_UNCOMMITTED) assert(f_ahead >= f_ncom);
    if (f_trk == F_COMMITTED) begin
        assert(f_ahead < f_ncom);
        if (f_ahead == {(AW+2){1'b0}} && out_valid_o) assert(out_data_o == f_data);
    end
    assert(f_trk != 2'd3);

    // Auxiliary invariants (make the above inductive): the pointers as the
    // shadow's counts, and the tracked word's storage slot holding its data.
    assert(cptr_q - rptr_q == f_ncom_s);
    assert(wptr_q - cptr_q == f_nunc[AW:0]);
    if (f_trk != F_NONE && !(f_trk == F_COMMITTED && f_ahead == {(AW+2){1'b0}} && out_valid_q))
        assert(mem[f_slot] == f_data);
end

always @(posedge clk) if (f_past_valid && !$past(rst)) begin
    // Valid/ready: while valid && !ready the head holds still.
    if ($past(out_valid_o && !out_ready_i && !clear_i)) begin
        assert(out_valid_o);
        assert(out_data_o == $past(out_data_o));
    end
    // Fall-through: a committed word left behind the head is there next cycle.
    if (!$past(clear_i) && $past(f_ncom) != {{(AW+1){1'b0}}, $past(f_pop)})
        assert(out_valid_o);
end
`endif

endmodule

`resetall
