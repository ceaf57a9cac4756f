// SPDX-License-Identifier: MIT
// plan/arc_fit.h: chains of G1 lines as arcs within planner.fit_arcs_mm. Each
// result is checked against the lines it replaced, by distances computed here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>

#include <fmt/format.h>

#include "plan/arc_fit.h"
#include "plan/gcode.h"
#include "plan/machine.h"
#include "plan/nurbs.h"

using namespace cpstep::plan;

namespace {

constexpr double kPi = std::numbers::pi;

Job parse(const std::string& text) {
    auto j = parse_gcode(text, "fit.ngc");
    EXPECT_TRUE(j.ok()) << join(j.errors);
    return j.ok() ? *j.value : Job{};
}

// G1 lines through the points (x, y), the first reached by G0.
std::string polyline(const std::vector<std::pair<double, double>>& pts, const char* feed = "F600") {
    std::string g = fmt::format("G21 G90 G17\nG0 X{:.6f} Y{:.6f}\n{}\n", pts[0].first, pts[0].second, feed);
    for (std::size_t i = 1; i < pts.size(); ++i) g += fmt::format("G1 X{:.6f} Y{:.6f}\n", pts[i].first, pts[i].second);
    return g;
}

std::vector<std::pair<double, double>> arc_points(double cx, double cy, double r, double a0, double a1, int n,
                                                  double noise = 0, unsigned seed = 1) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-noise, noise);
    std::vector<std::pair<double, double>> p;
    for (int i = 0; i <= n; ++i) {
        const double a = a0 + (a1 - a0) * i / n, rr = r + (i == 0 || i == n ? 0 : u(rng));
        p.push_back({cx + rr * std::cos(a), cy + rr * std::sin(a)});
    }
    return p;
}

// The distance of (x, y) from block b's path in XY: a line segment or an arc.
double distance_to(const MotionBlock& b, double x, double y) {
    if (b.kind == MotionKind::arc_cw || b.kind == MotionKind::arc_ccw) {
        const double r = std::hypot(b.start[0] - b.center_x, b.start[1] - b.center_y);
        const double a0 = std::atan2(b.start[1] - b.center_y, b.start[0] - b.center_x);
        const double a1 = std::atan2(b.end[1] - b.center_y, b.end[0] - b.center_x);
        const double a = std::atan2(y - b.center_y, x - b.center_x);
        // Within the arc's sweep (from a0 in its direction to a1)?
        auto ccw_from = [](double from, double to) { return std::fmod(std::fmod(to - from, 2 * kPi) + 2 * kPi, 2 * kPi); };
        const bool ccw = b.kind == MotionKind::arc_ccw;
        const double sweep = ccw ? ccw_from(a0, a1) : ccw_from(a1, a0);
        const double at = ccw ? ccw_from(a0, a) : ccw_from(a, a0);
        if (at <= sweep + 1e-12) return std::abs(std::hypot(x - b.center_x, y - b.center_y) - r);
        return std::min(std::hypot(x - b.start[0], y - b.start[1]), std::hypot(x - b.end[0], y - b.end[1]));
    }
    const double dx = b.end[0] - b.start[0], dy = b.end[1] - b.start[1];
    const double L2 = dx * dx + dy * dy;
    const double t = L2 > 0 ? std::clamp(((x - b.start[0]) * dx + (y - b.start[1]) * dy) / L2, 0.0, 1.0) : 0.0;
    return std::hypot(x - b.start[0] - t * dx, y - b.start[1] - t * dy);
}

// Every input vertex and the middle of every input line lie within tol of the
// output block that replaced them, the
// output starts and ends where the input does and keeps every end point of its
// blocks on an input vertex; the largest distance.
double check_within(const Job& in, const Job& out, double tol) {
    std::size_t k = 0;   // output block
    double worst = 0;
    for (const MotionBlock& b : in.blocks) {
        if (b.kind != MotionKind::linear) continue;
        while (k < out.blocks.size() && out.blocks[k].kind != MotionKind::linear &&
               out.blocks[k].kind != MotionKind::arc_cw && out.blocks[k].kind != MotionKind::arc_ccw)
            ++k;
        EXPECT_LT(k, out.blocks.size());
        if (k >= out.blocks.size()) return worst;
        const MotionBlock& o = out.blocks[k];
        const double d = distance_to(o, b.end[0], b.end[1]);
        EXPECT_LE(d, tol + 1e-9) << "vertex at line " << b.loc.line;
        // The line's middle too: the arc bows away from its chords.
        const double mid = distance_to(o, (b.start[0] + b.end[0]) / 2, (b.start[1] + b.end[1]) / 2);
        EXPECT_LE(mid, tol + 1e-9) << "middle of line " << b.loc.line;
        worst = std::max({worst, d, mid});
        if (b.end[0] == o.end[0] && b.end[1] == o.end[1]) ++k;   // the output block ends here
    }
    return worst;
}

}  // namespace

