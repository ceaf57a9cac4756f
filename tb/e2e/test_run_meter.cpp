// SPDX-License-Identifier: MIT
// run::RunMeter, the measure of a run taken as it goes (docs/SIM.md "Memory"),
// against the whole-run computations it replaces, on the example jobs run on
// the simulated HX8K card (its conic walker and torch): every move's planned
// times (MoveClock against plan::ideal_times and the chunks expanded here),
// the realized peaks (plan::realized_peaks on every recorded STEP edge, bit for
// bit), Klipper's cost (plan::queue_step_cost on every step), the curve
// deviation (every position of the recorded pins against the NURBS), and the
// meter fed live equal to the meter fed the recorded run afterwards. And the
// meter's memory stays bounded over a run far longer than its plan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <tuple>

#include <unistd.h>

#include <fmt/format.h>

#include "card/caps.h"
#include "plan/chunks.h"
#include "plan/gcode.h"
#include "plan/kinematics.h"
#include "plan/nurbs.h"
#include "plan/queue_step.h"
#include "run/card_job.h"
#include "run/measure.h"
#include "run/sim_run.h"
#include "run/torch.h"

namespace cpstep::tb {
namespace {

const std::string kSource = CPSTEP_SOURCE_DIR;

run::CardJob example(const std::string& name, bool streamed = false) {
  const auto caps = card::board_caps("hx8k");
  auto prepared = run::prepare_job(kSource + "/examples/jobs/" + name, kSource + "/examples/machines/seed002.toml", *caps,
                                   {}, streamed);
  EXPECT_TRUE(prepared.ok()) << plan::join(prepared.errors);
  return std::move(*prepared.value);
}

// A job's command words as its WordSource hands them out, 4,096 or more at a time.
std::vector<uint32_t> all_words(const run::CardJob& job) {
  run::WordSource src(job);
  std::vector<uint32_t> words;
  while (!src.exhausted()) {
    const std::span<const uint32_t> w = src.window(4096);
    words.insert(words.end(), w.begin(), w.end());
    src.consume(w.size());
  }
  return words;
}

void expect_same_cost(const plan::QueueStepCost& a, const plan::QueueStepCost& b, const char* what) {
  EXPECT_TRUE(a == b) << what << ": " << a.bytes << " bytes, " << a.queue_step << " queue_step, error '" << a.error
                      << "' against " << b.bytes << ", " << b.queue_step << ", '" << b.error << "'";
}

void expect_same_measure(const run::RunMeasure& a, const run::RunMeasure& b) {
  const auto timing = [](const run::RunMeasure& m) {
    return std::tuple(m.moves, m.job_time_cycles, m.max_timing_error_cycles, m.max_timing_error_move,
                      m.max_chunk_error_cycles, m.moves_off_chunk_time, m.curve.positions, m.curve.max_mm);
  };
  EXPECT_TRUE(timing(a) == timing(b)) << "moves, times, timing errors or curve deviation differ";
  const auto axis = [](const run::AxisMeasure& m) {
    return std::tuple(m.pulses, m.peak.v, m.peak.a, m.peak.j, m.within_limits);
  };
  for (int x = 0; x < plan::kAxes; ++x) EXPECT_TRUE(axis(a.axes[x]) == axis(b.axes[x])) << "axis " << x;
  expect_same_cost(a.klipper_pins_25us, b.klipper_pins_25us, "pins");
  expect_same_cost(a.klipper_25us, b.klipper_25us, "path 25 us");
}

class RunMeterJobs : public ::testing::TestWithParam<const char*> {};

TEST_P(RunMeterJobs, TheLiveMeasureIsTheWholeRunsMeasure) {
  const run::CardJob job = example(GetParam());
  const double hz = job.clock_hz();
  run::RunMeter meter(job);
  run::SimRunOptions o;
  o.board = "hx8k";
  o.meter = &meter;
  o.record_pins = true;  // the whole run as well, for the references
  const run::CardRun r = run::run_on_sim(job, o);
  ASSERT_TRUE(r.ok()) << r.faults.front().name << ": " << r.faults.front().message;
  const run::RunMeasure m = meter.finish(r);
  ASSERT_EQ(r.move_cycles.size(), job.moves());
  EXPECT_EQ(r.move_events, job.moves());
  EXPECT_EQ(m.moves, job.moves());

  // Every move's planned times, whole: the planner's ideal times and the chunks
  // expanded segment by segment (a pause's moves time the next move only).
  const std::vector<double> ideal = plan::ideal_times(job.planned, hz);
  std::vector<int64_t> chunk;
  int64_t last = 0;
  for (const plan::PlannedCardSegment& c : job.planned.card) {
    const std::vector<int64_t> t = plan::expand(c.chunks, last);
    if (!t.empty()) last = t.back();
    if (!c.segment.pause) chunk.insert(chunk.end(), t.begin(), t.end());
  }
  ASSERT_EQ(ideal.size(), job.moves());
  ASSERT_EQ(chunk.size(), job.moves());
  EXPECT_EQ(run::ideal_cycles(job), ideal);
  EXPECT_EQ(run::chunk_cycles(job), chunk);
  double worst = 0;
  uint64_t worst_move = 0, off = 0;
  int64_t worst_chunk = 0;
  for (size_t i = 0; i < job.moves(); ++i) {
    const int64_t event = int64_t(r.move_cycles[i] - r.start_cycle);
    const double e = std::abs(double(event) - ideal[i]);
    if (e > worst) worst = e, worst_move = i + 1;
    worst_chunk = std::max(worst_chunk, std::abs(event - chunk[i]));
    off += event != chunk[i];
  }
  EXPECT_EQ(m.max_timing_error_cycles, worst);
  EXPECT_EQ(m.max_timing_error_move, worst_move);
  EXPECT_EQ(m.max_chunk_error_cycles, worst_chunk);
  EXPECT_EQ(m.moves_off_chunk_time, off);
  EXPECT_EQ(m.job_time_cycles, r.move_cycles.back() - r.start_cycle);

  // The peaks from every recorded edge, and Klipper's cost of every step.
  std::vector<plan::StepperSteps> pins;
  for (int a = 0; a < plan::kAxes; ++a) {
    const plan::AxisConfig& ax = job.machine.axes[a];
    if (!ax.present) continue;
    const run::AxisPulses& p = r.pulses[a];
    EXPECT_EQ(m.axes[a].pulses, p.cycles.size());
    std::vector<double> t;
    for (uint64_t c : p.cycles) t.push_back(double(int64_t(c - r.start_cycle)) / hz);
    const std::vector<int> dirs(p.dirs.begin(), p.dirs.end());
    const run::Windows h = run::peak_windows(ax);
    const int e = run::kEvaluationsPerWindow;
    EXPECT_EQ(m.axes[a].peak.v, plan::realized_peaks(t, dirs, ax.steps_per_mm, h.v, e).v) << "axis " << a;
    EXPECT_EQ(m.axes[a].peak.a, plan::realized_peaks(t, dirs, ax.steps_per_mm, h.a, e).a) << "axis " << a;
    EXPECT_EQ(m.axes[a].peak.j, plan::realized_peaks(t, dirs, ax.steps_per_mm, h.j, e).j) << "axis " << a;
    if (p.cycles.empty()) continue;
    plan::StepperSteps s;
    for (uint64_t c : p.cycles) s.cycles.push_back(c - r.start_cycle);
    s.dirs = p.dirs;
    pins.push_back(std::move(s));
  }
  expect_same_cost(m.klipper_pins_25us, plan::queue_step_cost(pins, 25e-6 * hz), "pins");
  const std::vector<plan::StepperSteps> path = run::klipper_path_steps(job);
  expect_same_cost(m.klipper_25us, plan::queue_step_cost(path, 25e-6 * hz), "path 25 us");
  expect_same_cost(m.klipper_1us, plan::queue_step_cost(path, 1e-6 * hz), "path 1 us");

  // The curve deviation from every position the pins show, segment by segment.
  auto parsed = plan::load_gcode(job.job_file, plan::gcode_options(job.machine));
  ASSERT_TRUE(parsed.ok());
  std::map<std::pair<int, int>, const plan::MotionBlock*> curves;
  for (const auto& b : parsed->blocks)
    if (b.kind == plan::MotionKind::nurbs && b.curve) curves[{b.loc.line, b.loc.col}] = &b;
  std::vector<std::array<double, 2>> xy{{0, 0}};  // after each move
  {
    int64_t x = 0, y = 0;
    size_t nx = 0, ny = 0;
    for (uint64_t c : r.move_cycles) {
      if (nx < r.pulses[0].cycles.size() && r.pulses[0].cycles[nx] == c + 1) x += r.pulses[0].dirs[nx++];
      if (ny < r.pulses[1].cycles.size() && r.pulses[1].cycles[ny] == c + 1) y += r.pulses[1].dirs[ny++];
      xy.push_back({double(x) / job.machine.axes[0].steps_per_mm, double(y) / job.machine.axes[1].steps_per_mm});
    }
  }
  // Each position's distance to the curve, by brute force over all of its chords
  // (within 1e-6 mm of the curve).
  std::map<const plan::Nurbs*, std::vector<Eigen::Vector3d>> chords;
  const auto distance = [&chords](const plan::Nurbs& c, const Eigen::Vector3d& p) {
    std::vector<Eigen::Vector3d>& pts = chords[&c];
    if (pts.empty())
      for (double u : c.chord_parameters(1e-6)) pts.push_back(c.point(u));
    double best = (p - pts.front()).norm();
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
      const Eigen::Vector3d d = pts[i + 1] - pts[i];
      const double t = d.squaredNorm() > 0 ? std::clamp((p - pts[i]).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      best = std::min(best, (p - (pts[i] + t * d)).norm());
    }
    return best;
  };
  uint64_t positions = 0, prev = 0;
  double max_mm = 0;
  for (const run::Checkpoint& cp : job.checkpoints) {
    const auto it = curves.find({cp.loc.line, cp.loc.col});
    if (it != curves.end()) {
      const plan::Nurbs& c = *it->second->curve;
      const double z = c.points().front()[2];
      // The segment's positions, the one before its first move among them.
      for (uint64_t i = prev; i <= cp.moves; ++i, ++positions)
        max_mm = std::max(max_mm, distance(c, {xy[i][0], xy[i][1], z}));
    }
    prev = cp.moves;
  }
  EXPECT_EQ(m.curve.positions, positions);
  EXPECT_NEAR(m.curve.max_mm, max_mm, 2e-6);  // both within 1e-6 mm of the curve
  if (std::string(GetParam()) == "naca0025.ngc") {
    EXPECT_GT(positions, 1000u);
  }

  // The meter fed the recorded run afterwards measures the same.
  expect_same_measure(run::measure_run(job, r), m);
  // The path plot holds every position (these jobs are below its bound).
  ASSERT_EQ(meter.path_stride(), 1u);
  ASSERT_EQ(meter.path().size(), job.moves() + 1);
  EXPECT_DOUBLE_EQ(meter.path().back()[0], xy.back()[0]);
  EXPECT_DOUBLE_EQ(meter.path().back()[1], xy.back()[1]);
  const run::KinematicSeries ks = meter.series();
  ASSERT_FALSE(ks.t.empty());
  EXPECT_LE(ks.t.size(), run::RunMeter::kMaxSeriesSamples);
  EXPECT_GE(ks.t.back(), m.job_time_s - 1e-9);
}

// Every card segment of a streamed job made again by a run::PlanCursor from the
// job's blocks (what its sender, its clock and its checks do as the run reaches
// it): the whole plan's card segments with the same chunks and, for a CONIC
// piece, the same walk, its step segments and feeds, and its checkpoints.
TEST_P(RunMeterJobs, EveryCardSegmentIsMadeAgainExactly) {
  const run::CardJob job = example(GetParam());
  size_t conics = 0;
  for (const plan::PlannedCardSegment& c : job.planned.card) conics += c.conic != nullptr;
  if (std::string(GetParam()) == "tight_arcs.ngc" || std::string(GetParam()) == "bracket.ngc") {
    EXPECT_GT(conics, 0u);
  }
  // A streamed job's plan made again by a PlanCursor from its blocks: the
  // whole plan's card segments, step segments and feeds, and its checkpoints.
  const run::CardJob streamed = example(GetParam(), true);
  run::PlanCursor cursor(streamed);
  size_t s = 0;
  for (const plan::PlannedCardSegment* c; (c = cursor.next_card()) != nullptr; ++s) {
    ASSERT_LT(s, job.planned.card.size());
    const plan::PlannedCardSegment& w = job.planned.card[s];
    ASSERT_EQ(c->segment.step_segment, w.segment.step_segment) << "card segment " << s;
    ASSERT_EQ(c->segment.delta, w.segment.delta) << "card segment " << s;
    ASSERT_EQ(c->chunks, w.chunks) << "card segment " << s;
    ASSERT_EQ(bool(c->conic), bool(w.conic)) << "card segment " << s;
    if (c->conic) {
      ASSERT_EQ(c->conic->words(), w.conic->words()) << "card segment " << s;
    }
    if (c->segment.pause) continue;
    const plan::StreamedStep& st = cursor.step(c->segment.step_segment);
    ASSERT_EQ(st.segment.start, job.planned.step_segments[st.index].start) << "card segment " << s;
    ASSERT_EQ(st.feed.t_start, job.planned.feeds[st.index].t_start) << "card segment " << s;
  }
  EXPECT_EQ(s, job.planned.card.size());
  run::CheckpointCursor cps(streamed);
  size_t k = 0;
  for (const run::Checkpoint* cp; (cp = cps.next()) != nullptr; ++k) {
    ASSERT_LT(k, job.checkpoints.size());
    ASSERT_EQ(cp->moves, job.checkpoints[k].moves) << "checkpoint " << k;
    ASSERT_EQ(cp->position, job.checkpoints[k].position) << "checkpoint " << k;
    ASSERT_EQ(cp->loc, job.checkpoints[k].loc) << "checkpoint " << k;
  }
  EXPECT_EQ(k, job.checkpoints.size());
}

// A streamed job (run::CardJob::streamed: nothing of the plan kept but its
// blocks and statistics, the words made again as they are sent) sends the whole
// job's words, word for word, in windows of any size; its segment ends and
// counts are the whole job's; run on the card it makes the same pins and
// measures.
TEST_P(RunMeterJobs, AStreamedJobIsTheWholeJob) {
  const run::CardJob whole = example(GetParam());
  const run::CardJob streamed = example(GetParam(), true);
  ASSERT_TRUE(streamed.streamed);
  EXPECT_TRUE(streamed.words.empty());
  // Nothing of the plan kept per line: its blocks and statistics.
  EXPECT_TRUE(streamed.planned.card.empty());
  EXPECT_TRUE(streamed.planned.step_segments.empty());
  EXPECT_TRUE(streamed.planned.feeds.empty());
  EXPECT_TRUE(streamed.checkpoints.empty());
  EXPECT_EQ(streamed.checkpoint_count, whole.checkpoints.size());
  EXPECT_EQ(streamed.final_position, whole.checkpoints.back().position);
  EXPECT_EQ(streamed.start, whole.start);
  EXPECT_EQ(streamed.has_nurbs, whole.has_nurbs);
  EXPECT_EQ(streamed.planned.stats.duration_s, whole.planned.stats.duration_s);
  EXPECT_EQ(streamed.planned.stats.chunks, whole.planned.stats.chunks);
  EXPECT_EQ(streamed.planned.stats.card_segments, whole.planned.stats.card_segments);
  EXPECT_EQ(streamed.planned.stats.step_segments, whole.planned.stats.step_segments);
  EXPECT_EQ(streamed.word_count(), whole.words.size());
  EXPECT_EQ(streamed.wire_chunks(), whole.wire_chunks());
  EXPECT_TRUE(streamed.segment_end_word.empty() && streamed.segment_end_cycle.empty());
  EXPECT_EQ(streamed.wire.start_after, whole.wire.start_after);
  EXPECT_TRUE(streamed.wire.segments.empty());
  EXPECT_EQ(streamed.wire_segments(), whole.wire.segments.size());
  EXPECT_EQ(streamed.conic_segments(), whole.conic_segments());
  const std::vector<run::TorchSwitch> ts = run::torch_switches(streamed), tw = run::torch_switches(whole);
  ASSERT_EQ(ts.size(), tw.size());
  for (size_t i = 0; i < ts.size(); ++i) {
    EXPECT_EQ(std::tuple(ts[i].segment, ts[i].on, ts[i].earliest, ts[i].latest, ts[i].loc.line),
              std::tuple(tw[i].segment, tw[i].on, tw[i].earliest, tw[i].latest, tw[i].loc.line))
        << "torch switch " << i;
  }
  if (std::string(GetParam()) == "plasma.ngc") {
    EXPECT_GT(ts.size(), 2u);
  }
  EXPECT_EQ(streamed.moves(), whole.moves());
  EXPECT_EQ(run::chunk_cycles(streamed), run::chunk_cycles(whole));
  EXPECT_EQ(run::ideal_cycles(streamed), run::ideal_cycles(whole));
  for (const size_t window : {size_t{1}, size_t{97}, size_t{1} << 16}) {
    run::WordSource src(streamed, {7, 8});
    std::vector<uint32_t> words;
    while (!src.exhausted()) {
      const std::span<const uint32_t> w = src.window(window);
      ASSERT_FALSE(w.empty());
      const size_t n = std::min(w.size(), window);
      words.insert(words.end(), w.begin(), w.begin() + std::ptrdiff_t(n));
      src.consume(n);
    }
    ASSERT_EQ(words.size(), whole.words.size() + 2) << "window " << window;
    EXPECT_EQ(words[0], 7u);
    EXPECT_TRUE(std::equal(words.begin() + 2, words.end(), whole.words.begin())) << "window " << window;
  }
  // Its buffered time (what the client batches by), from the ends of the
  // segments its WordSource made and the card still holds: the whole job's
  // segment ends, the segment the card runs counted as done; a card that has
  // done half of what it was sent at each step.
  {
    run::WordSource src(streamed);
    const std::vector<uint64_t>& ends = whole.segment_end_word;
    ASSERT_EQ(ends.size(), whole.wire.segments.size());
    uint64_t handed = 0, done = 0;
    size_t checks = 0;
    while (!src.exhausted()) {
      const size_t n = std::min<size_t>(src.window(61).size(), 61);
      src.consume(n);
      handed += n;
      const auto sent = uint64_t(std::upper_bound(ends.begin(), ends.end(), handed) - ends.begin());
      for (const uint64_t d : {done, (done + sent) / 2}) {
        const double expect = sent > d ? double(whole.segment_end_cycle[sent - 1] - whole.segment_end_cycle[d]) /
                                             whole.clock_hz()
                                       : 0.0;
        ASSERT_DOUBLE_EQ(src.buffered_seconds(d, 0, handed), expect) << "handed " << handed << ", done " << d;
        checks += expect > 0;
      }
      done = (done + sent) / 2;
    }
    EXPECT_GT(checks, 0u);
  }
  // On the card: the same run, measured the same.
  run::SimRunOptions o;
  o.board = "hx8k";
  const run::CardRun a = run::run_on_sim(whole, o), b = run::run_on_sim(streamed, o);
  ASSERT_TRUE(b.ok()) << b.faults.front().name << ": " << b.faults.front().message;
  EXPECT_EQ(a.move_cycles, b.move_cycles);
  for (int x = 0; x < plan::kAxes; ++x) EXPECT_EQ(a.pulses[x].cycles, b.pulses[x].cycles) << "axis " << x;
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.checked_segments, b.checked_segments);
  expect_same_measure(run::measure_run(whole, a), run::measure_run(streamed, b));
}

INSTANTIATE_TEST_SUITE_P(Examples, RunMeterJobs,
                         ::testing::Values("tab.ngc", "tight_arcs.ngc", "naca0025.ngc", "bracket.ngc", "plasma.ngc"),
                         [](const auto& p) {
                           std::string n = p.param;
                           return n.substr(0, n.find('.'));
                         });

// A streamed job whose G1 chains are fitted with arcs (planner.fit_arcs_mm) fits
// them as its G-code file is read (plan::ArcFitter), keeping the file's mark and
// no blocks, and plans them again so: the whole job's words, checkpoints, fitting
// and measures all the same. (A job given as blocks keeps its fitted blocks.)
TEST(RunMeter, AStreamedJobFitsItsArcsAsItsFileIsRead) {
  const auto caps = card::board_caps("hx8k");
  std::ifstream in(kSource + "/examples/machines/seed002.toml");
  std::string toml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = toml.find("[planner]\n");
  ASSERT_NE(at, std::string::npos);
  toml.insert(at + 10, "fit_arcs_mm = 0.01\n");
  const auto machine_file = std::filesystem::temp_directory_path() / fmt::format("cpstep_fit_{}.toml", ::getpid());
  std::ofstream(machine_file) << toml;
  const std::string gcode = kSource + "/examples/jobs/dense.ngc";
  auto whole = run::prepare_job(gcode, machine_file, *caps);
  auto streamed = run::prepare_job(gcode, machine_file, *caps, {}, true);
  std::filesystem::remove(machine_file);
  ASSERT_TRUE(whole.ok() && streamed.ok()) << plan::join(whole.errors) << plan::join(streamed.errors);
  ASSERT_EQ(streamed->machine.planner.fit_arcs_mm, 0.01);
  ASSERT_TRUE(streamed->streamed && streamed->gcode_file && !streamed->blocks);
  const plan::ArcFitStats &fs = streamed->planned.stats.fit, &fw = whole->planned.stats.fit;
  EXPECT_GT(fs.arcs, 0u);
  EXPECT_EQ(std::tuple(fs.arcs, fs.lines_in_arcs, fs.merged, fs.lines_in_merged, fs.max_deviation_mm),
            std::tuple(fw.arcs, fw.lines_in_arcs, fw.merged, fw.lines_in_merged, fw.max_deviation_mm));
  EXPECT_EQ(streamed->conic_segments(), whole->conic_segments());
  EXPECT_GT(streamed->conic_segments(), 0u);
  EXPECT_EQ(all_words(*streamed), whole->words);
  run::CheckpointCursor cps(*streamed);
  size_t k = 0;
  for (const run::Checkpoint* cp; (cp = cps.next()) != nullptr; ++k) {
    ASSERT_LT(k, whole->checkpoints.size());
    ASSERT_EQ(cp->position, whole->checkpoints[k].position) << "checkpoint " << k;
  }
  EXPECT_EQ(k, whole->checkpoints.size());
  EXPECT_EQ(run::ideal_cycles(*streamed), run::ideal_cycles(*whole));

  // Given as blocks, a streamed job keeps its fitted blocks.
  auto job = run::read_card_gcode(gcode, streamed->machine);
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  auto from_blocks = run::plan_card_job(*job, streamed->machine, *caps, {}, true);
  ASSERT_TRUE(from_blocks.ok()) << plan::join(from_blocks.errors);
  ASSERT_TRUE(from_blocks->blocks && !from_blocks->gcode_file);
  EXPECT_EQ(from_blocks->planned.stats.fit.arcs, fw.arcs);
  EXPECT_EQ(all_words(*from_blocks), whole->words);
}

// A streamed job keeps its G-code file's mark, not its text, and reads the file
// again as it sends the job: a file written over after the job was planned
// stops the words at the piece that differs (run::JobFileChanged naming the
// file and the bytes), before any word of a different plan; the file as it was
// sends the job, and so does a file saved over it by name (the planned one is
// kept open).
TEST(RunMeter, AStreamedJobStopsWhenItsFileChanged) {
  const auto path = std::filesystem::temp_directory_path() / fmt::format("cpstep_changed_{}.ngc", ::getpid());
  std::ifstream in(kSource + "/examples/jobs/dense.ngc", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(text.size(), 2 * plan::kGcodePiece);
  const auto write = [&](const std::string& t) { std::ofstream(path, std::ios::binary | std::ios::trunc) << t; };
  write(text);
  const auto caps = card::board_caps("hx8k");
  auto job = run::prepare_job(path, kSource + "/examples/machines/seed002.toml", *caps, {}, true);
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  ASSERT_TRUE(job->gcode_file && !job->blocks);
  EXPECT_EQ(job->gcode_file->size, text.size());
  const auto send = [&] { return all_words(*job); };
  const run::CardJob whole = example("dense.ngc");
  EXPECT_EQ(send(), whole.words);
  // A digit of the second piece changed: the same length.
  std::string changed = text;
  const size_t digit = changed.find_first_of("123456789", plan::kGcodePiece + 500);
  changed[digit] = changed[digit] == '9' ? '8' : char(changed[digit] + 1);
  write(changed);
  try {
    send();
    ADD_FAILURE() << "a changed file sent its words";
  } catch (const run::JobFileChanged& e) {
    EXPECT_NE(std::string(e.what()).find(path.string() + ":"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fmt::format("the file changed after the job was planned from it: bytes {} to",
                                                     plan::kGcodePiece)),
              std::string::npos)
        << e.what();
  }
  write(text);
  EXPECT_EQ(send(), whole.words);
  // Saved over by another file under its name (as editors save): the file
  // planned is still the one read, kept open.
  std::ofstream(path.string() + ".new", std::ios::binary) << changed;
  std::filesystem::rename(path.string() + ".new", path);
  EXPECT_EQ(send(), whole.words);
  std::filesystem::remove(path);
}

namespace {

// A link that forwards to the card's and calls `act` once, at its n-th transfer.
class ActingLink : public card::Link {
 public:
  ActingLink(card::Link& inner, uint64_t n, std::function<void()> act) : inner_(inner), n_(n), act_(std::move(act)) {}
  std::vector<uint8_t> transfer(std::span<const uint8_t> mosi) override {
    if (++count_ == n_) act_();
    return inner_.transfer(mosi);
  }
  void wait(double seconds) override { inner_.wait(seconds); }
  [[nodiscard]] double now_s() const override { return inner_.now_s(); }
  [[nodiscard]] std::string name() const override { return inner_.name(); }

 private:
  card::Link& inner_;
  uint64_t n_, count_ = 0;
  std::function<void()> act_;
};

}  // namespace

// The file written over while the job runs on the card: the run stops sending
// where the change begins and ends with the host fault SOURCE (110), which says
// what changed and how far the words went; nothing after it was sent. A job of
// 12,000 corner moves (three 64 KiB pieces), the third piece changed after the
// card has started. The HX8K card (FEED) is held to a stand on its feed ramp —
// its last moves slow down, it latches no fault — then flushed and resumed, and
// the run's feed record keeps the override sent before the change and the HOLD;
// the iCEBreaker card (no FEED) runs what it holds.
class SourceChanged : public ::testing::TestWithParam<const char*> {};

TEST_P(SourceChanged, AFileWrittenOverDuringTheRunStopsIt) {
  const std::string board = GetParam();
  const auto path = std::filesystem::temp_directory_path() / fmt::format("cpstep_running_{}_{}.ngc", board, ::getpid());
  std::string text = "G21 G90 F3000 G1 X10 Y10\n";
  for (int i = 0; i < 12000; ++i) text += i % 2 ? "G1 X10 Y10.1\n" : "G1 X10.1 Y10\n";
  text += "M2\n";
  ASSERT_GT(text.size(), 2 * plan::kGcodePiece + 1000);
  std::ofstream(path, std::ios::binary) << text;
  const auto caps = card::board_caps(board);
  auto job = run::prepare_job(path, kSource + "/examples/machines/seed002.toml", *caps, {}, true);
  ASSERT_TRUE(job.ok()) << plan::join(job.errors);
  std::string changed = text;
  const size_t at = changed.find("X10.1", 2 * plan::kGcodePiece + 100);
  changed.replace(at, 5, "X10.2");
  run::SimRunOptions o;
  o.board = board;
  o.record_pins = true;
  if (caps->feed) o.override_pct = 90;
  o.wrap_link = [&](card::Link& inner) {
    return std::make_unique<ActingLink>(inner, 40, [&] {
      std::ofstream(path, std::ios::binary | std::ios::trunc) << changed;
    });
  };
  const run::CardRun r = run::run_on_sim(*job, o);
  std::filesystem::remove(path);
  const auto source = std::find_if(r.faults.begin(), r.faults.end(), [](const run::Fault& f) { return f.code == 110; });
  ASSERT_NE(source, r.faults.end()) << (r.faults.empty() ? "no fault" : r.faults.front().name);
  EXPECT_EQ(source->name, "SOURCE");
  EXPECT_NE(source->message.find(fmt::format("{}:{}:1: the file changed after the job was planned from it: bytes {} to",
                                             path.string(),
                                             std::count(text.begin(), text.begin() + 2 * plan::kGcodePiece, '\n') + 1,
                                             2 * plan::kGcodePiece)),
            std::string::npos)
      << source->message;
  EXPECT_NE(source->message.find("the host sent no more (word "), std::string::npos) << source->message;
  EXPECT_GT(r.move_events, 1000u);
  EXPECT_LT(r.move_events, job->moves());
  if (caps->feed) {
    EXPECT_NE(source->message.find("the card held to a stand on its feed ramp, then FLUSH and RESUME"),
              std::string::npos)
        << source->message;
    EXPECT_FALSE(r.status.fault) << r.status.err_code;
    EXPECT_FALSE(r.status.running);
    EXPECT_FALSE(r.status.held);
    ASSERT_EQ(r.feed.size(), 2u);
    EXPECT_EQ(r.feed[0].event.kind, run::FeedEvent::Kind::override_pct);
    EXPECT_EQ(r.feed[0].event.pct, 90);
    EXPECT_EQ(r.feed[1].event.kind, run::FeedEvent::Kind::hold);
    // The ramp: the last move came at least 4 times later after the one before it
    // than the moves did before the hold (about 10 times here: the card's s was
    // near 0.1 when its last move fell due).
    const std::vector<uint64_t>& m = r.move_cycles;
    ASSERT_GT(m.size(), 200u);
    const double start_s = r.feed[1].taken_s;
    size_t before = 0;
    while (before + 1 < m.size() && double(m[before + 1] - r.start_cycle) / job->clock_hz() < start_s) ++before;
    ASSERT_GT(before, 1u);
    const uint64_t cruising = m[before] - m[before - 1], last = m[m.size() - 1] - m[m.size() - 2];
    EXPECT_GT(last, 4 * cruising) << last << " against " << cruising << " cycles, moves " << before << " and " << m.size();
  } else {
    EXPECT_NE(source->message.find("the card, which has no feed hold, runs what it holds"), std::string::npos)
        << source->message;
  }
}

INSTANTIATE_TEST_SUITE_P(Boards, SourceChanged, ::testing::Values("hx8k", "icebreaker"),
                         [](const ::testing::TestParamInfo<const char*>& i) { return std::string(i.param); });

// A run far longer than its plan (as under a feed hold, or a job of 10^8 moves):
// the series' grid and the path plot stay within their bounds, and what they
// keep is exact. X steps +1 every 1,000 cycles for 3,000,000 moves (75 s at
// 40 MHz, the plan 1.6 s).
TEST(RunMeter, ALongRunStaysWithinItsBounds) {
  const run::CardJob job = example("tab.ngc");
  const double hz = job.clock_hz();
  const double spm = job.machine.axes[0].steps_per_mm;
  run::RunMeter meter(job);
  meter.start(100, {});
  constexpr uint64_t kMoves = 3'000'000, kEvery = 1000;
  plan::PerAxis<int8_t> dirs{};
  dirs[0] = 1;
  for (uint64_t n = 1; n <= kMoves; ++n) meter.move(100 + n * kEvery + 1, 1u, dirs);
  run::CardRun r;
  const run::RunMeasure m = meter.finish(r);
  EXPECT_EQ(m.moves, kMoves);
  EXPECT_EQ(m.axes[0].pulses, kMoves);
  EXPECT_EQ(m.job_time_cycles, kMoves * kEvery);
  // The speed: 1 step per 1,000 cycles.
  const double v = hz / double(kEvery) / spm;
  EXPECT_NEAR(m.axes[0].peak.v, v, m.axes[0].tolerance.v);
  // The path: the start, every stride-th move, the last; each exact.
  const auto& path = meter.path();
  const uint64_t stride = meter.path_stride();
  EXPECT_GT(stride, 1u);
  EXPECT_LE(path.size(), run::RunMeter::kMaxPathPoints + 1);
  for (size_t k = 0; k + 1 < path.size(); ++k) ASSERT_DOUBLE_EQ(path[k][0], double(k * stride) / spm) << k;
  EXPECT_DOUBLE_EQ(path.back()[0], double(kMoves) / spm);
  // The series: its grid spacing grew; the measured speed in the middle is v.
  const run::KinematicSeries ks = meter.series();
  ASSERT_GT(ks.t.size(), 1000u);
  EXPECT_LE(ks.t.size(), run::RunMeter::kMaxSeriesSamples);
  EXPECT_GE(ks.t.back(), m.job_time_s - 1e-9);
  const size_t mid = ks.t.size() / 2;
  EXPECT_NEAR(ks.v[0][mid], v, 1e-6 * v);
  EXPECT_NEAR(ks.path_v[mid], v, 1e-6 * v);
  EXPECT_NEAR(ks.a[0][mid], 0, 1e-6);
}

}  // namespace
}  // namespace cpstep::tb
