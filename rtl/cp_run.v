// SPDX-License-Identifier: MIT
// cp_run — the motion core's runner: pattern banks and replay, the move-event
// timer, the fire decision and the stretch count.
//
// The banks hold two lanes of every axis's pattern: cp_build writes the build
// lane while the replay reads the running one, one move a clock, into the replay
// registers. The timer takes chunks from the chunk queue (interval, count, add,
// add2) and counts the scaled time since the last move event: each clock adds
// scale_i (cp_feed, Q2.16; docs/CORE.md "Feed hold and override") to a fraction
// register and elapsed takes its carry (0, 1 or 2; always 1 at scale 1, so a
// move's interval is in clocks of scaled time). A move fires when the
// run is on, a segment is loaded, its move is due, the replay registers hold it
// and every stepping axis's cp_pulse is ready; a move that is due and cannot
// fire is counted late once. At a segment's last move the next built segment is
// loaded from the run queue (its moving axes take their directions); with none
// built and none coming, the run underruns. While a segment is under way, an axis
// it moves toward an active limit switch stops the run at once (lim_hit_o; docs/CORE.md
// "Inputs").
//
// The torch output (docs/CORE.md "Torch") is a register: while the run is on, it
// holds the out bit of the last segment loaded; it drops when the run stops, at
// E-stop and at abort.
//
// With PTIMER = 1 (a build toward the compact wire, docs/PROTOCOL.md "Toward a
// compact wire") the moves are timed by the phase timer (rtl/cp_ptimer.v) instead
// of chunks: the chunk queue carries its words ({sel, data} in the head's low 35
// bits, taken one a clock while its buffer is free), each segment's run queue word
// its move count U*2^k and its length per move L (Q2.30, in the phases' path
// units), and the timer counts half clocks of scaled time: each clock adds scale_i
// to a 17-bit fraction and the timer advances on its carry (0 or 1: at scale 1
// every other clock, at 2 every clock), from the run's START. A move is due when
// the timer says; its fire hands the timer the length of the move pending after
// it (the next segment's first when this one ends: owed while no segment is
// loaded). A timer that ran out of phases while a move waits undue stops the run
// as an underrun.
//
// With CONIC = 1 it holds the conic walker (rtl/cp_conic_serial.v), which cp_build
// loads: in a conic segment the plane axes u, v step by the walker's moves (each
// move's direction on their DIR, and in the move's own directions), the others by
// their patterns; a move fires only when the walker presents it too. The walk must
// arrive at its end on the segment's last move and on no other: a presented move
// that says otherwise does not fire and is a fault (CONIC_END).
//
// Part of cp_core (docs/CORE.md "Structure"); model twin model/cp_run.*, bench
// tb/core/test_core_parts.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_run #(
    parameter integer N = 4,
    parameter integer W = 1024,
    parameter integer CONIC = 0,
    // The conic walker's internal width (docs/CONIC.md "The walk, bit-serial").
    parameter integer CIW = 40,
    // 1: the timer runs on scale_i (cp_feed); 0: scale_i is not looked at, the timer
    // counts clocks (its scale is 1 and synthesis keeps no fraction register).
    parameter integer FEED = 0,
    // 1: moves timed by the phase timer (above); 0: by chunks.
    parameter integer PTIMER = 0
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          flush_i,          // stop and empty (cp_status)
    input  wire          estop_i,
    input  wire          start_i,          // CONTROL start, this cycle
    input  wire          stop_i,           // STOP (out of band), this cycle
    input  wire          abort_i,          // CONTROL abort, this cycle
    input  wire          fault_i,          // a fault is latched
    // Active limit switches (cp_inputs): a segment under way that moves an axis
    // toward an active limit stops at once (lim_hit_o; docs/CORE.md "Inputs").
    input  wire [N-1:0]  lim_min_i,
    input  wire [N-1:0]  lim_max_i,
    // The timer's scale, Q2.16 (cp_feed; 0x10000 = 1): the scaled time each clock adds.
    input  wire [17:0]   scale_i,

    // Chunk queue head: {last, add2, count, add, interval}.
    input  wire          ch_valid_i,
    input  wire [80:0]   ch_head_i,
    output reg           ch_pop_o,
    // Run queue head: {[L, k, U,] [conic, u, v,] out, lane, end, moving[N], dir[N]}
    // (L, k, U: PTIMER builds).
    input  wire          run_valid_i,
    input  wire [RDW-1:0] run_head_i,
    input  wire [1:0]    run_level_i,
    output reg           run_pop_o,
    // Whether more is coming: committed segments not yet built, one being built.
    input  wire          segq_empty_i,
    input  wire          build_busy_i,

    // The banks' write port (cp_build).
    input  wire          bank_we_i,
    input  wire [2:0]    bank_axis_i,
    input  wire [AW-1:0] bank_waddr_i,
    input  wire          bank_wbit_i,
    input  wire          bank_lane_i,
    input  wire          len_we_i,
    input  wire [AW-1:0] len_m1_i,

    // The conic walker's word port (cp_build), and whether it is free for the next
    // conic: not walking, and its last move taken.
    input  wire          cw_wr_i,
    input  wire [2:0]    cw_sel_i,
    input  wire [31:0]   cw_data_i,
    input  wire          cw_start_i,
    input  wire          cw_cont_i,        // the walk continues the last one (docs/CORE.md)
    output wire          walker_free_o,

    // Pulse timers: ready for a step; the steps of this move event and the
    // direction each axis steps in.
    input  wire [N-1:0]  pulse_ready_i,
    output reg  [N-1:0]  step_o,
    output wire [N-1:0]  dir_o,

    output wire          running_o,
    output wire          torch_o,          // the torch output (a register)
    output wire          cur_valid_o,      // a segment is loaded
    output wire          fire_o,           // a move event now
    output wire          seg_done_o,       // the loaded segment's last move fires now
    output wire          stretch_o,        // a move is counted late now
    output wire          seg_active_o,     // a segment is under way and not ending now
    output reg           fault_o,          // underrun, or a conic's walk not ending on its last move
    output wire          fault_conic_o,    // the fault is the conic's (CONIC_END)
    output wire          lim_hit_o         // the run stops now: a limit toward which it moves is active
);

