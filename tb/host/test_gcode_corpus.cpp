// SPDX-License-Identifier: MIT
// The G-code corpus (examples/gcode/, README there): programs written here in
// the dialects of common CAM posts and hand-written LinuxCNC code. Every one
// plans on the machine it is written for; the refused ones are refused with
// file:line:col on every error.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <regex>
#include <string>

#include <unistd.h>

#include <fmt/format.h>

#include "cpstep/builds.h"
#include "plan/gcode.h"
#include "plan/nurbs.h"
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

namespace {

// Two blocks the same, field by field (a curve: the same control points).
void expect_same_block(const MotionBlock& a, const MotionBlock& b, std::size_t i) {
    ASSERT_EQ(a.kind, b.kind) << "block " << i;
    ASSERT_EQ(a.loc, b.loc) << "block " << i;
    ASSERT_EQ(a.start, b.start) << "block " << i;
    ASSERT_EQ(a.end, b.end) << "block " << i;
    ASSERT_EQ(a.center_x, b.center_x) << "block " << i;
    ASSERT_EQ(a.center_y, b.center_y) << "block " << i;
    ASSERT_EQ(a.center_z, b.center_z) << "block " << i;
    ASSERT_EQ(a.feed, b.feed) << "block " << i;
    ASSERT_EQ(a.dwell_s, b.dwell_s) << "block " << i;
    ASSERT_EQ(a.spindle_on, b.spindle_on) << "block " << i;
    ASSERT_EQ(a.output0, b.output0) << "block " << i;
    ASSERT_EQ(a.plane, b.plane) << "block " << i;
    ASSERT_EQ(a.pause, b.pause) << "block " << i;
    ASSERT_EQ(a.tool, b.tool) << "block " << i;
    ASSERT_EQ(a.curve != nullptr, b.curve != nullptr) << "block " << i;
    if (a.curve) {
        ASSERT_EQ(a.curve->points().size(), b.curve->points().size()) << "block " << i;
        for (std::size_t k = 0; k < a.curve->points().size(); ++k)
            ASSERT_EQ(a.curve->points()[k], b.curve->points()[k]) << "block " << i;
    }
}

// The file read whole and streamed: the same blocks, errors and warnings.
void expect_stream_is_whole(const std::string& path, const GcodeOptions& o) {
    SCOPED_TRACE(path);
    auto whole = load_gcode(path, o);
    std::vector<MotionBlock> got;
    auto streamed = stream_gcode(path, o, [&](MotionBlock&& b, std::size_t i) {
        ASSERT_EQ(i, got.size());
        got.push_back(std::move(b));
    });
    EXPECT_EQ(join(streamed.errors), join(whole.errors));
    EXPECT_EQ(join(streamed.warnings), join(whole.warnings));
    EXPECT_EQ(streamed.ok(), whole.ok());
    if (!whole.ok()) {
        std::ifstream in(path, std::ios::binary);
        auto text = std::make_shared<std::string>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        GcodeBlockReader reader(text, path, o);
        while (reader.next()) {
        }
        EXPECT_EQ(join(reader.result().errors), join(whole.errors));
        return;
    }
    ASSERT_EQ(got.size(), whole->blocks.size());
    for (std::size_t i = 0; i < got.size(); ++i) expect_same_block(got[i], whole->blocks[i], i);
    const auto pull_all = [&](GcodeBlockReader& r) {
        std::size_t k = 0;
        while (auto b = r.next()) {
            ASSERT_LT(k, whole->blocks.size());
            expect_same_block(*b, whole->blocks[k], k);
            ++k;
        }
        EXPECT_EQ(k, whole->blocks.size());
        EXPECT_TRUE(r.result().ok());
        EXPECT_EQ(join(r.result().warnings), join(whole.warnings));
    };
    // And pulled from the file's text, block by block.
    std::ifstream in(path, std::ios::binary);
    auto text = std::make_shared<std::string>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    GcodeBlockReader reader(text, path, o);
    pull_all(reader);
    // And from the file with its mark taken, then again checked against the mark.
    GcodeFileMark mark;
    {
        GcodeBlockReader first(path, o, &mark);
        pull_all(first);
    }
    const auto size = std::filesystem::file_size(path);
    EXPECT_EQ(mark.size, size);
    EXPECT_EQ(mark.pieces.size(), size / kGcodePiece + 1);
    GcodeBlockReader again(std::make_shared<const GcodeFileMark>(mark), o);
    pull_all(again);
}

}  // namespace

