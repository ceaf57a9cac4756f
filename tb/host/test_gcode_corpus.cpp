// SPDX-License-Identifier: MIT
// The G-code corpus (examples/gcode/, README there): programs written here in
// the dialects of common CAM posts and hand-written LinuxCNC code. Every one
// plans on the machine it is written for; the refused ones are refused with
// file:line:col on every error.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "cpstep/builds.h"
#include "plan/gcode.h"
#include "plan/pipeline.h"

using namespace cpstep::plan;

namespace {

const std::string kDir = std::string(CPSTEP_EXAMPLES_DIR) + "/gcode/";

Machine bound_machine(const std::string& name) {
    auto loaded = load_machine(std::string(CPSTEP_EXAMPLES_DIR) + "/machines/" + name);
    EXPECT_TRUE(loaded.ok()) << join(loaded.errors);
    Machine m = *loaded;
    // Planned for the default board's card (rtl/builds.json), as `cpstep plan` does.
    const cpstep::builds::Build& b = *cpstep::builds::find(cpstep::builds::kDefaultBoard);
    const auto errors = bind_card(m, {std::string(b.name), double(b.clock_hz), b.w, b.kmax, b.tw});
    EXPECT_TRUE(errors.empty()) << join(errors);
    return m;
}

struct Program {
    const char* file;
    const char* machine;
    const char* warnings;  // every warning the reader gives, joined
};

}  // namespace

class Corpus : public ::testing::TestWithParam<Program> {};

TEST_P(Corpus, Plans) {
    const Program& p = GetParam();
    const Machine m = bound_machine(p.machine);
    auto job = load_gcode(kDir + p.file, gcode_options(m));
    ASSERT_TRUE(job.ok()) << join(job.errors);
    std::string w = join(job.warnings);
    const std::string prefix = kDir + p.file + ":";
    for (std::size_t at; (at = w.find(prefix)) != std::string::npos;) w.replace(at, prefix.size(), "");
    EXPECT_EQ(w, p.warnings);
    EXPECT_GT(job->blocks.size(), 10u);
    auto plan = plan_job(*job, m);
    ASSERT_TRUE(plan.ok()) << join(plan.errors);
    EXPECT_GT(plan->stats.moves, 1000u);
}

INSTANTIATE_TEST_SUITE_P(
    All, Corpus,
    ::testing::Values(
        Program{"linuxcnc_params.ngc", "router.toml", ""},
        Program{"linuxcnc_inch.ngc", "router.toml", ""},
        Program{"fusion360_router.nc", "router.toml", ""},
        Program{"fusion360_grbl.nc", "router.toml", ""},
        Program{"freecad_path.ngc", "router.toml", ""},
        Program{"gcodetools_inkscape.ngc", "plotter.toml",
                "11:1: the program sets no units (G20/G21): millimetres assumed"},
        Program{"pcb2gcode_drill.ngc", "router.toml", ""},
        Program{"dxf2gcode_contour.ngc", "router.toml", ""},
        Program{"sheetcam_plasma.tap", "router.toml", ""},
        Program{"plotter_pen.ngc", "plotter.toml", ""}),
    [](const auto& p) {
        std::string n = p.param.file;
        for (auto& ch : n)
            if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
        return n;
    });

TEST(CorpusRefused, EveryErrorHasFileLineColumn) {
    const Machine m = bound_machine("router.toml");
    struct Case {
        const char* file;
        std::vector<std::string> errors;  // after "<path>:"
    };
    const Case cases[] = {
        {"refused/o_word_loop.ngc",
         {"4:1: O-word 'o100while[#1lt3]': subroutines, loops and conditionals (o-codes) are not supported; "
          "expand them before planning",
          "7:1: O-word 'o100endwhile': subroutines, loops and conditionals (o-codes) are not supported; "
          "expand them before planning"}},
        {"refused/probe.ngc", {"5:1: G38.2: probing needs a card with a probe input, on `cpstep run` (docs/HOST.md \"Probing\")"}},
        {"refused/garbage.ngc", {"3:10: unexpected character '@'", "5:20: unexpected character '~'"}},
    };
    const std::regex shape(R"(^.+:[0-9]+:[0-9]+: .+$)");
    for (const auto& c : cases) {
        auto job = load_gcode(kDir + c.file, gcode_options(m));
        EXPECT_FALSE(job.ok()) << c.file;
        std::vector<std::string> got;
        for (const auto& e : job.errors) {
            EXPECT_TRUE(std::regex_match(e.str(), shape)) << e.str();
            std::string s = e.str();
            const std::string prefix = kDir + c.file + ":";
            if (s.rfind(prefix, 0) == 0) s = s.substr(prefix.size());
            got.push_back(s);
        }
        EXPECT_EQ(got, c.errors) << c.file;
    }
}
