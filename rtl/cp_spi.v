// SPDX-License-Identifier: MIT
// cp_spi — the card's SPI front end: frames in on MOSI, replies out on MISO, and
// the command buffer between the frames and the motion core's command port.
//
// SPI mode 0, MSB first, one CS-low period per frame (docs/PROTOCOL.md is the
// contract). SCK, CS and MOSI are sampled in the clk domain through two-flop
// synchronizers, so SCK may be at most clk/8. One 32-bit register carries both
// directions: MOSI bits enter at the bottom, MISO leaves from the top, and at
// every 32-bit boundary the received word is taken off it and the next reply word
// is loaded onto it (frame words and reply words share their boundaries: the
// frame header is one word).
//
// A COMMANDS frame's words go into the command buffer (cp_fifo) uncommitted as
// they arrive; at CS rise the frame is committed whole or rolled back whole
// (result codes 0..6). The executor feeds committed words to the core's command
// port and keeps its READ replies.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_spi #(
    // Number of axes: the reply carries N positions; a SEGMENT has 2 + N + ... words.
    parameter integer N = 4,
    // Command buffer address width: it holds 2^CBUF_AW words.
    parameter integer CBUF_AW = 9,
    // 1: CONIC commands (opcode 5, docs/CORE.md "CONIC") are framed as whole commands
    // of 2 + N + 7 + chunk words (2 + N + 2 + chunk words with H0[18], a continuation); 0: opcode 5 is refused (BAD_COMMAND), as the core
    // would refuse it.
    parameter integer CONIC = 0,
    // 1: the core's moves are timed by the phase timer (docs/CORE.md "Phase-timer
    // builds"): a SEGMENT or CONIC carries no chunks but its axis form's v words (every
    // axis's, or with H0[15] those of the mask H0[7:0]), a CONIC's K words and one L
    // word; a PHASE (opcode 6) is 2, 4, 6 or 8 words (H0[24] adds r, H0[27] S and H).
    // 0: opcode 6 is refused (BAD_COMMAND), as the core would refuse it.
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,

    // SPI pins (asynchronous to clk).
    input  wire          spi_sck_i,
    input  wire          spi_cs_n_i,
    input  wire          spi_mosi_i,
    output wire          spi_miso_o,
    output wire          spi_miso_oe_o,

    // The motion core's command port (docs/CORE.md).
    output wire          cmd_valid_o,
    input  wire          cmd_ready_i,
    output wire [31:0]   cmd_data_o,
    input  wire          rsp_valid_i,
    output wire          rsp_ready_o,
    input  wire [7:0]    rsp_addr_i,
    // The core's read port: its READ registers, read as each reply word goes out.
    output wire [7:0]    rd_addr_o,
    input  wire [31:0]   rd_data_i,

    // What the reply reports (estop_i already synchronized).
    input  wire          estop_i,
    input  wire          enable_i,

    // An URGENT frame (type 0x02, one word) accepted at this CS rise: its word's
    // [0] START, [1] STOP and [2] FLUSH go to the core at once, past the command
    // buffer, which FLUSH empties; [3] ACK clears a fault, an E-stop's too
    // (docs/PROTOCOL.md "Out of band").
    output reg           ctl_start_o,
    output reg           ctl_stop_o,
    output reg           ctl_flush_o,
    output reg           ctl_ack_o,
    // [4] HOLD, [5] RESUME, [6] OVERRIDE to [31:16] (Q2.14): the feed's target (cp_feed,
    // FEED builds); the value is the last URGENT word's, valid with ctl_ovr_o.
    output reg           ctl_hold_o,
    output reg           ctl_resume_o,
    output reg           ctl_ovr_o,
    output wire [15:0]   ctl_ovr_val_o,
    // A whole frame with a good CRC ended at this CS rise, whatever its type or
    // result: the host is alive (the core's watchdog kick, docs/CORE.md "Watchdog").
    output reg           frame_ok_o
);