localparam integer AW = (W > 2) ? $clog2(W) : 1;
localparam integer RCW = 3 + 2 * N + ((CONIC == 0) ? 0 : 7);   // below the PTIMER fields
localparam integer RDW = RCW + ((PTIMER == 0) ? 0 : 60);

reg          running_q, running_d;       // reset
reg          cur_valid_q, cur_valid_d;   // reset: a segment is loaded for running
reg          cur_lane_q, cur_lane_d;     // reset
reg          ch_loaded_q, ch_loaded_d;   // reset: the timer holds a chunk
reg          late_q, late_d;             // reset: the pending move has been counted as stretched
reg          rp_valid_q, rp_valid_d;     // reset: the replay registers hold the next move
reg [N-1:0]  dir_q, dir_d;               // reset
reg [N-1:0]  moving_q, moving_d;         // reset: the loaded segment's moving axes
reg          cur_end_q, cur_end_d;
reg          out_q, out_d;               // reset: the out bit of the segment last loaded
reg          torch_q, torch_d;           // reset: the torch pin
reg [31:0]   delay_q, delay_d;
reg [15:0]   left_q, left_d;
reg [31:0]   tinc_q, tinc_d;             // the running increment (signed)
reg [15:0]   tadd2_q, tadd2_d;
reg [31:0]   elapsed_q, elapsed_d;       // scaled time since the last move event
reg [15:0]   ph_q;                       // reset: the fraction of scaled time (Q0.16)
reg [1:0]    inc_q;                      // reset: what the last clock added to elapsed
reg          tlast_q, tlast_d;           // the timer's chunk is its segment's last
reg          due_q, due_d;               // reset: ch_loaded_q && elapsed_q >= delay_q
reg          cur_conic_q, cur_conic_d;   // the loaded segment is a conic, its plane axes:
reg [2:0]    cur_au_q, cur_au_d, cur_av_q, cur_av_d;
// PTIMER: the loaded segment's moves still to fire and its length per move, the
// phase timer's fraction of half clocks of scaled time.
reg [33:0]   mleft_q, mleft_d;
reg [31:0]   cur_len_q, cur_len_d;
reg [16:0]   pa_q;                       // reset