// Every program of the corpus and every example job (but the probing one)
// streamed block by block gives what load_gcode() gives.
TEST(StreamGcode, EveryCorpusProgramAndExampleJobStreamsAsItReadsWhole) {
    const Machine m = bound_machine("router.toml");
    std::size_t files = 0;
    for (const char* dir : {"/gcode/", "/gcode/refused/", "/jobs/"}) {
        for (const auto& e : std::filesystem::directory_iterator(std::string(CPSTEP_EXAMPLES_DIR) + dir)) {
            const std::string path = e.path().string();
            if (!e.is_regular_file() || path.ends_with("README.md") || path.ends_with("probe.ngc")) continue;
            expect_stream_is_whole(path, gcode_options(m));
            expect_stream_is_whole(path, {});
            ++files;
        }
    }
    EXPECT_GT(files, 15u);
}

// Lines across the 64 KiB pieces it reads, a byte-order mark, CR LF, no newline
// at the end, text after M2, binary data and an unopenable file.
TEST(StreamGcode, PiecesMarksLineEndsAndRefusals) {
    const auto dir = std::filesystem::temp_directory_path() / fmt::format("cpstep_stream_{}", ::getpid());
    std::filesystem::create_directories(dir);
    const auto write = [&](const std::string& name, const std::string& text) {
        const auto p = dir / name;
        std::ofstream(p, std::ios::binary) << text;
        return p.string();
    };
    std::string long_lines = "\xEF\xBB\xBFG21 G90 G1 F600\r\n";
    for (int i = 0; long_lines.size() < 300000; ++i) {
        long_lines += fmt::format("G1 X{:.4f} Y{:.4f} (", 10 + (i % 50) * 0.1, 10 + (i % 7) * 0.3);
        long_lines += std::string(std::size_t(i * 37 % 3000), 'c') + ")\r\n";
    }
    expect_stream_is_whole(write("long.ngc", long_lines), {});
    expect_stream_is_whole(write("no_newline.ngc", "G1 X1 F100\nG1 X2"), {});
    expect_stream_is_whole(write("after_end.ngc", "G1 X1 F100\nM2\nG1 X5\n"), {});
    expect_stream_is_whole(write("bad_line.ngc", "G1 X1 F100\nG1 X2 Q\nG1 X3\n"), {});
    expect_stream_is_whole(write("binary.ngc", std::string("G1 X1\n\0\0\0", 9)), {});
    expect_stream_is_whole(write("open_curve.ngc", "G1 X1 F100\nG5.2 X1 Y2 P1 L3\nX2 Y3 P1\nX3 Y1 P1\n"), {});
    auto missing = stream_gcode(dir / "none.ngc", {}, [](MotionBlock&&, std::size_t) {});
    EXPECT_EQ(join(missing.errors), (dir / "none.ngc").string() + ": cannot open file");
    std::filesystem::remove_all(dir);
}

