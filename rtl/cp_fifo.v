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
);

generate
    if (DW < 1) begin : g_check_dw
        cp_fifo_parameter_DW_must_be_positive u_bad ();
    end
    if (AW < 1 || AW > 16) begin : g_check_aw
        cp_fifo_parameter_AW_must_be_1_to_16 u_bad ();
    end
endgenerate

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

endmodule

`resetall