TEST(ArcFit, ChordsOfAnArcBecomeThatArc) {
    for (bool ccw : {true, false}) {
        SCOPED_TRACE(ccw ? "ccw" : "cw");
        const auto pts = ccw ? arc_points(20, 30, 10, 0.1, 0.1 + kPi / 2, 200)
                             : arc_points(20, 30, 10, 0.1 + kPi / 2, 0.1, 200);
        const Job in = parse(polyline(pts));
        ArcFitStats st;
        const Job out = fit_arcs(in, 0.002, &st);
        ASSERT_EQ(out.blocks.size(), 2u);   // G0, the arc
        const MotionBlock& a = out.blocks[1];
        EXPECT_EQ(a.kind, ccw ? MotionKind::arc_ccw : MotionKind::arc_cw);
        EXPECT_NEAR(a.center_x, 20, 1e-4);
        EXPECT_NEAR(a.center_y, 30, 1e-4);
        EXPECT_EQ(a.start, in.blocks[1].start);
        EXPECT_EQ(a.end, in.blocks.back().end);
        EXPECT_EQ(a.loc.line, in.blocks[1].loc.line);
        EXPECT_EQ(a.feed, in.blocks[1].feed);
        EXPECT_EQ(st.arcs, 1u);
        EXPECT_EQ(st.lines_in_arcs, 200u);
        EXPECT_LE(st.max_deviation_mm, 0.002);
        check_within(in, out, 0.002);
    }
}

TEST(ArcFit, NoisyChordsStayWithinTheTolerance) {
    // Vertices up to 0.4 tol off the circle: every one within tol of the result.
    for (unsigned seed = 1; seed <= 20; ++seed) {
        const double tol = 0.01;
        const auto pts = arc_points(0, 0, 5 + seed, 0, 1.5 * kPi, 300, 0.4 * tol, seed);
        const Job in = parse(polyline(pts));
        ArcFitStats st;
        const Job out = fit_arcs(in, tol, &st);
        EXPECT_GE(st.arcs, 1u);
        EXPECT_LE(out.blocks.size(), 6u) << seed;
        EXPECT_LE(check_within(in, out, tol), tol);
        EXPECT_LE(st.max_deviation_mm, tol);
    }
}

TEST(ArcFit, CollinearRunsBecomeOneLineAndCornersStay) {
    // Five lines along x (one 0.001 mm off), a corner, three along y.
    const Job in = parse(polyline({{1, 1}, {2, 1}, {3, 1.001}, {4, 1}, {5, 1}, {6, 1}, {6, 2}, {6, 3}, {6, 4}}));
    ArcFitStats st;
    const Job out = fit_arcs(in, 0.002, &st);
    ASSERT_EQ(out.blocks.size(), 3u);
    EXPECT_EQ(out.blocks[1].kind, MotionKind::linear);
    EXPECT_EQ(out.blocks[1].end[0], 6);
    EXPECT_EQ(out.blocks[2].end[1], 4);
    EXPECT_EQ(st.merged, 2u);
    EXPECT_EQ(st.lines_in_merged, 8u);
    EXPECT_EQ(st.arcs, 0u);
    check_within(in, out, 0.002);
    // A line that goes back along the run is not merged.
    const Job back = parse(polyline({{1, 1}, {3, 1}, {2, 1}, {4, 1}}));
    EXPECT_EQ(fit_arcs(back, 0.002).blocks.size(), 4u);
}