// A file read against the mark of an earlier reading: a byte changed in its
// second piece, bytes added, bytes cut, each written over the file itself. The
// reading stops at the piece that differs (the blocks before it as they were),
// with an error at that piece's first line naming the bytes; the same bytes
// again (rewritten) read through. A file saved over it under its name, or the
// name removed, leave the file planned to be read (it is kept open).
TEST(StreamGcode, AFileChangedAfterItsMarkStopsTheReading) {
    const auto path = std::filesystem::temp_directory_path() / fmt::format("cpstep_mark_{}.ngc", ::getpid());
    std::string text = "G21 G90 G1 F600\n";
    for (int i = 0; text.size() < 3 * kGcodePiece; ++i) text += fmt::format("G1 X{} Y{}\n", 10 + i % 2, 10 + i % 3);
    const auto write = [&](const std::string& t) { std::ofstream(path, std::ios::binary | std::ios::trunc) << t; };
    write(text);
    GcodeFileMark mark;
    std::size_t blocks = 0;
    {
        GcodeBlockReader first(path, {}, &mark);
        while (first.next()) ++blocks;
        ASSERT_TRUE(first.result().ok());
    }
    ASSERT_EQ(mark.pieces.size(), 4u);
    const auto shared = std::make_shared<const GcodeFileMark>(mark);
    const auto read = [&](std::size_t& n) {
        GcodeBlockReader r(shared, {});
        n = 0;
        while (r.next()) ++n;
        return r.result();
    };
    // The line that holds the piece's first byte, counted as the reader counts lines.
    const auto line_at = [&](std::size_t byte) { return int(std::count(text.begin(), text.begin() + long(byte), '\n')) + 1; };
    std::size_t n = 0;
    EXPECT_TRUE(read(n).ok());
    EXPECT_EQ(n, blocks);

    std::string changed = text;
    const std::size_t at = kGcodePiece + 1000;
    changed[changed.find("Y1", at) + 1] = '2';  // Y1 -> Y2: the same length
    write(changed);
    auto r = read(n);
    ASSERT_EQ(r.errors.size(), 1u);
    EXPECT_EQ(r.errors[0].str(), fmt::format("{}:{}:1: the file changed after the job was planned from it: bytes {} to "
                                             "{} differ ({} bytes then, {} now)",
                                             path.string(), line_at(kGcodePiece), kGcodePiece, 2 * kGcodePiece - 1,
                                             text.size(), text.size()));
    EXPECT_LT(n, blocks);
    EXPECT_GT(n, blocks / 4);  // the first piece's blocks came out

    write(text + "G1 X5\n");
    r = read(n);
    ASSERT_EQ(r.errors.size(), 1u);
    EXPECT_NE(r.errors[0].message.find(fmt::format("bytes {} to", 3 * kGcodePiece)), std::string::npos)
        << r.errors[0].str();
    EXPECT_NE(r.errors[0].message.find(fmt::format("{} now", text.size() + 6)), std::string::npos);

    write(text.substr(0, text.size() - 100));
    r = read(n);
    ASSERT_EQ(r.errors.size(), 1u);
    EXPECT_NE(r.errors[0].message.find("changed after the job was planned"), std::string::npos);

    write(text);
    EXPECT_TRUE(read(n).ok());
    EXPECT_EQ(n, blocks);
    // Another file saved under its name (written aside, renamed over it, as
    // editors save), or the name removed: the file planned is still read.
    const auto other = path.string() + ".new";
    std::ofstream(other, std::ios::binary) << changed;
    std::filesystem::rename(other, path);
    EXPECT_TRUE(read(n).ok());
    EXPECT_EQ(n, blocks);
    std::filesystem::remove(path);
    EXPECT_TRUE(read(n).ok());
    EXPECT_EQ(n, blocks);
    // A mark without its open file opens the name again: gone.
    GcodeFileMark bare = mark;
    bare.descriptor.reset();
    GcodeBlockReader gone(std::make_shared<const GcodeFileMark>(bare), {});
    EXPECT_FALSE(gone.next());
    ASSERT_FALSE(gone.result().ok());
    EXPECT_EQ(gone.result().errors[0].str(), path.string() + ": cannot open file");
}

// Blocks come out as their lines are read: a program whose error is on its
// last line has handed out every block before it when the error is found.
TEST(StreamGcode, BlocksComeOutBeforeTheRestIsRead) {
    const auto path = std::filesystem::temp_directory_path() / fmt::format("cpstep_stream_late_{}.ngc", ::getpid());
    {
        std::ofstream out(path);
        out << "G1 F600\n";
        for (int i = 0; i < 100000; ++i) out << fmt::format("G1 X{} Y{}\n", 10 + i % 2, 10 + i % 3);
        out << "G1 X1 Q\n";
    }
    std::size_t n = 0;
    auto r = stream_gcode(path, {}, [&](MotionBlock&&, std::size_t) { ++n; });
    EXPECT_FALSE(r.ok());
    EXPECT_GE(n, 100000u);
    std::filesystem::remove(path);
}
