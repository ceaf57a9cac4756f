// SPDX-License-Identifier: MIT
// cp_ptimer — the phase timer: moves timed by phases of constant jerk (issue 13,
// toward the compact wire; cp_run's timer in a PTIMER build of cp_core). The
// host's side is host/plan/phases.h, whose arithmetic this is, clock by clock:
//
//   every clock of a jerk phase (adv_i):  p += step; the pending move is due
//       while p >= its length * 2^S, kept as r = p - that length * 2^S (due: r's
//       sign clear); a fire (fire_i) takes off the next move's length: len_i is
//       the length of the move pending after this clock (in a clock that fires,
//       the next one's), when len_valid_i says it is known; until it is (the
//       next segment not loaded yet, a conic move's length still being divided)
//       the length is owed, taken off in the first clock that has it, and no
//       move is due
//   at the end of each tick (2^S clocks from the phase's start):
//       step += 2H + 6u, H += 3u
//       summed bit-serially over the tick's clocks (below), the same bits
//
// The step S, H and u are the cubic V m + H m^2 + u m^3 over ticks as the timer
// needs it (S = V + H + u: the distance of the tick; H half the acceleration, u a
// sixth of the jerk; no V is kept), so a phase changes u without p, S or H
// jumping (a new u changes the step from the phase's second tick on). A phase
// (W0 = {load S and H, rest, timed, load r, 4'b0, ticks[23:0]}) holds u for
// `ticks` ticks (0: 1), then the next phase loads at once (none: the timer stops
// and says `starved`). It carries r, S and H on, or starts from rest (p, S, H =
// 0), and/or loads S and H (the host's correction back to its plan), and/or r,
// from the buffer, in that order; a timed phase is one move, due `ticks` clocks
// after the phase's start, p, S and H frozen until then and p = 0 after (r = 0
// until the timed move fires and takes off the next one's length; the last move
// of a stop, which no phase times within 1 us). A move that came due in the last
// clock of the phase before it (r's sign clear in the timed phase's first) is due
// there too: r is frozen, so nothing else is.
//
// The next phase is written word by word into a buffer (sel 1: u; 2, 3: r's top
// 64 bits, low word first; 4, 5: S; 6, 7: H) and committed by W0 (sel 0) while
// ready_o; a write while not ready changes nothing.
//
// Model twin model/cp_ptimer.*, bench tb/core/test_ptimer.cpp.
`resetall
`timescale 1ns / 1ps
`default_nettype none

module cp_ptimer #(
    parameter integer S  = 6,     // a tick is 2^S clocks
    parameter integer F  = 60,    // fractional bits of r, S, H and u
    parameter integer VW = 56,    // the step S (signed)
    parameter integer HW = 40,    // H (signed)
    parameter integer UW = 24,    // u (signed)
    parameter integer LW = 62     // a move's length (unsigned, 2^-F units)
    // (32 < HW <= VW <= 64, VW <= 2^S, UW <= 32, UW <= HW, LW <= F + 2, F + S + 3 > 64)
) (
    input  wire          clk,
    input  wire          rst,
    input  wire          clear_i,       // stop and empty (FLUSH, E-stop)
    input  wire          adv_i,         // this clock counts
    input  wire          wr_i,
    input  wire [2:0]    sel_i,
    input  wire [31:0]   data_i,
    input  wire          fire_i,        // the due move fires now
    input  wire [LW-1:0] len_i,         // the pending move's length after this clock
    input  wire          len_valid_i,   // ... is known (else it is owed)
    output wire          due_o,
    output wire          active_o,
    output wire          ready_o,
    output wire          starved_o,
    output wire [3:0]    kind_o         // the running phase's {load S and H, rest, timed, load r}
);

localparam integer RW = F + S + 3;      // r (signed)
localparam integer TW = 24;             // ticks

reg           active_q, timed_q, tdue_q, starved_q, nvalid_q;
reg           bdue_q;         // a move came due in the last clock of the phase before, whose r the load replaced
reg           owe_q;          // the pending move's length is still to be taken off r (no move due)
reg  [3:0]    kind_q, nkind_q;
reg  [TW-1:0] tleft_q, nticks_q;
reg  [S-1:0]  tcnt_q;
reg  signed [UW-1:0] u_q;
reg  signed [VW-1:0] step_q;     // the step S
reg  signed [HW-1:0] h_q;
reg  [RW-1:0] r_q;            // p minus the pending move's length (times 2^S)
reg  [UW-1:0] nu_q;
reg  [63:0]   np_q;           // r's top 64 bits (a reload)
reg  [VW-1:0] ns_q;           // S (an adjust or a reload)
reg  [HW-1:0] nh_q;
reg  [VW-1:0] sn_q;           // the step again, rotating out and the next shifting in
reg  [3:0]    cy_q;           // the serial sums' carries
reg           up_q, hp_q, tp_q;   // u's, H's and 3u's bit before (for 2u, 2H, 6u)
reg           hs_q;           // the tick's H's sign (its bits past HW)

wire [RW-1:0] thresh = {{(RW-LW-S){1'b0}}, len_i, {S{1'b0}}};
// Due: the timed move at its phase's end; a move that came due in the last clock of a
// jerk phase whose r the next phase replaced (rest, load r: bdue_q); or r's sign clear
// (not while owed) — also in a timed phase, whose r is frozen: it is clear there only
// when the move before the timed one came due in the jerk phase's last clock. The
// host's arithmetic fires every such move where it comes due (plan::simulate_phases),
// the card in the clock after, as every other.
wire          due = tdue_q || bdue_q || (!owe_q && !r_q[RW-1]);
assign due_o     = due;
assign active_o  = active_q;
assign ready_o   = !nvalid_q;
assign starved_o = starved_q;
assign kind_o    = kind_q;

// The tick's end: the next step and H, computed bit-serially over the tick (bit
// i at its clock i, least significant first; VW <= 2^S): the step rotates through
// sn_q, H and u through h_q and u_q, which hold the tick's values at its start
// and (sn_q, h_q) the next tick's at its end, when sn_q moves to step_q. So at
// the tick's end every register holds what the parallel sums step += 2H + 6u,
// H += 3u would give.
localparam integer HW1 = HW - 1;
localparam [S:0] BU = UW[S:0], BH = HW[S:0], BV = VW[S:0], BH1 = HW1[S:0];
wire [S:0]   bi    = {1'b0, tcnt_q};               // the bit of this clock
wire         b0    = tcnt_q == {S{1'b0}};
wire         u_b   = (bi < BU) ? u_q[0] : u_q[UW-1];   // u, sign-extended (u_q is whole again at UW)
wire         h_b   = (bi < BH) ? h_q[0] : hs_q;        // the tick's H, sign-extended
wire         u2_b  = b0 ? 1'b0 : up_q;                 // 2u: u's bit before
wire         h2_b  = b0 ? 1'b0 : hp_q;                 // 2H
wire [3:0]   cy    = b0 ? 4'd0 : cy_q;                 // the four sums' carries
// t = 3u = u + 2u; H' = H + t; a = S + 2H; S' = a + 2t
wire t_b  = u_b ^ u2_b ^ cy[0];
wire t2_b = b0 ? 1'b0 : tp_q;                          // 6u = 2t
wire hu_b = h_b ^ t_b ^ cy[1];
wire a_b  = sn_q[0] ^ h2_b ^ cy[2];
wire su_b = a_b ^ t2_b ^ cy[3];
wire [3:0] cy_n = {(a_b & t2_b) | (a_b & cy[3]) | (t2_b & cy[3]),
                   (sn_q[0] & h2_b) | (sn_q[0] & cy[2]) | (h2_b & cy[2]),
                   (h_b & t_b) | (h_b & cy[1]) | (t_b & cy[1]),
                   (u_b & u2_b) | (u_b & cy[0]) | (u2_b & cy[0])};

wire          tick_end  = tcnt_q == {S{1'b1}};
wire          running   = active_q && adv_i;
wire          phase_end = running && (timed_q ? (tleft_q == {{(TW-1){1'b0}}, 1'b1})
                                               : (tick_end && tleft_q == {{(TW-1){1'b0}}, 1'b1}));
wire          load      = phase_end || (!active_q && nvalid_q);

// The loaded phase's step and H: sn_q and h_q are the step and H carried on (at
// a tick's end the next tick's, shifted in).
wire signed [VW-1:0] step_ld = nkind_q[3] ? ns_q : nkind_q[2] ? {VW{1'b0}} : sn_q;
wire signed [HW-1:0] h_ld    = nkind_q[3] ? nh_q : nkind_q[2] ? {HW{1'b0}} : h_q;

// r: this clock's fire (or a length owed: after a start from rest, p = 0, or a
// fire whose next length was not known) takes off the pending move's length if
// len_valid_i, else owes it; then the step.
wire          tdue_n  = (tdue_q && !(fire_i && due)) || (running && timed_q && phase_end);
// (A bdue_q move's fire takes nothing off: the replaced r is already the next move's.)
wire          take    = (fire_i && due && !bdue_q) || owe_q;
wire [RW-1:0] step_r  = {{(RW-VW){step_q[VW-1]}}, step_q};
wire [RW-1:0] r_fired = (take && len_valid_i) ? r_q - thresh : r_q;
wire [RW-1:0] r_run   = (running && !timed_q) ? r_fired + step_r
                      : (running && timed_q && phase_end) ? {RW{1'b0}} : r_fired;
// This clock ends a jerk phase with its pending move due (r's sign clear, nothing owed
// after it) and the next phase replaces r.
wire          b_cross = running && !timed_q && phase_end && nvalid_q && (nkind_q[0] || nkind_q[2]) &&
                        !r_run[RW-1] && !(take && !len_valid_i);

always @(posedge clk) begin
    if (rst || clear_i) begin
        active_q  <= 1'b0;
        timed_q   <= 1'b0;
        tdue_q    <= 1'b0;
        bdue_q    <= 1'b0;
        starved_q <= 1'b0;
        nvalid_q  <= 1'b0;
        kind_q    <= 4'd0;
        nkind_q   <= 4'd0;
        tleft_q   <= {TW{1'b0}};
        nticks_q  <= {TW{1'b0}};
        tcnt_q    <= {S{1'b0}};
        u_q       <= {UW{1'b0}};
        h_q       <= {HW{1'b0}};
        step_q    <= {VW{1'b0}};
        r_q       <= {RW{1'b1}};   // -1: nothing due until a phase from rest or loading r
        owe_q     <= 1'b0;
        nu_q      <= {UW{1'b0}};
        np_q      <= 64'd0;
        ns_q      <= {VW{1'b0}};
        nh_q      <= {HW{1'b0}};
        sn_q      <= {VW{1'b0}};
        cy_q      <= 4'd0;
        up_q      <= 1'b0;
        hp_q      <= 1'b0;
        tp_q      <= 1'b0;
        hs_q      <= 1'b0;
    end else begin
        if (wr_i && !nvalid_q) begin
            case (sel_i)
                3'd0: begin
                    nkind_q  <= data_i[31:28];
                    nticks_q <= data_i[TW-1:0];
                    nvalid_q <= 1'b1;
                end
                3'd1: nu_q <= data_i[UW-1:0];
                3'd2: np_q[31:0]  <= data_i;
                3'd3: np_q[63:32] <= data_i;
                3'd4: ns_q[31:0]  <= data_i;
                3'd5: ns_q[VW-1:32] <= data_i[VW-33:0];
                3'd6: nh_q[31:0]  <= data_i;
                default: nh_q[HW-1:32] <= data_i[HW-33:0];
            endcase
        end
        if (fire_i && tdue_q) tdue_q <= 1'b0;
        if (fire_i && bdue_q) bdue_q <= 1'b0;
        if (b_cross) bdue_q <= 1'b1;
        if (running && timed_q && phase_end) tdue_q <= 1'b1;
        if (running && timed_q && !phase_end) tleft_q <= tleft_q - 1'b1;
        if (running && !timed_q) begin
            tcnt_q <= tcnt_q + 1'b1;
            cy_q   <= cy_n;
            up_q   <= u_b;
            hp_q   <= h_b;
            tp_q   <= t_b;
            if (bi == BH1) hs_q <= h_b;
            if (bi < BV) sn_q <= {su_b, sn_q[VW-1:1]};
            if (bi < BH) h_q <= {hu_b, h_q[HW-1:1]};
            if (bi < BU) u_q <= {u_q[0], u_q[UW-1:1]};
            if (tick_end) begin
                step_q <= sn_q;
                if (!phase_end) tleft_q <= tleft_q - 1'b1;
            end
        end
        r_q   <= r_run;
        owe_q <= take && !len_valid_i;
        // A timed move's end: p = 0, whatever was owed (its fire takes off the next's).
        if (running && timed_q && phase_end) owe_q <= 1'b0;
        if (load) begin
            if (nvalid_q) begin
                nvalid_q  <= 1'b0;
                active_q  <= 1'b1;
                starved_q <= 1'b0;
                kind_q    <= nkind_q;
                timed_q   <= nkind_q[1];
                u_q       <= nu_q;
                tleft_q   <= (nticks_q == {TW{1'b0}}) ? {{(TW-1){1'b0}}, 1'b1} : nticks_q;
                tcnt_q    <= {S{1'b0}};
                h_q       <= h_ld;
                step_q    <= step_ld;
                sn_q      <= step_ld;
                // p = 0: r = 0, the pending move's length owed, taken off from the
                // next clock (a timed move still to fire takes off the next one's
                // itself); a loaded r has it taken off.
                if (nkind_q[2]) begin
                    r_q   <= {RW{1'b0}};
                    owe_q <= !tdue_n;
                end
                if (nkind_q[0]) begin
                    r_q   <= {np_q, {(RW-64){1'b0}}};
                    owe_q <= 1'b0;
                end
            end else begin
                active_q  <= 1'b0;
                starved_q <= 1'b1;
            end
        end
    end
end

endmodule
`resetall