genvar ga;

// ---------------------------------------------------------------- banks and replay
// Axis a's bank holds lane l's pattern at {l, address}.
reg            bank_re;
reg  [AW-1:0]  rp_next [0:N-1];          // the address each axis reads next
reg            rp_lane;                  // and the lane
reg  [AW-1:0]  rp_ptr_q [0:N-1];         // the address of the move in the replay register
reg  [AW-1:0]  lm1_q [0:15];             // lane l, axis a: pattern length - 1 at {l, a}
wire [N-1:0]   lane_move;                // the replay registers: the next move's bits

generate
    for (ga = 0; ga < N; ga = ga + 1) begin : g_bank
        localparam [2:0] AX = ga;
        reg bank [0:2*(1<<AW)-1];
        reg rbit_q;
        always @(posedge clk) begin
            if (bank_we_i && bank_axis_i == AX) bank[{bank_lane_i, bank_waddr_i}] <= bank_wbit_i;
            if (bank_re) rbit_q <= bank[{rp_lane, rp_next[ga]}];
        end
        assign lane_move[ga] = rbit_q;
    end
endgenerate

// ---------------------------------------------------------------- the conic walker
wire       wk_valid, wk_end, wk_busy;
wire [1:0] wk_dx, wk_dy;
wire [31:0] wk_len;                      // PTIMER: the presented conic move's length
wire       wk_ready;                     // a conic move fires now
generate
    if (CONIC != 0) begin : g_walker
        cp_conic_serial #(.QW(16), .IW(CIW), .XW(24), .LEN(PTIMER)) u_walker (
            .clk(clk), .rst(rst), .clear_i(flush_i),
            .wr_i(cw_wr_i), .wr_sel_i(cw_sel_i), .wr_data_i(cw_data_i), .start_i(cw_start_i), .cont_i(cw_cont_i),
            .busy_o(wk_busy), .move_valid_o(wk_valid), .move_ready_i(wk_ready),
            .move_dx_o(wk_dx), .move_dy_o(wk_dy), .move_end_o(wk_end),
            .len_k_i(cur_len_q), .len_go_i(cur_valid_q && cur_conic_q), .len_o(wk_len));
    end else begin : g_no_walker
        assign wk_valid = 1'b0;
        assign wk_end   = 1'b0;
        assign wk_busy  = 1'b0;
        assign wk_dx    = 2'b00;
        assign wk_dy    = 2'b00;
        assign wk_len   = 32'd0;
        localparam [31:0] CIW_WORD = CIW;
        wire unused_walker = &{1'b0, cw_wr_i, cw_sel_i, cw_data_i, cw_start_i, cw_cont_i, wk_ready, CIW_WORD};
    end
endgenerate
assign walker_free_o = !wk_busy && !wk_valid;

// ---------------------------------------------------------------- the phase timer (PTIMER)
// Half clocks of scaled time: the fraction pa_q takes scale_i (at most 2) each clock
// and the timer advances on its carry. Its words come from the chunk queue while its
// buffer is free. The length of the move pending after a fire is owed to it and
// handed the clock after (so that nothing of a fire's clock reaches the timer's
// subtraction but the fire itself): the loaded segment's, a line's L (cur_len_q) or,
// with a conic loaded (pt_walk), the walker's (the length rule's) once it presents
// the move (wk_valid). So a move never fires in the clock after another (the host
// plans none that close: card::plan_phase_timer_job).
wire        pt_due, pt_ready, pt_starved;
wire [17:0] pa_scale = (FEED != 0) ? scale_i : 18'h10000;
wire [17:0] pa_sum   = {1'b0, pa_q} + pa_scale;
wire        pt_adv   = running_q && pa_sum[17];
wire        pt_wr    = ch_valid_i && pt_ready;
wire        pt_walk  = CONIC != 0 && cur_valid_q && cur_conic_q;
wire [31:0] pt_len   = pt_walk ? wk_len : cur_len_q;
wire        pt_len_valid = !fire_o && (pt_walk ? wk_valid : cur_valid_q);
generate
    if (PTIMER != 0) begin : g_ptimer
        wire       pt_active;
        wire [3:0] pt_kind;
        cp_ptimer u_ptimer (
            .clk(clk), .rst(rst), .clear_i(flush_i), .adv_i(pt_adv),
            .wr_i(pt_wr), .sel_i(ch_head_i[34:32]), .data_i(ch_head_i[31:0]),
            .fire_i(fire_o), .len_i({pt_len, 30'd0}), .len_valid_i(pt_len_valid),
            .due_o(pt_due), .active_o(pt_active), .ready_o(pt_ready), .starved_o(pt_starved), .kind_o(pt_kind));
        wire unused_pt = &{1'b0, pt_active, pt_kind};
    end else begin : g_no_ptimer
        assign pt_due     = 1'b0;
        assign pt_ready   = 1'b0;
        assign pt_starved = 1'b0;
        wire unused_pt = &{1'b0, pt_adv, pt_wr, pt_len, pt_len_valid};
    end
endgenerate

// The plane axes' steps and directions in the presented move (none outside a conic).
wire          conic_on = CONIC != 0 && cur_conic_q;
wire [N-1:0]  u_bit = {{(N-1){1'b0}}, 1'b1} << cur_au_q;
wire [N-1:0]  v_bit = {{(N-1){1'b0}}, 1'b1} << cur_av_q;
wire [N-1:0]  plane_step = (conic_on && wk_valid) ? ((wk_dx[0] ? u_bit : {N{1'b0}}) | (wk_dy[0] ? v_bit : {N{1'b0}}))
                                                  : {N{1'b0}};
// Positive: 01; negative: 11. A plane axis that steps shows the move's direction.
wire [N-1:0]  plane_dir = (wk_dx[1] ? {N{1'b0}} : u_bit) | (wk_dy[1] ? {N{1'b0}} : v_bit);
wire [N-1:0]  move_steps = lane_move | plane_step;
wire          seg_last = (PTIMER != 0) ? mleft_q == 34'd1 : (left_q == 16'd1 && tlast_q);
// A conic move's end mark must agree with the segment's last move.
wire          conic_ok = !conic_on || (wk_valid && wk_end == seg_last);

// ---------------------------------------------------------------- the decisions
// A move fires when it is due, the replay registers hold it and every axis that
// steps in it is ready; E-stop and abort stop it in the same cycle. A move is
// counted late once: in the first cycle it is due and does not fire, or when it
// fires after its time without having waited due (its chunk came late).
// due is ch_loaded_q && elapsed_q >= delay_q, registered: its next value is compared
// beside the fire decision (below), not after it.
wire due = (PTIMER != 0) ? pt_due : due_q;
// PTIMER: the timer ran out of phases while the pending move is not due: an underrun.
wire pt_stall = PTIMER != 0 && running_q && cur_valid_q && pt_starved && !pt_due;
// A limit hit: the segment under way moves an axis toward its active limit (a
// plane axis of a conic: the presented move steps it toward it). The run stops in
// this cycle as with STOP, and cp_status latches LIMIT.
wire [N-1:0] toward = (moving_q & ((dir_q & lim_max_i) | (~dir_q & lim_min_i))) |
                      (plane_step & ((plane_dir & lim_max_i) | (~plane_dir & lim_min_i)));
assign lim_hit_o = running_q && cur_valid_q && |toward;
wire halt = stop_i || lim_hit_o;
assign fire_o = running_q && cur_valid_q && !estop_i && !abort_i && !halt && due && rp_valid_q && conic_ok &&
                &(pulse_ready_i | ~move_steps);
assign wk_ready = fire_o && conic_on;
assign fault_conic_o = running_q && cur_valid_q && !estop_i && !abort_i && !halt && due && rp_valid_q &&
                       conic_on && wk_valid && wk_end != seg_last;
assign stretch_o = running_q && due && !late_q && !estop_i && !abort_i && !halt &&
                   (!fire_o || !on_time);
assign seg_done_o = fire_o && seg_last;

// ---------------------------------------------------------------- next state
integer i;
// A run queue word with the conic fields (and a spare bit; see cp_build).
localparam integer RFW = 10 + 2 * N;
reg [RFW:0] run_wide;
wire unused_run = &{1'b0, run_wide[RFW]};
reg [59:0]  run_pt;   // the PTIMER fields (0 in other builds)
wire [RCW+60:0] run_head_x = {{(RCW+61-RDW){1'b0}}, run_head_i};
wire unused_head_x = &{1'b0, run_head_x[RCW+60]};

// The timer's next values, whatever fires: the count one on (saturating), the next
// interval of the running chunk, the head chunk's first.
// Scaled time: this clock's increment inc (the fraction's carry).
wire [17:0] ph_sum      = {2'b00, ph_q} + scale_i;
wire [1:0]  inc         = (FEED != 0) ? ph_sum[17:16] : 2'd1;
wire [32:0] elapsed_sum = {1'b0, elapsed_q} + {31'd0, inc};
wire [31:0] elapsed_inc = elapsed_sum[32] ? 32'hFFFF_FFFF : elapsed_sum[31:0];
wire [31:0] inc_word    = {30'd0, inc};
wire [31:0] delay_sum   = delay_q + tinc_q;
wire [31:0] head_delay  = ch_head_i[31:0];
wire        start_now   = start_i && !fault_i && !running_q;  // exclusive with fire_o
wire        ge_inc_delay = elapsed_inc >= delay_q;
wire        ge_inc_head  = elapsed_inc >= head_delay;
wire        le1_delay    = delay_q <= inc_word;
wire        le1_head     = head_delay <= inc_word;
wire        le1_sum      = delay_sum <= inc_word;
// The pending move is on time when it fires in the clock its scaled time reached it:
// elapsed passed delay by less than the last clock's increment (at scale 1: equal).
wire [31:0] past_due     = elapsed_q - delay_q;
// (PTIMER: a move fires in the clock it falls due or is counted late while it waits.)
wire        on_time      = PTIMER != 0 || past_due < {30'd0, inc_q};

always @* begin
    running_d = running_q;  cur_valid_d = cur_valid_q;  cur_lane_d = cur_lane_q;
    ch_loaded_d = ch_loaded_q;  late_d = late_q;  rp_valid_d = rp_valid_q;  dir_d = dir_q;
    moving_d = moving_q;
    cur_end_d = cur_end_q;  out_d = out_q;  delay_d = delay_q;  left_d = left_q;  tinc_d = tinc_q;
    tadd2_d = tadd2_q;  tlast_d = tlast_q;
    cur_conic_d = cur_conic_q;  cur_au_d = cur_au_q;  cur_av_d = cur_av_q;
    mleft_d = mleft_q;  cur_len_d = cur_len_q;
    elapsed_d = elapsed_inc;
    ch_pop_o = 1'b0;  run_pop_o = 1'b0;  step_o = {N{1'b0}};  fault_o = fault_conic_o;
    run_wide = {(RFW+1){1'b0}};
    run_pt   = 60'd0;
    bank_re = 1'b0;  rp_lane = cur_lane_q;
    for (i = 0; i < N; i = i + 1) rp_next[i] = rp_ptr_q[i];

    if (stretch_o) late_d = 1'b1;
    if (fire_o) late_d = 1'b0;

    // The timer takes the chunk queue's head when it holds none, and when the move
    // that fires is its chunk's last (never both: a move fires only with a chunk).
    // (PTIMER: the phase timer takes the queue's words instead.)
    if (PTIMER != 0) ch_pop_o = pt_wr;
    if (PTIMER == 0 && ch_valid_i && (!ch_loaded_q || (fire_o && left_q == 16'd1))) begin
        ch_pop_o    = 1'b1;
        ch_loaded_d = 1'b1;
        delay_d     = ch_head_i[31:0];
        tinc_d      = {{16{ch_head_i[47]}}, ch_head_i[47:32]};
        left_d      = ch_head_i[63:48];
        tadd2_d     = ch_head_i[79:64];
        tlast_d     = ch_head_i[80];
    end
    if (fire_o) begin
        step_o    = move_steps;
        elapsed_d = inc_word;
        mleft_d   = mleft_q - 1'b1;
        // A plane axis that steps keeps the direction it stepped in.
        for (i = 0; i < N; i = i + 1)
            if (plane_step[i]) dir_d[i] = plane_dir[i];
        if (left_q != 16'd1) begin
            left_d  = left_q - 1'b1;
            delay_d = delay_sum;
            tinc_d  = tinc_q + {{16{tadd2_q[15]}}, tadd2_q};
        end else if (!ch_valid_i) begin
            ch_loaded_d = 1'b0;
        end
        // The replay registers fetch the next move of the running lane's patterns.
        if (!seg_done_o) begin
            bank_re = 1'b1;
            for (i = 0; i < N; i = i + 1)
                rp_next[i] = (rp_ptr_q[i] == lm1_q[{cur_lane_q, i[2:0]}]) ? {AW{1'b0}} : rp_ptr_q[i] + 1'b1;
        end
    end
    // A conic move whose end mark disagrees: the run stops before it, the segment is
    // dropped (the latched fault then flushes the rest).
    if (fault_conic_o) begin
        running_d   = 1'b0;
        cur_valid_d = 1'b0;
        rp_valid_d  = 1'b0;
    end
    if (pt_stall) begin
        running_d = 1'b0;
        fault_o   = 1'b1;
    end
    if (seg_done_o) begin
        cur_valid_d = 1'b0;
        rp_valid_d  = 1'b0;
        if (cur_end_q) begin
            running_d = 1'b0;
        end else if (run_level_i == 2'd0 && segq_empty_i && !build_busy_i && !fault_i) begin
            running_d = 1'b0;
            fault_o   = 1'b1;
        end
    end
    // Load the next built segment; its moving axes take their directions.
    if ((!cur_valid_q || seg_done_o) && run_valid_i && !fault_i) begin
        run_pop_o   = 1'b1;
        cur_valid_d = 1'b1;
        cur_lane_d  = run_head_i[1+2*N];
        cur_end_d   = run_head_i[2*N];
        out_d       = run_head_i[2+2*N];
        run_wide    = {{(RFW+1-RCW){1'b0}}, run_head_i[RCW-1:0]};
        cur_conic_d = CONIC != 0 && run_wide[RFW-1];
        cur_au_d    = run_wide[RFW-2 -: 3];
        cur_av_d    = run_wide[RFW-5 -: 3];
        moving_d    = run_head_i[2*N-1:N];
        // (PTIMER: the segment's moves U*2^k and its length per move.)
        run_pt      = run_head_x[RCW +: 60];
        mleft_d     = {10'd0, run_pt[23:0]} << run_pt[27:24];
        cur_len_d   = run_pt[59:28];
        for (i = 0; i < N; i = i + 1)
            if (run_head_i[N + i]) dir_d[i] = run_head_i[i];
        // The replay registers fetch each pattern's first move.
        bank_re    = 1'b1;
        rp_lane    = run_head_i[1+2*N];
        rp_valid_d = 1'b1;
        for (i = 0; i < N; i = i + 1) rp_next[i] = {AW{1'b0}};
    end
    if (start_now) begin
        running_d = 1'b1;
        elapsed_d = inc_word;
    end
    // STOP: the run is off; what is loaded and queued stays (a START goes on, the
    // pending move timed from it). A limit hit: the same, then its fault's flush.
    if (halt) running_d = 1'b0;
    if (flush_i) begin
        running_d   = 1'b0;
        cur_valid_d = 1'b0;
        ch_loaded_d = 1'b0;
        cur_lane_d  = 1'b0;
        late_d      = 1'b0;
        rp_valid_d  = 1'b0;
        out_d       = 1'b0;
    end
    // The torch: on while the run is on and the segment last loaded says so; off from
    // the cycle after an E-stop or an abort is seen (their flush comes in that cycle).
    torch_d = running_d && out_d;
    // due_d = ch_loaded_d && elapsed_d >= delay_d, case by case. A move that fires
    // sets elapsed to this clock's increment and either steps to its chunk's next
    // interval or takes the head chunk (or none); otherwise elapsed counts on (or
    // starts at the increment) against the
    // running interval or the head chunk taken now.
    if (flush_i)
        due_d = 1'b0;
    else if (fire_o)
        due_d = (left_q != 16'd1) ? le1_sum : (ch_valid_i && le1_head);
    else if (ch_valid_i && !ch_loaded_q)
        due_d = start_now ? le1_head : ge_inc_head;
    else
        due_d = ch_loaded_q && (start_now ? le1_delay : ge_inc_delay);
end

// ---------------------------------------------------------------- registers
integer a;
always @(posedge clk) begin
    if (rst) begin
        running_q   <= 1'b0;
        cur_valid_q <= 1'b0;
        cur_lane_q  <= 1'b0;
        ch_loaded_q <= 1'b0;
        late_q      <= 1'b0;
        rp_valid_q  <= 1'b0;
        dir_q       <= {N{1'b0}};
        moving_q    <= {N{1'b0}};
        due_q       <= 1'b0;
        cur_conic_q <= 1'b0;
        out_q       <= 1'b0;
        torch_q     <= 1'b0;
        ph_q        <= 16'd0;
        pa_q        <= 17'd0;
        inc_q       <= 2'd1;
    end else begin
        running_q   <= running_d;
        cur_valid_q <= cur_valid_d;
        cur_lane_q  <= cur_lane_d;
        ch_loaded_q <= ch_loaded_d;
        late_q      <= late_d;
        rp_valid_q  <= rp_valid_d;
        dir_q       <= dir_d;
        moving_q    <= moving_d;
        due_q       <= due_d;
        cur_conic_q <= cur_conic_d;
        out_q       <= out_d;
        torch_q     <= torch_d;
        ph_q        <= (FEED != 0) ? ph_sum[15:0] : 16'd0;
        pa_q        <= (PTIMER == 0 || start_now) ? 17'd0 : pa_sum[16:0];
        inc_q       <= inc;
    end
    cur_au_q <= cur_au_d;  cur_av_q <= cur_av_d;
    cur_end_q <= cur_end_d;  delay_q <= delay_d;  left_q <= left_d;  tinc_q <= tinc_d;
    tadd2_q <= tadd2_d;  tlast_q <= tlast_d;  elapsed_q <= elapsed_d;
    mleft_q <= mleft_d;  cur_len_q <= cur_len_d;
    for (a = 0; a < N; a = a + 1) if (bank_re) rp_ptr_q[a] <= rp_next[a];
    // Only an axis that exists (the entries of others are never read: none are kept).
    if (len_we_i && {29'd0, bank_axis_i} < N) lm1_q[{bank_lane_i, bank_axis_i}] <= len_m1_i;
end

// ---------------------------------------------------------------- outputs
// A plane axis shows the presented conic move's direction before the move fires,
// so that its pulse timer keeps DIR setup (its readiness waits for the pin).
assign dir_o        = (dir_q & ~plane_step) | (plane_dir & plane_step);
assign running_o    = running_q;
assign torch_o      = torch_q;
assign cur_valid_o  = cur_valid_q;
assign seg_active_o = running_q && cur_valid_q && !seg_done_o;

endmodule

`resetall