generate
    if (N < 1 || N > 8) begin : g_check_n
        cp_spi_parameter_N_must_be_1_to_8 u_bad ();
    end
    if (CBUF_AW < 1 || CBUF_AW > 14) begin : g_check_aw
        cp_spi_parameter_CBUF_AW_must_be_1_to_14 u_bad ();
    end
    if (CONIC != 0 && CONIC != 1) begin : g_check_conic
        cp_spi_parameter_CONIC_must_be_0_or_1 u_bad ();
    end
    if (PTIMER != 0 && PTIMER != 1) begin : g_check_ptimer
        cp_spi_parameter_PTIMER_must_be_0_or_1 u_bad ();
    end
endgenerate

// ---------------------------------------------------------------- constants
localparam [7:0] MAGIC = 8'hC5;
localparam [7:0] T_POLL = 8'h00;
localparam [7:0] T_COMMANDS = 8'h01;
localparam [7:0] T_URGENT = 8'h02;

localparam [2:0] R_OK        = 3'd0;
localparam [2:0] R_TRUNCATED = 3'd1;
localparam [2:0] R_BAD_CRC   = 3'd2;
localparam [2:0] R_BAD_TYPE  = 3'd3;
localparam [2:0] R_NO_ROOM   = 3'd4;
localparam [2:0] R_BAD_CMD   = 3'd5;
localparam [2:0] R_SPLIT     = 3'd6;

// Receive phase of a frame.
localparam [1:0] PH_HDR   = 2'd0;   // type, seq, nwords
localparam [1:0] PH_WORDS = 2'd1;   // command words
localparam [1:0] PH_CRC   = 2'd2;   // the frame's CRC
localparam [1:0] PH_DONE  = 2'd3;   // padding

// Reply words: 0 header, 1 buffer, 2..5 core counters, 6 last READ reply,
// 7..6+N positions, 7+N the CRC, then zeros.
localparam integer TXW = 5;
localparam [TXW-1:0] TX_POS0 = 5'd7;
localparam [TXW-1:0] TX_CRC  = 5'd7 + N[TXW-1:0];
localparam [TXW-1:0] TX_ZERO = 5'd8 + N[TXW-1:0];

localparam [4:0] SEG_HDR_WORDS = 5'd1 + N[4:0];   // H1 and the N v words after H0
localparam [4:0] CON_HDR_WORDS = 5'd8 + N[4:0];   // and a CONIC's seven K words