TEST(ArcFit, ZigzagsAndTooFewLinesStayLines) {
    // Alternate turns: no arc (and no line: the points are 0.05 mm off).
    std::vector<std::pair<double, double>> z;
    for (int i = 0; i <= 20; ++i) z.push_back({i * 1.0, i % 2 ? 0.05 : 0.0});
    const Job in = parse(polyline(z));
    EXPECT_EQ(fit_arcs(in, 0.002).blocks.size(), in.blocks.size());
    // Two chords of an arc: left alone (an arc needs at least three lines).
    const Job two = parse(polyline(arc_points(0, 0, 10, 0, 0.2, 2)));
    EXPECT_EQ(fit_arcs(two, 0.002).blocks.size(), two.blocks.size());
}

TEST(ArcFit, RunsBreakAtFeedZToolAndRapids) {
    const auto p = arc_points(0, 0, 10, 0, kPi / 2, 40);
    std::string g = "G21 G90 G17\nG0 X10 Y0\nF600\n";
    for (std::size_t i = 1; i < p.size(); ++i) {
        if (i == 10) g += "F300\n";                               // a new feed
        if (i == 20) g += "G1 Z-0.1\n";                           // Z moves: not in a run
        if (i == 30) g += fmt::format("G0 X{:.6f} Y{:.6f}\n", p[i].first, p[i].second);  // a rapid
        else g += fmt::format("G1 X{:.6f} Y{:.6f}\n", p[i].first, p[i].second);
    }
    const Job in = parse(g);
    ArcFitStats st;
    const Job out = fit_arcs(in, 0.002, &st);
    // Runs: lines 1-9 (F600), 10-19 (F300), 20-29 after the Z move, 31-40 after the
    // rapid: four arcs; the Z move and the rapid stay.
    EXPECT_EQ(st.arcs, 4u);
    int z = 0, rapids = 0;
    for (const MotionBlock& b : out.blocks) {
        z += b.kind == MotionKind::linear && b.start[2] != b.end[2];
        rapids += b.kind == MotionKind::rapid;
    }
    EXPECT_EQ(z, 1);
    EXPECT_EQ(rapids, 2);
    check_within(in, out, 0.002);
}

TEST(ArcFit, AFullCircleIsCutBelowItsWholeTurn) {
    const Job in = parse(polyline(arc_points(0, 0, 10, 0, 2 * kPi, 360)));
    ArcFitStats st;
    const Job out = fit_arcs(in, 0.002, &st);
    EXPECT_EQ(st.arcs, 2u);
    EXPECT_EQ(st.lines_in_arcs, 360u);
    check_within(in, out, 0.002);
}

TEST(ArcFit, TheDenseSpiralWithinTolerance) {
    const auto j = load_gcode(CPSTEP_EXAMPLES_DIR "/jobs/dense.ngc", GcodeOptions{});
    ASSERT_TRUE(j.ok()) << join(j.errors);
    ArcFitStats st;
    const Job out = fit_arcs(*j.value, 0.002, &st);
    EXPECT_EQ(st.lines_in_arcs + st.lines_in_merged, 12000u);
    EXPECT_LT(out.blocks.size(), 400u);   // from 12,005
    EXPECT_LE(check_within(*j.value, out, 0.002), 0.002);
}

TEST(ArcFit, MachineFileKey) {
    // seed002.toml with the key in its [planner] table; a value out of range is
    // refused at its line.
    std::ifstream f(CPSTEP_EXAMPLES_DIR "/machines/seed002.toml");
    const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    const std::size_t at = text.find("[planner]\n");
    ASSERT_NE(at, std::string::npos);
    const auto with = [&](const std::string& v) {
        return text.substr(0, at + 10) + "fit_arcs_mm = " + v + "\n" + text.substr(at + 10);
    };
    const int line = 2 + static_cast<int>(std::count(text.begin(), text.begin() + std::ptrdiff_t(at), '\n'));
    auto ok = parse_machine(with("0.005"), "m.toml");
    ASSERT_TRUE(ok.ok()) << join(ok.errors);
    EXPECT_EQ(ok.value->planner.fit_arcs_mm, 0.005);
    auto bad = parse_machine(with("2"), "m.toml");
    ASSERT_FALSE(bad.errors.empty());
    EXPECT_NE(join(bad.errors).find(fmt::format("m.toml:{}:", line)), std::string::npos) << join(bad.errors);
    EXPECT_NE(join(bad.errors).find("fit_arcs_mm"), std::string::npos) << join(bad.errors);
}

