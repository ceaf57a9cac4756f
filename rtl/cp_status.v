// SPDX-License-Identifier: MIT
// cp_status — the motion core's status: faults, counters, configuration and
// the READ registers.
//
// Fault requests come from the parser (a refusal with its code), the builder
// (a pattern too long), the runner (underrun, or a conic walk not ending on its last move), CONTROL abort, the
// watchdog and the E-stop input; one priority encoder picks the code: E-stop, abort, watchdog, the runner's
// (underrun or CONIC_END), pattern, then the parser's. CLEAR drops what was latched before this cycle; then the
// first fault latches. The flush (stop and empty every queue) is raised by the
// E-stop, by abort, and by a latched fault once no segment is under way.
// It also holds the watchdog (no frame for its timeout: STOP, drivers off, WATCHDOG),
// the drivers' enable, the stretch flag and the counters, each
// axis's pulse configuration (CONFIG) and the READ registers, with two read
// ports: the READ command's and the SPI front end's.
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_status.*,
// bench tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_status #(
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer UMAX = 1048575,
    parameter integer KMAX = 8,
    parameter integer CAW = 6,
    parameter integer SAW = 2,
    parameter integer TW = 16,
    parameter integer PW = 32,
    parameter integer STEP_HIGH_RESET = 1,
    parameter integer STEP_LOW_RESET = 1,
    parameter integer DIR_SETUP_RESET = 1,
    parameter integer DIR_HOLD_RESET = 1,
    parameter [0:0] STEP_POL_RESET = 1'b1,
    parameter [0:0] DIR_POL_RESET = 1'b1,
    parameter integer CBUF_AW = 0,
    parameter integer CLK_HZ = 48000000,
    parameter [31:0] BUILD_ID = 32'h0,
    // Reported only (READ 0x26): conic segments taken, and the walker's width.
    parameter integer CONIC = 0,
    parameter integer CIW = 40,
    // Reported only (READ 0x23 [24]): limit and probe inputs (cp_inputs).
    parameter integer INPUTS = 0,
    // Reported only (READ 0x23 [25]): feed hold and override (cp_feed).
    parameter integer FEED = 0,
    // Moves timed by the phase timer (READ 0x23 [26]); its segments' length word
    // widens the segment queue (SQW).
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          estop_i,

    // Requests of the command word taken now (cp_cmd).
    input  wire          abort_i,
    input  wire          clear_i,
    input  wire          ack_i,            // ACK (out of band): clears any fault, E-stop's too
    input  wire          kick_i,           // a whole frame with a good CRC ended (cp_spi): the watchdog's kick
    input  wire          drivers_on_i,
    input  wire          drivers_off_i,
    input  wire          cfg_write_i,
    input  wire [31:0]   cfg_word_i,
    // Fault requests.
    input  wire          cmd_fault_i,
    input  wire [7:0]    cmd_code_i,
    input  wire          build_fault_i,
    input  wire          run_fault_i,
    input  wire          run_conic_i,      // the runner's fault is CONIC_END, not UNDERRUN
    input  wire          lim_hit_i,        // the runner stopped at an active limit (LIMIT)
    // The inputs, active (cp_inputs): READ 0x27 live, 0x28 the limits at the LIMIT fault.
    input  wire [N-1:0]  lim_min_i,
    input  wire [N-1:0]  lim_max_i,
    input  wire          probe_i,
    input  wire [2:0]    seek_i,           // the seek: {tripped, mode} (cp_inputs)
    // Feed hold and override (cp_feed; 0 without): READ 0x29 and 0x2A.
    input  wire [31:0]   feed_i,
    input  wire [15:0]   override_i,

    // Events from the runner.
    input  wire          stretch_i,
    input  wire          fire_i,
    input  wire          seg_done_i,
    input  wire          seg_active_i,
    // What the status word counts.
    input  wire          running_i,
    input  wire          torch_i,          // the torch output (status bit 5)
    input  wire          cur_valid_i,
    input  wire [SQW:0]  segq_i,
    input  wire          build_busy_i,
    input  wire [1:0]    run_level_i,
    input  wire [CAW:0]  ch_level_i,
    input  wire [N*PW-1:0] position_i,

    // Read ports: the READ command's and the SPI front end's.
    input  wire [7:0]    rd_addr0_i,
    output wire [31:0]   rd_data0_o,
    input  wire [7:0]    rd_addr1_i,
    output wire [31:0]   rd_data1_o,

    output wire          fault_o,
    output wire [7:0]    err_o,
    output wire          flush_o,
    output wire          stretched_o,
    output wire          enable_o,
    output wire [31:0]   status_o,
    output wire [31:0]   stretch_cnt_o,
    output wire [31:0]   moves_done_o,
    output wire [31:0]   segs_done_o,

    // Each axis's pulse configuration.
    output wire [N*TW-1:0] cfg_high_o,
    output wire [N*TW-1:0] cfg_low_o,
    output wire [N*TW-1:0] cfg_setup_o,
    output wire [N*TW-1:0] cfg_hold_o,
    output wire [N-1:0]  cfg_step_pol_o,
    output wire [N-1:0]  cfg_dir_pol_o,
    output wire          cfg_new_o,        // CONFIG was written at the last edge (cp_pulse)
    // The watchdog ran out (docs/CORE.md "Watchdog"): the runner stops at once, at a
    // move boundary; the drivers go off and WATCHDOG latches.
    output wire          wd_trip_o
);