// The set bits of an axis mask.
function [3:0] ones8(input [7:0] m);
    integer i;
    begin
        ones8 = 4'd0;
        for (i = 0; i < 8; i = i + 1) ones8 = ones8 + {3'd0, m[i]};
    end
endfunction

// CRC-16/CCITT-FALSE, one bit: polynomial 0x1021, MSB first.
function [15:0] crc_bit(input [15:0] crc, input b);
    crc_bit = {crc[14:0], 1'b0} ^ ((crc[15] ^ b) ? 16'h1021 : 16'h0000);
endfunction

// ---------------------------------------------------------------- synchronizers
// [0] first flop, [1] second (the synchronized level), [2] its previous value.
reg [2:0] sck_q, cs_q;
reg [1:0] mosi_q;

always @(posedge clk) begin
    mosi_q <= {mosi_q[0], spi_mosi_i};
    if (rst) begin
        sck_q <= 3'b000;
        cs_q  <= 3'b111;
    end else begin
        sck_q <= {sck_q[1:0], spi_sck_i};
        cs_q  <= {cs_q[1:0], spi_cs_n_i};
    end
end

wire cs_fall = !cs_q[1] && cs_q[2];
wire cs_rise = cs_q[1] && !cs_q[2];
// A bit: SCK rises while CS has been low for a sample already.
wire shift   = sck_q[1] && !sck_q[2] && !cs_q[1] && !cs_q[2];
wire bit_in  = mosi_q[1];

// ---------------------------------------------------------------- command buffer
wire [CBUF_AW:0] used, level;
wire             full;
`ifdef FORMAL
wire             f_buf_wr, f_buf_commit, f_buf_rollback;
wire [31:0]      f_buf_wdata;
`endif
reg              buf_wr, buf_commit, buf_rollback;
wire [31:0]      rx_word;

cp_fifo #(.DW(32), .AW(CBUF_AW)) u_cbuf (
    .clk(clk), .rst(rst), .clear_i(ctl_flush_o),
    .wr_i(buf_wr), .wr_data_i(rx_word), .commit_i(buf_commit), .rollback_i(buf_rollback),
    .full_o(full), .used_o(used), .level_o(level),
    .out_valid_o(cmd_valid_o), .out_ready_i(cmd_ready_i), .out_data_o(cmd_data_o)
`ifdef FORMAL
    // The buffer's own view of its write side (docs/FORMAL.md).
    , .f_wr_o(f_buf_wr), .f_wr_data_o(f_buf_wdata), .f_commit_o(f_buf_commit),
    .f_rollback_o(f_buf_rollback)
`endif
    );

wire unused_buf = &{1'b0, full, level};

// Free words: 2^CBUF_AW minus every word held (the head included).
localparam [CBUF_AW:0] CBUF_WORDS = 1 << CBUF_AW;
wire [CBUF_AW:0] free = used[CBUF_AW] ? {(CBUF_AW+1){1'b0}} : CBUF_WORDS - used;
wire [15:0]      free16 = {{(15 - CBUF_AW){1'b0}}, free};

// ---------------------------------------------------------------- state
// Control (reset).
reg [7:0]     seq_q, seq_d;              // byte 1 of the last frame that had one
reg [2:0]     result_q, result_d;        // result of the last frame
reg           fresh_q, fresh_d;          // no frame has ended since reset
reg [15:0]    reads_q, reads_d;          // READ replies taken, mod 2^16
// Frame state (initialized at CS fall).
reg [1:0]     ph_q, ph_d;
reg [4:0]     bit_q, bit_d;              // bits of the current word received
reg [TXW-1:0] txn_q, txn_d;              // the next reply word to load
reg [15:0]    crc_rx_q, crc_rx_d;
reg [15:0]    crc_tx_q, crc_tx_d;
reg [15:0]    left_q, left_d;            // command words still to come
reg           wr_ok_q, wr_ok_d;          // the frame's words go into the buffer
reg           bad_type_q, bad_type_d;
reg           no_room_q, no_room_d;
reg           bad_cmd_q, bad_cmd_d;
reg           urg_q, urg_d;              // an URGENT frame: its one word is not a command
reg [22:0]    uw_q, uw_d;                // its word's {[31:16], [6:0]}
// Whole-command tracking: a segment's header words, then its chunks' words.
reg [4:0]     hdr_left_q, hdr_left_d;
reg [15:0]    chunks_left_q, chunks_left_d;
reg [1:0]     cw_q, cw_d;                // words of the current chunk taken
reg           seg_add2_q, seg_add2_d;    // three words per chunk
// Datapath.
reg [31:0]    sr_q, sr_d;                // MOSI in at [0], MISO out of [31]
reg [7:0]     last_addr_q;              // the register the last READ named

assign rx_word = {sr_q[30:0], bit_in};
wire [15:0] crc_tx_next = crc_bit(crc_tx_q, sr_q[31]);
wire        in_cmd = (hdr_left_q != 5'd0) || (chunks_left_q != 16'd0);
// PTIMER: a segment's v words after H1, by its axis form H0[15:0].
wire [4:0]  pt_v_words = rx_word[15] ? {1'b0, ones8(rx_word[7:0])} : N[4:0];
wire        word_end = shift && (bit_q == 5'd31);

// The reply words, each loaded onto MISO when its first bit goes out: word 0 at
// CS fall, word txn_q at the end of the word before it. Words 2..6+N are core
// registers, read through the core's read port as they go out.
wire [31:0]   tx_word0 = {MAGIC, seq_q, 5'd0, result_q, 4'd0, fresh_q, enable_i, estop_i,
                         used != {(CBUF_AW+1){1'b0}}};
wire [TXW-1:0] txn_pos = txn_q - TX_POS0;
reg [31:0]    tx_word;
reg [7:0]     rd_addr;
always @* begin
    // Registers 0x00..0x03 (status and counters), the one the last READ named,
    // 0x10+i (positions); 0xFF reads 0.
    case (txn_q)
    5'd2: rd_addr = 8'h00;
    5'd3: rd_addr = 8'h01;
    5'd4: rd_addr = 8'h02;
    5'd5: rd_addr = 8'h03;
    5'd6: rd_addr = last_addr_q;
    default: rd_addr = (txn_q >= TX_POS0 && txn_q < TX_CRC) ? 8'h10 + {3'd0, txn_pos} : 8'hFF;
    endcase
    if (txn_q == 5'd1)         tx_word = {free16, reads_q};
    else if (txn_q == TX_CRC)  tx_word = {crc_tx_next, 16'd0};
    else                       tx_word = rd_data_i;
end

always @* begin
    seq_d = seq_q;  result_d = result_q;  fresh_d = fresh_q;
    reads_d = rsp_valid_i ? reads_q + 1'b1 : reads_q;
    ph_d = ph_q;  bit_d = bit_q;  txn_d = txn_q;  crc_rx_d = crc_rx_q;  crc_tx_d = crc_tx_q;
    left_d = left_q;  wr_ok_d = wr_ok_q;  bad_type_d = bad_type_q;  no_room_d = no_room_q;
    bad_cmd_d = bad_cmd_q;  hdr_left_d = hdr_left_q;  chunks_left_d = chunks_left_q;
    cw_d = cw_q;  seg_add2_d = seg_add2_q;  urg_d = urg_q;  uw_d = uw_q;
    sr_d = sr_q;
    buf_wr = 1'b0;  buf_commit = 1'b0;  buf_rollback = 1'b0;
    ctl_start_o = 1'b0;  ctl_stop_o = 1'b0;  ctl_flush_o = 1'b0;  ctl_ack_o = 1'b0;
    ctl_hold_o = 1'b0;  ctl_resume_o = 1'b0;  ctl_ovr_o = 1'b0;
    frame_ok_o = 1'b0;

    if (cs_fall) begin
        // A frame begins: the reply's word 0 goes out at once.
        sr_d = tx_word0;
        ph_d = PH_HDR;  bit_d = 5'd0;  txn_d = 5'd1;
        crc_rx_d = 16'hFFFF;  crc_tx_d = 16'hFFFF;
        wr_ok_d = 1'b0;  bad_type_d = 1'b0;  no_room_d = 1'b0;  bad_cmd_d = 1'b0;
        hdr_left_d = 5'd0;  chunks_left_d = 16'd0;  cw_d = 2'd0;  urg_d = 1'b0;
    end else if (shift) begin
        bit_d = bit_q + 1'b1;
        if (ph_q != PH_DONE) crc_rx_d = crc_bit(crc_rx_q, bit_in);
        if (txn_q <= TX_CRC) crc_tx_d = crc_tx_next;
        if (word_end) begin
            // The received word comes off the register, the next reply word goes on.
            sr_d = tx_word;
            if (txn_q != TX_ZERO) txn_d = txn_q + 1'b1;
        end else begin
            sr_d = rx_word;
        end

        case (ph_q)
        PH_HDR: begin
            if (bit_q == 5'd15) seq_d = rx_word[7:0];
            if (word_end) begin
                // rx_word = {type, seq, nwords}. Room is judged against the free
                // words that go out in reply word 1, loaded in this same cycle.
                left_d = rx_word[15:0];
                bad_type_d = !(rx_word[31:24] == T_COMMANDS ||
                               (rx_word[31:24] == T_POLL && rx_word[15:0] == 16'd0) ||
                               (rx_word[31:24] == T_URGENT && rx_word[15:0] == 16'd1));
                urg_d = rx_word[31:24] == T_URGENT;
                no_room_d = rx_word[31:24] == T_COMMANDS && rx_word[15:0] > free16;
                wr_ok_d = rx_word[31:24] == T_COMMANDS && rx_word[15:0] <= free16;
                ph_d = (rx_word[15:0] == 16'd0) ? PH_CRC : PH_WORDS;
            end
        end
        PH_WORDS: if (word_end) begin
            buf_wr = wr_ok_q;
            left_d = left_q - 1'b1;
            if (left_q == 16'd1) ph_d = PH_CRC;
            if (urg_q) begin
                // An URGENT frame's word: not a command, kept for its CS rise.
                uw_d = {rx_word[31:16], rx_word[6:0]};
            end else if (!in_cmd) begin
                // A command starts: a SEGMENT has H1, N v words and its chunks to
                // come, a CONIC also K0..K6 before its chunks.
                case (rx_word[31:28])
                4'h1: begin
                    if (PTIMER != 0) begin
                        // H1, the form's v words, L; no chunks.
                        hdr_left_d = 5'd2 + pt_v_words;
                        chunks_left_d = 16'd0;
                    end else begin
                        hdr_left_d = SEG_HDR_WORDS;
                        chunks_left_d = rx_word[15:0];
                    end
                    seg_add2_d = rx_word[22];
                    cw_d = 2'd0;
                end
                4'h5: begin
                    if (CONIC != 0) begin
                        // H0[18]: a continuation carries K5, K6 only.
                        if (PTIMER != 0) begin
                            hdr_left_d = 5'd2 + pt_v_words + (rx_word[18] ? 5'd2 : 5'd7);
                            chunks_left_d = 16'd0;
                        end else begin
                            hdr_left_d = rx_word[18] ? CON_HDR_WORDS - 5'd5 : CON_HDR_WORDS;
                            chunks_left_d = rx_word[15:0];
                        end
                        seg_add2_d = rx_word[22];
                        cw_d = 2'd0;
                    end else begin
                        bad_cmd_d = 1'b1;
                    end
                end
                4'h6: begin
                    // PHASE: u, r's two words with H0[24], S and H's four with H0[27].
                    if (PTIMER != 0)
                        hdr_left_d = 5'd1 + (rx_word[24] ? 5'd2 : 5'd0) + (rx_word[27] ? 5'd4 : 5'd0);
                    else
                        bad_cmd_d = 1'b1;
                end
                4'h2, 4'h3, 4'h4: ;
                default: bad_cmd_d = 1'b1;
                endcase
            end else if (hdr_left_q != 5'd0) begin
                hdr_left_d = hdr_left_q - 1'b1;
            end else if (cw_q == {seg_add2_q, !seg_add2_q}) begin
                cw_d = 2'd0;
                chunks_left_d = chunks_left_q - 1'b1;
            end else begin
                cw_d = cw_q + 1'b1;
            end
        end
        PH_CRC: if (bit_q == 5'd15) ph_d = PH_DONE;
        default: ;
        endcase
    end

    if (cs_rise) begin
        // The frame ends: the first failing check is its result.
        if (ph_q != PH_DONE)          result_d = R_TRUNCATED;
        else if (crc_rx_q != 16'd0)   result_d = R_BAD_CRC;
        else if (bad_type_q)          result_d = R_BAD_TYPE;
        else if (no_room_q)           result_d = R_NO_ROOM;
        else if (bad_cmd_q)           result_d = R_BAD_CMD;
        else if (in_cmd)              result_d = R_SPLIT;
        else                          result_d = R_OK;
        buf_commit   = result_d == R_OK;
        buf_rollback = result_d != R_OK;
        fresh_d = 1'b0;
        ctl_start_o  = result_d == R_OK && urg_q && uw_q[0];
        ctl_stop_o   = result_d == R_OK && urg_q && uw_q[1];
        ctl_flush_o  = result_d == R_OK && urg_q && uw_q[2];
        ctl_ack_o    = result_d == R_OK && urg_q && uw_q[3];
        ctl_hold_o   = result_d == R_OK && urg_q && uw_q[4];
        ctl_resume_o = result_d == R_OK && urg_q && uw_q[5];
        ctl_ovr_o    = result_d == R_OK && urg_q && uw_q[6];
        frame_ok_o   = ph_q == PH_DONE && crc_rx_q == 16'd0;
    end
end

always @(posedge clk) begin
    if (rst) begin
        seq_q    <= 8'd0;
        result_q <= R_OK;
        fresh_q  <= 1'b1;
        reads_q  <= 16'd0;
        last_addr_q <= 8'hFF;
    end else begin
        seq_q    <= seq_d;
        result_q <= result_d;
        fresh_q  <= fresh_d;
        reads_q  <= reads_d;
        if (rsp_valid_i) last_addr_q <= rsp_addr_i;
    end
    ph_q <= ph_d;  bit_q <= bit_d;  txn_q <= txn_d;  crc_rx_q <= crc_rx_d;  crc_tx_q <= crc_tx_d;
    left_q <= left_d;  wr_ok_q <= wr_ok_d;  bad_type_q <= bad_type_d;  no_room_q <= no_room_d;
    bad_cmd_q <= bad_cmd_d;  hdr_left_q <= hdr_left_d;  chunks_left_q <= chunks_left_d;
    cw_q <= cw_d;  seg_add2_q <= seg_add2_d;  urg_q <= urg_d;  uw_q <= uw_d;
    sr_q <= sr_d;
end

`ifdef FORMAL
// ---------------------------------------------------------------- formal
// Properties for yosys-smtbmc (docs/FORMAL.md, scripts/formal, row `spi` of
// formal/proofs.tsv): a refused frame leaves no trace in the command buffer, an
// accepted one puts exactly its command words there, in order. The shadow below
// is a second frame decoder written from docs/PROTOCOL.md ("Host -> card", "What
// the card does with a frame"), fed with the synchronized pins (cs_fall, cs_rise,
// shift, bit_in: the sampling itself is checked to the cycle by tb/spi). It
// counts words and bits instead of following phases, and parses commands by
// their lengths instead of hdr_left/chunks_left/cw. The environment is free:
// pins, core and reads, any value on any cycle, reset in the first.
reg f_past_valid = 1'b0;
always @(posedge clk) f_past_valid <= 1'b1;
always @* if (!f_past_valid) assume(rst);

reg          f_in = 1'b0;      // inside a frame: CS fall seen, CS rise not yet
reg [16:0]   f_wc;             // whole 32-bit words received (saturates)
reg [4:0]    f_b5;             // bits of the current word received
reg [31:0]   f_sr;             // the last 32 bits received
reg [31:0]   f_hdr;            // word 0: type, seq, nwords
reg [15:0]   f_crc;            // CRC-16 over every bit up to the CRC's last
reg [15:0]   f_free;           // free words announced when the header ended
reg [17:0]   f_cl;             // words still due in the current command
reg          f_bc;             // a command started with an unknown opcode
reg [16:0]   f_nwr;            // command words this frame put into the buffer
reg [CBUF_AW+1:0] f_lvl;       // committed words in the buffer (head included)
reg [22:0]   f_uw;             // an URGENT frame's word, {[31:16], [6:0]}

wire [31:0] f_word    = {f_sr[30:0], bit_in};                // the word ending now
wire        f_wend    = shift && f_b5 == 5'd31;
wire [15:0] f_nwords  = f_hdr[15:0];
wire [7:0]  f_type    = f_hdr[31:24];
wire [16:0] f_nw17    = {1'b0, f_nwords};
wire        f_hdr_ok  = f_wc != 17'd0;                       // the header has arrived
// The CRC's last bit has arrived: words 0..nwords, then 16 bits.
wire        f_done    = f_hdr_ok && (f_wc > f_nw17 + 17'd1 || (f_wc == f_nw17 + 17'd1 && f_b5 >= 5'd16));
wire        f_cmdword = f_wend && f_hdr_ok && f_wc <= f_nw17; // a command word ends now
wire        f_badtype = !(f_type == 8'h01 || (f_type == 8'h00 && f_nwords == 16'd0) ||
                          (f_type == 8'h02 && f_nwords == 16'd1));
wire        f_urgent  = f_type == 8'h02;                     // its word is not a command
wire        f_noroom  = f_type == 8'h01 && f_nwords > f_free;
wire        f_wr_ok   = f_type == 8'h01 && !f_noroom;
wire        f_pop     = cmd_valid_o && cmd_ready_i;
wire [CBUF_AW+1:0] f_pop_w = {{(CBUF_AW+1){1'b0}}, f_pop};
// Free words as reply word 1 states them: CBUF_WORDS - held, 0 at the least.
wire [15:0] f_free_now = (used >= CBUF_WORDS) ? 16'd0 : CBUF_WORDS - used;
// Words of a command starting with this word, after it (docs/PROTOCOL.md).
wire [17:0] f_nchunks = {2'd0, f_word[15:0]};
wire [17:0] f_seg_len = N + (f_word[22] ? 18'd3 * f_nchunks : 18'd2 * f_nchunks) + 18'd1;
wire [17:0] f_con_len = f_seg_len + (f_word[18] ? 18'd2 : 18'd7);
wire        f_conic   = CONIC != 0;
// PTIMER (docs/CORE.md "Phase-timer builds"): no chunks; the axis form's v words, L.
wire [17:0] f_pt_v    = !f_word[15] ? N[17:0] : {17'd0, f_word[0]} + {17'd0, f_word[1]} + {17'd0, f_word[2]} +
                        {17'd0, f_word[3]} + {17'd0, f_word[4]} + {17'd0, f_word[5]} +
                        {17'd0, f_word[6]} + {17'd0, f_word[7]};
wire [17:0] f_pt_seg  = f_pt_v + 18'd2;
wire [17:0] f_pt_con  = f_pt_seg + (f_word[18] ? 18'd2 : 18'd7);
wire [17:0] f_phase   = 18'd1 + (f_word[24] ? 18'd2 : 18'd0) + (f_word[27] ? 18'd4 : 18'd0);
wire        f_ptimer  = PTIMER != 0;
// The most header words a command has left (PTIMER: H1, at most 8 v words, a mask's,
// a CONIC's seven K words and L).
localparam [4:0] HDR_MAX = (PTIMER != 0) ? ((CONIC != 0) ? 5'd17 : 5'd10)
                                         : ((CONIC != 0) ? CON_HDR_WORDS : SEG_HDR_WORDS);

// The result of the frame ending now: the first failing check.
reg [2:0] f_result;
always @* begin
    if (!f_done)                f_result = R_TRUNCATED;
    else if (f_crc != 16'd0)    f_result = R_BAD_CRC;
    else if (f_badtype)         f_result = R_BAD_TYPE;
    else if (f_noroom)          f_result = R_NO_ROOM;
    else if (f_bc)              f_result = R_BAD_CMD;
    else if (f_cl != 18'd0)     f_result = R_SPLIT;
    else                        f_result = R_OK;
end

always @(posedge clk) begin
    f_lvl <= f_lvl - f_pop_w;
    if (cs_fall) begin
        f_in <= 1'b1;  f_wc <= 17'd0;  f_b5 <= 5'd0;  f_crc <= 16'hFFFF;
        f_cl <= 18'd0;  f_bc <= 1'b0;  f_nwr <= 17'd0;
    end
    if (shift) begin
        f_b5 <= f_b5 + 1'b1;
        f_sr <= f_word;
        if (!f_done) f_crc <= crc_bit(f_crc, bit_in);
        if (f_wend && f_wc != 17'h1FFFF) f_wc <= f_wc + 1'b1;
        if (f_wend && !f_hdr_ok) begin
            f_hdr  <= f_word;
            f_free <= f_free_now;
        end
        if (f_cmdword && f_urgent) f_uw <= {f_word[31:16], f_word[6:0]};
        if (f_cmdword && !f_urgent) begin
            if (f_wr_ok) f_nwr <= f_nwr + 1'b1;
            if (f_cl != 18'd0)                f_cl <= f_cl - 1'b1;
            else if (f_word[31:28] == 4'h1)   f_cl <= f_ptimer ? f_pt_seg : f_seg_len;
            else if (f_word[31:28] == 4'h5 && f_conic) f_cl <= f_ptimer ? f_pt_con : f_con_len;
            else if (f_word[31:28] == 4'h6 && f_ptimer) f_cl <= f_phase;
            else if (f_word[31:28] < 4'h2 || f_word[31:28] > 4'h4) f_bc <= 1'b1;
        end
    end
    if (cs_rise) begin
        f_in <= 1'b0;
        if (f_result == R_OK) f_lvl <= f_lvl - f_pop_w + f_nwr[CBUF_AW+1:0];
        // An accepted URGENT FLUSH empties the buffer.
        if (f_result == R_OK && f_urgent && f_uw[2]) f_lvl <= {(CBUF_AW+2){1'b0}};
    end
    if (rst) begin
        f_in  <= 1'b0;
        f_lvl <= {(CBUF_AW+2){1'b0}};
    end
end

// RTL counterparts of the shadow's command parser.
wire [17:0] f_cpc = seg_add2_q ? 18'd3 : 18'd2;             // words per chunk
wire [17:0] f_rtl_cl = {13'd0, hdr_left_q} + f_cpc * {2'd0, chunks_left_q} - {16'd0, cw_q};
wire [31:0] f_mask = (32'd1 << f_b5) - 32'd1;

always @* if (f_past_valid) begin
    // The buffer changes at a frame's end only, and then always: commit exactly
    // when every check of the table passes, roll back otherwise.
    // (As the buffer sees its write side: f_buf_* are cp_fifo's own inputs.)
    if (f_buf_commit || f_buf_rollback) assert(cs_rise);
    // An URGENT frame acts at its CS rise, when every check passes, and only then.
    assert(ctl_start_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[0]));
    assert(ctl_stop_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[1]));
    assert(ctl_flush_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[2]));
    assert(ctl_ack_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[3]));
    assert(ctl_hold_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[4]));
    assert(ctl_resume_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[5]));
    assert(ctl_ovr_o == (cs_rise && f_result == R_OK && f_urgent && f_uw[6]));
    if (ctl_ovr_o) assert(ctl_ovr_val_o == f_uw[22:7]);
    // The watchdog's kick: at a CS rise that ends a whole frame whose CRC checks.
    assert(frame_ok_o == (cs_rise && f_done && f_crc == 16'd0));
    if (cs_rise) begin
        assert(result_d == f_result);
        assert(f_buf_commit == (f_result == R_OK));
        assert(f_buf_rollback == (f_result != R_OK));
    end
    // A word goes into the buffer exactly when a command word of a frame that
    // fits ends, it is the 32 bits just received, and the buffer has room.
    assert(f_buf_wr == (f_in && f_cmdword && f_wr_ok));
    if (f_buf_wr) assert(!full && f_buf_wdata == f_word);
    // Committed words: those of accepted frames, less what the core took; the
    // uncommitted ones: this frame's, and none between frames.
    assert(level == f_lvl);
    assert(used == f_lvl + (f_in ? f_nwr[CBUF_AW+1:0] : {(CBUF_AW+2){1'b0}}));

    // Auxiliary invariants: the RTL's frame state as the shadow's.
    assert(f_in == !cs_q[2]);
    if (f_in) begin
        assert(bit_q == f_b5);
        assert(crc_rx_q == f_crc);
        assert(((sr_q ^ f_sr) & f_mask) == 32'd0);
        assert(bad_cmd_q == f_bc);
        assert(f_rtl_cl == f_cl);
        assert(cw_q < f_cpc[1:0] && hdr_left_q <= HDR_MAX);
        if (f_ptimer) assert(chunks_left_q == 16'd0);
        if (hdr_left_q != 5'd0 || chunks_left_q == 16'd0) assert(cw_q == 2'd0);
        if (!f_hdr_ok) begin
            assert(ph_q == PH_HDR && f_cl == 18'd0 && !f_bc && f_nwr == 17'd0 && !urg_q);
        end else begin
            assert(bad_type_q == f_badtype && no_room_q == f_noroom && wr_ok_q == f_wr_ok);
            assert(urg_q == f_urgent);
            // An URGENT frame's word, once received, as the shadow's.
            if (f_urgent && f_nwords != 16'd0 && f_wc > 17'd1) assert(uw_q == f_uw);
            if (f_wc <= f_nw17) begin
                assert(ph_q == PH_WORDS && left_q == f_nwords + 16'd1 - f_wc[15:0]);
            end else begin
                assert(left_q == 16'd0 && ph_q == (f_done ? PH_DONE : PH_CRC));
            end
            if (f_wr_ok) begin
                assert(f_nwr == f_nw17 - {1'b0, left_q});
                // Room: the words still due fit beside every word held.
                if (left_q != 16'd0)
                    assert({16'd0, used} + {{(CBUF_AW+1){1'b0}}, left_q} <= {16'd0, CBUF_WORDS});
            end else begin
                assert(f_nwr == 17'd0);
            end
        end
        assert(f_nwr <= CBUF_WORDS);
    end
end
`endif

// ---------------------------------------------------------------- outputs
assign spi_miso_o    = sr_q[31];
// Driven only while CS is low (the raw pin: released at once when CS rises).
assign spi_miso_oe_o = !spi_cs_n_i;
// Replies are taken as they come; the register the last one named is word 6.
assign rsp_ready_o   = 1'b1;
assign rd_addr_o     = rd_addr;
assign ctl_ovr_val_o = uw_q[22:7];

endmodule

`resetall