namespace {

// The fitted blocks of `job`, fed to an ArcFitter one at a time, each block
// handed out as soon as it is made; the most it held and the blocks pushed when
// the first arc came out.
struct Streamed {
    std::vector<MotionBlock> blocks;
    ArcFitStats stats;
    std::size_t max_held = 0, first_arc_after = 0;
};
Streamed stream_fit(const Job& job, double tol, bool whole_runs) {
    Streamed r;
    ArcFitter f(tol, whole_runs);
    for (std::size_t i = 0; i < job.blocks.size(); ++i) {
        f.push(job.blocks[i]);
        r.max_held = std::max(r.max_held, f.held());
        while (auto b = f.next()) {
            if (r.first_arc_after == 0 && b->kind != MotionKind::linear && b->kind != MotionKind::rapid)
                r.first_arc_after = i + 1;
            r.blocks.push_back(std::move(*b));
        }
    }
    f.finish();
    while (auto b = f.next()) r.blocks.push_back(std::move(*b));
    r.stats = f.stats();
    return r;
}

void expect_same_blocks(const std::vector<MotionBlock>& a, const std::vector<MotionBlock>& b, const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const MotionBlock &x = a[i], &y = b[i];
        const bool same = x.kind == y.kind && x.start == y.start && x.end == y.end && x.center_x == y.center_x &&
                          x.center_y == y.center_y && x.plane == y.plane && x.feed == y.feed &&
                          x.loc.line == y.loc.line && x.loc.col == y.loc.col;
        ASSERT_TRUE(same) << what << ": block " << i << " (line " << x.loc.line << " against " << y.loc.line << ")";
    }
}

}  // namespace

// The fitter decides a stretch of a run once the lines it holds settle it (past
// the first doubled length that failed), not at the run's end: the blocks are
// those of deciding with each whole run held, bit for bit, on random programs of
// arcs, collinear runs, zigzags and breaks, and on the dense spiral (one run of
// 12,000 lines), holding a few hundred lines, not the run.
TEST(ArcFit, StreamedAsTheBlocksArriveIsTheWholeRunFit) {
    std::mt19937 rng(20261129);
    std::uniform_real_distribution<double> u(0, 1);
    for (int prog = 0; prog < 40; ++prog) {
        std::vector<std::pair<double, double>> pts{{0, 0}};
        std::string g = "G21 G90 G17\nG0 X0 Y0\nF600\n";
        double x = 0, y = 0, heading = 0;
        const auto line_to = [&](double nx, double ny) {
            g += fmt::format("G1 X{:.5f} Y{:.5f}\n", nx, ny);
            x = nx;
            y = ny;
        };
        for (int piece = 0; piece < 12; ++piece) {
            const int kind = int(u(rng) * 6);
            const int n = 2 + int(u(rng) * (prog % 4 == 3 ? 900 : 120));
            const double step = 0.05 + u(rng) * 0.5, noise = u(rng) < 0.5 ? 0 : 0.0008;
            if (kind <= 1) {  // an arc's chords, either way, maybe noisy
                const double r = 0.5 + u(rng) * 40, turn = (kind == 0 ? 1 : -1) * step / r;
                const double cx = x - r * std::cos(heading - (kind == 0 ? -1 : 1) * kPi / 2);
                const double cy = y - r * std::sin(heading - (kind == 0 ? -1 : 1) * kPi / 2);
                double a = std::atan2(y - cy, x - cx);
                for (int i = 0; i < n; ++i) {
                    a += turn;
                    line_to(cx + (r + noise * (u(rng) - 0.5)) * std::cos(a), cy + (r + noise * (u(rng) - 0.5)) * std::sin(a));
                }
                heading += turn * n;
            } else if (kind == 2) {  // collinear, maybe jittered
                for (int i = 0; i < n; ++i)
                    line_to(x + step * std::cos(heading) + noise * (u(rng) - 0.5), y + step * std::sin(heading));
            } else if (kind == 3) {  // a zigzag
                for (int i = 0; i < n; ++i) {
                    heading += (i % 2 ? 1 : -1) * 1.2;
                    line_to(x + step * std::cos(heading), y + step * std::sin(heading));
                }
            } else if (kind == 4) {  // a break: a feed change, a Z move, a rapid or a dwell
                const int b = int(u(rng) * 4);
                g += b == 0 ? "F900\n" : b == 1 ? "G1 Z-0.5\nG1 Z0\n" : b == 2 ? "G4 P0.1\n" : "";
                if (b == 3) {
                    x += 1;
                    g += fmt::format("G0 X{:.5f} Y{:.5f}\n", x, y);
                }
            } else {  // a corner
                heading += 1 + u(rng) * 2;
            }
        }
        const Job job = parse(g);
        for (double tol : {0.001, 0.01}) {
            const Streamed s = stream_fit(job, tol, false), w = stream_fit(job, tol, true);
            const std::string what = fmt::format("program {}, tolerance {}", prog, tol);
            expect_same_blocks(s.blocks, w.blocks, what);
            EXPECT_EQ(s.stats.arcs, w.stats.arcs) << what;
            EXPECT_EQ(s.stats.lines_in_arcs, w.stats.lines_in_arcs) << what;
            EXPECT_EQ(s.stats.merged, w.stats.merged) << what;
            EXPECT_EQ(s.stats.max_deviation_mm, w.stats.max_deviation_mm) << what;
            expect_same_blocks(fit_arcs(job, tol).blocks, s.blocks, what + ", fit_arcs");
        }
    }
    const auto dense = load_gcode(CPSTEP_EXAMPLES_DIR "/jobs/dense.ngc", GcodeOptions{});
    ASSERT_TRUE(dense.ok()) << join(dense.errors);
    const Streamed s = stream_fit(*dense.value, 0.002, false), w = stream_fit(*dense.value, 0.002, true);
    expect_same_blocks(s.blocks, w.blocks, "dense.ngc");
    EXPECT_GE(w.max_held, 12000u);  // the reference holds the spiral
    EXPECT_LT(s.max_held, 600u) << "the stream holds the lines its decisions need";
    EXPECT_GT(s.first_arc_after, 0u);
    EXPECT_LT(s.first_arc_after, 300u);
    std::printf("dense.ngc: the stream held at most %zu lines, its first arc out after %zu blocks\n", s.max_held,
                s.first_arc_after);
}