localparam integer SQW = SAW + $clog2(N + 1 + ((PTIMER != 0) ? 1 : 0));

localparam [7:0] E_NONE        = 8'd0;
localparam [7:0] E_SEG_PATTERN = 8'd8;
localparam [7:0] E_UNDERRUN    = 8'd9;
localparam [7:0] E_ESTOP       = 8'd10;
localparam [7:0] E_ABORT       = 8'd11;
localparam [7:0] E_CONIC_END   = 8'd17;
localparam [7:0] E_WATCHDOG    = 8'd19;
localparam [7:0] E_LIMIT       = 8'd20;

reg          fault_q, fault_d;
reg [7:0]    err_q, err_d;
reg          stretched_q, stretched_d;
reg          enable_q, enable_d;
reg [31:0]   stretch_cnt_q, stretch_cnt_d;
reg [31:0]   moves_done_q, moves_done_d;
reg [31:0]   segs_done_q, segs_done_d;
reg [TW-1:0] cfg_high_q [0:N-1];
reg [TW-1:0] cfg_low_q [0:N-1];
reg [TW-1:0] cfg_setup_q [0:N-1];
reg [TW-1:0] cfg_hold_q [0:N-1];
reg [N-1:0]  cfg_step_pol_q, cfg_dir_pol_q;
reg          cfg_new_q;
reg [N-1:0]  lim_min_at_q, lim_max_at_q;   // the active limits when LIMIT latched

