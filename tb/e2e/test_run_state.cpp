// SPDX-License-Identifier: MIT
// The run state file (run/run_state.h) and a job's contours (run/resume.h):
// FNV-1a 64 against the published test vectors, the file read back as written
// and refused field by field, contours and the lines that end them found in
// G-code written here, and the blocks a resumed or stopped run plans.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "run/resume.h"
#include "run/run_state.h"

namespace cpstep::run {
namespace {

namespace fs = std::filesystem;

const fs::path kDir = fs::path(CPSTEP_TEST_DIR) / "run_state";

RunState sample() {
  RunState s;
  s.job = "jobs/cut.ngc";
  s.job_fnv1a64 = "0123456789abcdef";
  s.machine = "m.toml";
  s.axes = {true, true, true, false};
  s.steps_per_mm = {80, 80, 400, 0};
  s.contours = 5;
  s.contours_completed = 3;
  s.last_m5_line = 41;
  s.job_start = {10, -20, 0, 0};
  s.position = {1048, 183, -4, 0};
  s.ended = RunEnd::stopped;
  return s;
}

TEST(RunState, Fnv1a64MatchesThePublishedVectors) {
  EXPECT_EQ(fnv1a64_hex(""), "cbf29ce484222325");
  EXPECT_EQ(fnv1a64_hex("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(fnv1a64_hex("foobar"), "85944171f73967e8");
}

TEST(RunState, ReadsBackWhatItWrites) {
  fs::create_directories(kDir);
  const fs::path f = kDir / "state.json";
  const RunState s = sample();
  ASSERT_EQ(write_state(f, s), "");
  const auto r = read_state(f);
  ASSERT_TRUE(r.ok()) << plan::join(r.errors);
  EXPECT_EQ(r->job, s.job);
  EXPECT_EQ(r->job_fnv1a64, s.job_fnv1a64);
  EXPECT_EQ(r->machine, s.machine);
  EXPECT_EQ(r->axes, s.axes);
  EXPECT_EQ(r->steps_per_mm, s.steps_per_mm);
  EXPECT_EQ(r->contours, 5u);
  EXPECT_EQ(r->contours_completed, 3u);
  EXPECT_EQ(r->last_m5_line, 41);
  EXPECT_EQ(r->job_start, s.job_start);
  EXPECT_EQ(r->position, s.position);
  EXPECT_EQ(r->ended, RunEnd::stopped);
  EXPECT_DOUBLE_EQ(r->position_mm()[0], 13.1);
  EXPECT_DOUBLE_EQ(r->position_mm()[2], -0.01);
  // Written over: the new state whole, no temporary file left.
  RunState t = s;
  t.contours_completed = 5;
  t.ended = RunEnd::finished;
  ASSERT_EQ(write_state(f, t), "");
  EXPECT_EQ(read_state(f)->ended, RunEnd::finished);
  for (const auto& e : fs::directory_iterator(kDir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  // A directory that does not exist: an error naming the file.
  EXPECT_NE(write_state(kDir / "no" / "such.json", s).find("such.json"), std::string::npos);
}

// The error for the sample state's text with `from` replaced by `to`.
std::string error_for(const std::string& from, const std::string& to) {
  std::string text = state_text(sample());
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  const auto r = parse_state(text, "s.json");
  EXPECT_FALSE(r.ok()) << text;
  return plan::join(r.errors);
}

TEST(RunState, RefusesEachBadFieldByName) {
  EXPECT_EQ(error_for("\"contours_completed\": 3", "\"contours_completed\": -3"),
            "s.json: contours_completed: expected a whole number, 0 or more");
  EXPECT_EQ(error_for("\"contours_completed\": 3", "\"contours_completed\": 6"),
            "s.json: contours_completed: 6 is more than the job's 5 contours");
  EXPECT_EQ(error_for("\"job\": \"jobs/cut.ngc\",", ""), "s.json: job: missing");
  EXPECT_EQ(error_for("\"job_fnv1a64\": \"0123456789abcdef\"", "\"job_fnv1a64\": \"0123\""),
            "s.json: job_fnv1a64: expected 16 lowercase hex digits");
  EXPECT_EQ(error_for("\"ended\": \"stopped\"", "\"ended\": \"paused\""),
            "s.json: ended: \"paused\": expected finished, stopped or fault");
  EXPECT_EQ(error_for("\"x\": 1048", "\"q\": 1048"), "s.json: position_steps.q: no such axis (x, y, z, a)");
  EXPECT_EQ(error_for("\"x\": 1048", "\"x\": \"1048\""), "s.json: position_steps.x: expected a whole number of steps");
  EXPECT_EQ(error_for("\"version\": 1", "\"version\": 2"), "s.json: version: 2 is not a version this cpstep reads (1)");
  EXPECT_EQ(error_for("\"format\": \"cpstep run state\"", "\"format\": \"other\""),
            "s.json: format: expected \"cpstep run state\" (not a state written by cpstep run --state)");
  EXPECT_NE(error_for("{", "[").find("s.json: not a JSON state file"), std::string::npos);
}

plan::Job parse(const std::string& text) {
  auto r = plan::parse_gcode(text, "t.ngc");
  EXPECT_TRUE(r.ok()) << plan::join(r.errors);
  return r.ok() ? *r.value : plan::Job{};
}

// Three contours, ended by M5 (after a comment that names M5), by "m 05",
// and by the program's end (M30) without an M5.
const char* kJob =
    "G21 G90 F600\n"          // 1
    "G0 X1 Y1\n"              // 2
    "M3\n"                    // 3
    "G4 P0.5\n"               // 4
    "G1 X2\n"                 // 5
    "G1 Y2\n"                 // 6
    "(M5 is not here)\n"      // 7
    "M5\n"                    // 8
    "G0 X5 Y5\n"              // 9
    "M3 G4 P0.2\n"            // 10
    "G1 X6\n"                 // 11
    "m 05 (done)\n"           // 12
    "G91 G0 X1\n"             // 13
    "M3\n"                    // 14
    "G1 Y1\n"                 // 15
    "M30\n";                  // 16

TEST(Contours, FoundWithTheLinesThatEndThem) {
  const plan::Job job = parse(kJob);
  const std::string text = kJob;
  const std::vector<Contour> c = find_contours(job, text);
  ASSERT_EQ(c.size(), 3u);
  const auto line = [&](size_t block) { return job.blocks.at(block).loc.line; };
  EXPECT_EQ(line(c[0].first_block), 4);
  EXPECT_EQ(line(c[0].last_block), 6);
  EXPECT_EQ(c[0].m5_line, 8);
  EXPECT_EQ(line(c[1].first_block), 10);
  EXPECT_EQ(line(c[1].last_block), 11);
  EXPECT_EQ(c[1].m5_line, 12);
  EXPECT_EQ(line(c[2].first_block), 15);
  EXPECT_EQ(c[2].m5_line, 16);
}

TEST(Contours, ResumedRunRapidsToTheNextPierceThenRunsToTheEnd) {
  const plan::Job job = parse(kJob);
  const std::vector<Contour> c = find_contours(job, kJob);
  ContourSelection s;
  s.done = 1;
  s.from_mm = plan::PerAxis<double>{2.5, 1.5, 0, 0};
  const plan::Job r = select_contours(job, c, s);
  ASSERT_EQ(r.blocks.size(), 1 + job.blocks.size() - c[1].first_block);
  const plan::MotionBlock& rapid = r.blocks[0];
  EXPECT_EQ(rapid.kind, plan::MotionKind::rapid);
  EXPECT_FALSE(torch_on(rapid));
  EXPECT_EQ(rapid.start, (plan::PerAxis<double>{2.5, 1.5, 0, 0}));
  EXPECT_EQ(rapid.end, (plan::PerAxis<double>{5, 5, 0, 0}));
  EXPECT_EQ(rapid.loc.line, 9);  // the G0 to the pierce point
  EXPECT_EQ(r.blocks[1].kind, plan::MotionKind::dwell);  // the pierce, again
  EXPECT_DOUBLE_EQ(r.blocks[1].dwell_s, 0.2);
  // The G91 move after contour 2 keeps the interpreter's position: from X6.
  EXPECT_DOUBLE_EQ(r.blocks.back().end[0], 7);
  EXPECT_EQ(r.blocks.back().loc.line, 15);

  // Stopped after contour 2: the blocks up to its last, from the job's start.
  ContourSelection stop;
  stop.stop_after = 2;
  const plan::Job p = select_contours(job, c, stop);
  ASSERT_EQ(p.blocks.size(), c[1].last_block + 1);
  EXPECT_EQ(p.blocks.back().loc.line, 11);
  EXPECT_EQ(p.blocks.front().loc.line, job.blocks.front().loc.line);
}

TEST(Contours, DoneCountsContoursWhoseLastMoveWasMade) {
  const std::vector<uint64_t> ends = {100, 250, 250, 400};
  EXPECT_EQ(contours_done(ends, 0), 0u);
  EXPECT_EQ(contours_done(ends, 99), 0u);
  EXPECT_EQ(contours_done(ends, 100), 1u);
  EXPECT_EQ(contours_done(ends, 249), 1u);
  EXPECT_EQ(contours_done(ends, 250), 3u);
  EXPECT_EQ(contours_done(ends, 400), 4u);
}

}  // namespace
}  // namespace cpstep::run