// A run is taken at most kArcFitMaxLines lines at a time, which bounds what the
// fitter holds: 10,000 collinear lines become three lines.
TEST(ArcFit, ALongCollinearRunIsCutAtTheCap) {
    std::vector<std::pair<double, double>> pts;
    for (int i = 0; i <= 10000; ++i) pts.push_back({0.01 * i, 0.005 * i});
    const Job job = parse(polyline(pts));
    const Streamed s = stream_fit(job, 0.001, false);
    std::vector<std::size_t> lines;
    for (const MotionBlock& b : s.blocks)
        if (b.kind == MotionKind::linear) lines.push_back(std::size_t(std::llround((b.end[0] - b.start[0]) / 0.01)));
    EXPECT_EQ(lines, (std::vector<std::size_t>{kArcFitMaxLines, kArcFitMaxLines, 10000 - 2 * kArcFitMaxLines}));
    EXPECT_EQ(s.stats.merged, 3u);
    EXPECT_LE(s.max_held, kArcFitMaxLines + 1);
    expect_same_blocks(s.blocks, stream_fit(job, 0.001, true).blocks, "collinear");
}

namespace {

// n + 1 points along block b's path in XY, from its start to its end.
std::vector<Eigen::Vector3d> along(const MotionBlock& b, int n) {
    std::vector<Eigen::Vector3d> pts;
    if (b.kind == MotionKind::arc_cw || b.kind == MotionKind::arc_ccw) {
        const double r = std::hypot(b.start[0] - b.center_x, b.start[1] - b.center_y);
        const double a0 = std::atan2(b.start[1] - b.center_y, b.start[0] - b.center_x);
        const double a1 = std::atan2(b.end[1] - b.center_y, b.end[0] - b.center_x);
        double sweep = a1 - a0;
        if (b.kind == MotionKind::arc_ccw) while (sweep <= 0) sweep += 2 * kPi;
        else while (sweep >= 0) sweep -= 2 * kPi;
        for (int i = 0; i <= n; ++i) {
            const double a = a0 + sweep * i / n;
            pts.emplace_back(b.center_x + r * std::cos(a), b.center_y + r * std::sin(a), 0.0);
        }
        return pts;
    }
    for (int i = 0; i <= n; ++i) {
        const double t = double(i) / n;
        pts.emplace_back(b.start[0] + t * (b.end[0] - b.start[0]), b.start[1] + t * (b.end[1] - b.start[1]), 0.0);
    }
    return pts;
}

}  // namespace