// ---------------------------------------------------------------- watchdog
// CONFIG field 5 sets the timeout in units of 4096 clocks (0: off). The count is
// 1 in the clock after a kick (or the CONFIG write) and counts the clocks since;
// when it reaches timeout·4096 with no kick in that clock, the watchdog trips, and
// stays tripped (the count holds) until a kick: no frame for timeout·4096 clocks.
reg [15:0]   wd_limit_q;
reg [27:0]   wd_cnt_q, wd_cnt_d;
wire         wd_cfg = cfg_write_i && cfg_word_i[23:20] == 4'd5;
wire         wd_at  = wd_cnt_q == {wd_limit_q, 12'd0};
wire         wd_trip = wd_limit_q != 16'd0 && wd_at && !kick_i;
always @* begin
    wd_cnt_d = wd_cnt_q;
    if (kick_i || wd_cfg)                    wd_cnt_d = 28'd1;
    else if (wd_limit_q != 16'd0 && !wd_at) wd_cnt_d = wd_cnt_q + 1'b1;
end

// ---------------------------------------------------------------- fault priority
// The one place that decides which fault a cycle raises.
reg       fault_set;
reg [7:0] fault_code;
always @* begin
    fault_set = 1'b1;
    if (estop_i)            fault_code = E_ESTOP;
    else if (abort_i)       fault_code = E_ABORT;
    else if (wd_trip)       fault_code = E_WATCHDOG;
    else if (lim_hit_i)     fault_code = E_LIMIT;
    else if (run_fault_i)   fault_code = run_conic_i ? E_CONIC_END : E_UNDERRUN;
    else if (build_fault_i) fault_code = E_SEG_PATTERN;
    else if (cmd_fault_i)   fault_code = cmd_code_i;
    else begin
        fault_set  = 1'b0;
        fault_code = E_NONE;
    end
end

// ---------------------------------------------------------------- next state
// A latched fault waits for the segment under way to end before its flush.
wire flush_pending = fault_q && !flush_o;
reg clearing;
always @* begin
    fault_d = fault_q;  err_d = err_q;  enable_d = enable_q;
    stretched_d   = stretched_q || stretch_i;
    stretch_cnt_d = stretch_cnt_q + {31'd0, stretch_i};
    moves_done_d  = moves_done_q + {31'd0, fire_i};
    segs_done_d   = segs_done_q + {31'd0, seg_done_i};
    // Drivers: off wins over on; E-stop and a tripped watchdog hold them off.
    if (drivers_on_i) enable_d = 1'b1;
    if (drivers_off_i || estop_i || wd_trip) enable_d = 1'b0;
    // CLEAR drops what was latched before this cycle (a stretch in this very cycle
    // stays), but not an E-stop: only the out-of-band ACK, with the input released,
    // clears that (a CLEAR buffered before the E-stop cannot); then the first fault
    // latches. Neither clears a fault whose flush is still pending (the segment under
    // way has not ended): the queues are flushed before the core takes segments again.
    clearing = !estop_i && !flush_pending && ((clear_i && err_q != E_ESTOP) || ack_i);
    if (clearing) begin
        fault_d     = 1'b0;
        err_d       = E_NONE;
        stretched_d = stretch_i;
    end
    if (fault_set && (!fault_q || clearing)) begin
        fault_d = 1'b1;
        err_d   = fault_code;
    end
end
wire lim_latch = fault_set && (!fault_q || clearing) && fault_code == E_LIMIT;
// A latched fault lets the segment under way complete; E-stop and abort do not.
assign flush_o = estop_i || abort_i || (fault_q && !seg_active_i);

// ---------------------------------------------------------------- registers
integer a;
always @(posedge clk) begin
    if (rst) begin
        fault_q       <= 1'b0;
        err_q         <= E_NONE;
        stretched_q   <= 1'b0;
        enable_q      <= 1'b0;
        stretch_cnt_q <= 32'd0;
        moves_done_q  <= 32'd0;
        segs_done_q   <= 32'd0;
        cfg_step_pol_q <= {N{STEP_POL_RESET}};
        cfg_dir_pol_q  <= {N{DIR_POL_RESET}};
        cfg_new_q      <= 1'b0;
        wd_limit_q     <= 16'd0;
        wd_cnt_q       <= 28'd1;
        lim_min_at_q   <= {N{1'b0}};
        lim_max_at_q   <= {N{1'b0}};
        for (a = 0; a < N; a = a + 1) begin
            cfg_high_q[a]  <= STEP_HIGH_RESET[TW-1:0];
            cfg_low_q[a]   <= STEP_LOW_RESET[TW-1:0];
            cfg_setup_q[a] <= DIR_SETUP_RESET[TW-1:0];
            cfg_hold_q[a]  <= DIR_HOLD_RESET[TW-1:0];
        end
    end else begin
        fault_q       <= fault_d;
        err_q         <= err_d;
        stretched_q   <= stretched_d;
        enable_q      <= enable_d;
        stretch_cnt_q <= stretch_cnt_d;
        moves_done_q  <= moves_done_d;
        segs_done_q   <= segs_done_d;
        cfg_new_q     <= cfg_write_i;
        wd_cnt_q      <= wd_cnt_d;
        // The limits that stopped the run, kept while LIMIT is latched.
        if (lim_latch) begin
            lim_min_at_q <= lim_min_i;
            lim_max_at_q <= lim_max_i;
        end else if (clearing) begin
            lim_min_at_q <= {N{1'b0}};
            lim_max_at_q <= {N{1'b0}};
        end
        if (wd_cfg) wd_limit_q <= cfg_word_i[15:0];
        if (cfg_write_i) begin
            for (a = 0; a < N; a = a + 1) begin
                if (cfg_word_i[27:24] == a[3:0]) begin
                    case (cfg_word_i[23:20])
                    4'd0: cfg_high_q[a]  <= cfg_word_i[TW-1:0];
                    4'd1: cfg_low_q[a]   <= cfg_word_i[TW-1:0];
                    4'd2: cfg_setup_q[a] <= cfg_word_i[TW-1:0];
                    4'd3: cfg_hold_q[a]  <= cfg_word_i[TW-1:0];
                    4'd4: begin
                        cfg_step_pol_q[a] <= cfg_word_i[0];
                        cfg_dir_pol_q[a]  <= cfg_word_i[1];
                    end
                    default: ;  // card-wide fields (5: the watchdog) are not an axis's
                    endcase
                end
            end
        end
    end
end

// ---------------------------------------------------------------- READ registers
wire [31:0] ch_level32 = {{(31 - CAW){1'b0}}, ch_level_i};
// Segments queued: committed, being built, built and waiting, loaded.
wire [7:0]  segs_queued = {{(7 - SQW){1'b0}}, segq_i} + {7'd0, build_busy_i} +
                          {6'd0, run_level_i} + {7'd0, cur_valid_i};
wire [31:0] status_word = {ch_level32 > 32'd255 ? 8'd255 : ch_level32[7:0],
                           segs_queued,
                           err_q, FEED != 0 && !feed_i[30], feed_i[31], torch_i, enable_q, estop_i, stretched_q, fault_q, running_i};
// Capabilities (READ 0x20..0x25): what the host must know of this build.
localparam [31:0] CAPS = {3'd0, TW[4:0], SAW[3:0], CAW[3:0], KMAX[7:0], N[7:0]};
localparam [31:0] W_WORD = W;
localparam [31:0] UMAX_WORD = UMAX;
// The version of the command set and register map (docs/CORE.md) together with
// the SPI frames (docs/PROTOCOL.md); the host refuses a card of another version.
localparam [7:0] PROTOCOL_VERSION = 8'd2;
localparam [0:0] INPUTS_BIT = INPUTS != 0;
localparam [0:0] FEED_BIT = FEED != 0;
localparam [0:0] PTIMER_BIT = PTIMER != 0;
localparam [31:0] CAPS2 = {5'd0, PTIMER_BIT, FEED_BIT, INPUTS_BIT, PROTOCOL_VERSION, CBUF_AW[7:0], PW[7:0]};
localparam [31:0] CLK_WORD = CLK_HZ;
localparam [31:0] CONIC_WORD = (CONIC == 0) ? 32'd0 : CIW;

// The inputs (INPUTS = 1 builds; 0 otherwise): [7:0] min active, [15:8] max active,
// [16] probe active, [18:17] the seek's mode, [19] the seek tripped; and the limits
// active when LIMIT latched.
wire [8:0]  min9 = {{(9 - N){1'b0}}, lim_min_i};
wire [8:0]  max9 = {{(9 - N){1'b0}}, lim_max_i};
wire [8:0]  min9_at = {{(9 - N){1'b0}}, lim_min_at_q};
wire [8:0]  max9_at = {{(9 - N){1'b0}}, lim_max_at_q};
wire [31:0] inputs_word = {12'd0, seek_i, probe_i, max9[7:0], min9[7:0]};
wire [31:0] limits_at_word = {16'd0, max9_at[7:0], min9_at[7:0]};
wire unused_inputs = &{1'b0, min9[8], max9[8], min9_at[8], max9_at[8]};

wire [7:0] read_addr [0:1];
assign read_addr[0] = rd_addr0_i;
assign read_addr[1] = rd_addr1_i;
reg [31:0] read_value [0:1];
integer    ri, rp;
always @* begin
    for (rp = 0; rp < 2; rp = rp + 1) begin
        read_value[rp] = 32'd0;
        case (read_addr[rp])
        8'h00: read_value[rp] = status_word;
        8'h01: read_value[rp] = stretch_cnt_q;
        8'h02: read_value[rp] = moves_done_q;
        8'h03: read_value[rp] = segs_done_q;
        8'h1F: read_value[rp] = 32'h43505331;   // "CPS1"
        8'h20: read_value[rp] = CAPS;
        8'h21: read_value[rp] = W_WORD;
        8'h22: read_value[rp] = UMAX_WORD;
        8'h23: read_value[rp] = CAPS2;
        8'h24: read_value[rp] = CLK_WORD;
        8'h25: read_value[rp] = BUILD_ID;
        8'h26: read_value[rp] = CONIC_WORD;
        8'h27: read_value[rp] = inputs_word;
        8'h28: read_value[rp] = limits_at_word;
        8'h29: read_value[rp] = feed_i;
        8'h2A: read_value[rp] = {16'd0, override_i};
        default: begin
            for (ri = 0; ri < N; ri = ri + 1)
                if (read_addr[rp] == 8'h10 + ri[7:0]) read_value[rp] = position_i[PW*ri +: 32];
        end
        endcase
    end
end

// ---------------------------------------------------------------- outputs
// CONFIG's axis, field and value bits only (a value's bits above TW are zero).
wire unused = &{1'b0, cfg_word_i[31:28], cfg_word_i[19:0]};
genvar ga;
generate
    for (ga = 0; ga < N; ga = ga + 1) begin : g_cfg
        assign cfg_high_o[TW*ga +: TW]  = cfg_high_q[ga];
        assign cfg_low_o[TW*ga +: TW]   = cfg_low_q[ga];
        assign cfg_setup_o[TW*ga +: TW] = cfg_setup_q[ga];
        assign cfg_hold_o[TW*ga +: TW]  = cfg_hold_q[ga];
    end
endgenerate
assign cfg_step_pol_o = cfg_step_pol_q;
assign cfg_dir_pol_o  = cfg_dir_pol_q;
assign cfg_new_o      = cfg_new_q;
assign rd_data0_o     = read_value[0];
assign rd_data1_o     = read_value[1];
assign fault_o        = fault_q;
assign err_o          = err_q;
assign stretched_o    = stretched_q;
assign enable_o       = enable_q;
assign status_o       = status_word;
assign stretch_cnt_o  = stretch_cnt_q;
assign moves_done_o   = moves_done_q;
assign segs_done_o    = segs_done_q;
assign wd_trip_o      = wd_trip;

endmodule

`resetall