// naca0025.ngc's NURBS (seed 002's airfoil) cut into arcs: the blocks made run
// from the curve's start to its end without a gap, every point of them lies within
// the tolerance of the true curve, and every point of the curve within the
// tolerance of them (both measured here against the curve sampled finely).
TEST(ArcFit, ANurbsBecomesArcsWithinTheToleranceOfTheCurve) {
    const auto j = load_gcode(CPSTEP_EXAMPLES_DIR "/jobs/naca0025.ngc", GcodeOptions{});
    ASSERT_TRUE(j.ok()) << join(j.errors);
    const MotionBlock* curve = nullptr;
    for (const MotionBlock& b : j.value->blocks)
        if (b.kind == MotionKind::nurbs) curve = &b;
    ASSERT_NE(curve, nullptr);
    for (const double tol : {0.002, 0.01}) {
        ArcFitStats st;
        const Job out = fit_arcs(*j.value, tol, &st);
        EXPECT_EQ(st.curves, 1u);
        EXPECT_GT(st.curve_arcs, 5u);
        EXPECT_EQ(st.arcs, 0u) << "no G1 lines in the job";
        std::vector<MotionBlock> made;
        for (const MotionBlock& b : out.blocks) {
            EXPECT_NE(b.kind, MotionKind::nurbs) << "the curve was replaced";
            if (b.kind == MotionKind::linear || b.kind == MotionKind::arc_cw || b.kind == MotionKind::arc_ccw)
                if (b.feed > 0) made.push_back(b);
        }
        ASSERT_EQ(made.size(), st.curve_arcs + st.curve_lines);
        const std::size_t chords = curve->curve->chord_parameters(tol).size() - 1;
        EXPECT_LT(made.size() * 3, chords) << "fewer blocks than the curve's chords within the tolerance";
        EXPECT_EQ(made.front().start, curve->start);
        EXPECT_EQ(made.back().end, curve->end);
        for (std::size_t k = 1; k < made.size(); ++k) EXPECT_EQ(made[k].start, made[k - 1].end) << "block " << k;
        for (const MotionBlock& b : made) {
            EXPECT_EQ(b.feed, curve->feed);
            EXPECT_EQ(b.loc.line, curve->loc.line);
        }
        // The made path against the curve.
        CurveDistance from_curve(*curve->curve, 1e-7);
        double worst_out = 0;
        for (const MotionBlock& b : made)
            for (const Eigen::Vector3d& p : along(b, 400)) worst_out = std::max(worst_out, from_curve(p));
        // The curve against the made path.
        double worst_in = 0;
        const std::vector<double> us = curve->curve->chord_parameters(1e-5);
        for (std::size_t i = 0; i + 1 < us.size(); ++i)
            for (int h = 0; h < 4; ++h) {
                const Eigen::Vector3d q = curve->curve->point(us[i] + (us[i + 1] - us[i]) * h / 4);
                double d = 1e9;
                for (const MotionBlock& b : made) d = std::min(d, distance_to(b, q[0], q[1]));
                worst_in = std::max(worst_in, d);
            }
        std::printf("naca0025 at %g mm: %zu arcs and %zu lines for %zu chords; the path within %.5f mm of the "
                    "curve, the curve within %.5f mm of it (bound %.5f)\n",
                    tol, st.curve_arcs, st.curve_lines, chords, worst_out, worst_in, st.curve_max_deviation_mm);
        EXPECT_LE(worst_out, tol + 1e-6);
        EXPECT_LE(worst_in, tol + 1e-6);
        EXPECT_LE(st.curve_max_deviation_mm, tol + 1e-12);
    }
}

// A curve the fitting cannot shorten stays a NURBS: a straight cubic has too few
// chords for an arc.
TEST(ArcFit, ANurbsTheArcsCannotShortenStaysACurve) {
    const Job in = parse("G21 G90 G17\nG0 X0 Y0\nG5 I1 J0 P-1 Q0 X3 Y0 F600\nG1 X4 Y0\n");
    ArcFitStats st;
    const Job out = fit_arcs(in, 0.002, &st);
    EXPECT_EQ(st.curves, 0u);
    std::size_t curves = 0;
    for (const MotionBlock& b : out.blocks) curves += b.kind == MotionKind::nurbs;
    EXPECT_EQ(curves, 1u);
    EXPECT_EQ(out.blocks.size(), in.blocks.size());
}
