// SPDX-License-Identifier: MIT
// RS274NGC as LinuxCNC and Grbl users write it (docs/PLANNING.md, G-code),
// parsed into motion blocks in machine millimetres with every modal state,
// offset, parameter and canned cycle resolved.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "plan/common.h"
#include "plan/machine.h"

namespace cpstep::plan {

class Nurbs;  // plan/nurbs.h

enum class MotionKind {
    rapid,    // G0: at the machine's limits
    linear,   // G1 at the feed rate
    arc_cw,   // G2 in the block's plane (helical when the other axes move too)
    arc_ccw,  // G3
    dwell,    // G4 P<seconds>: zero motion, a real pause; M0/M1: a stop (see pause)
    nurbs,    // G5, G5.1, G5.2..G5.3: a rational B-spline in the XY plane (MotionBlock::curve)
};

// The plane of an arc (G17 / G18 / G19), named by its first and second axis in
// RS274NGC's order: the arc turns from the first towards the second for G3.
enum class Plane { xy, zx, yz };

// Why a dwell block stops (M0 / M1); none for G4 and canned-cycle dwells.
enum class PauseKind { none, program_stop, optional_stop };

struct MotionBlock {
    MotionKind kind = MotionKind::linear;
    SourceLoc loc;               // the block's first word
    PerAxis<double> start{};     // machine mm (A: degrees)
    PerAxis<double> end{};       // machine mm
    double center_x = 0;         // arcs: centre in machine mm (the two of the plane's axes)
    double center_y = 0;
    double feed = 0;             // mm/s (G1/G2/G3); 0 for G0 and G4
    double dwell_s = 0;          // G4 only
    bool spindle_on = false;     // M3/M4 ... M5 state while this block runs
    bool output0 = false;        // digital output P0 (M62/M63 with the next motion, M64/M65 at once)
    double spindle_speed = 0;    // last S word (recorded, not interpreted)
    // Added with RS274NGC coverage (all default to the old meaning):
    Plane plane = Plane::xy;     // arcs: G17 / G18 / G19
    double center_z = 0;         // arcs in G18 / G19: the centre's Z, machine mm
    PauseKind pause = PauseKind::none;  // dwell blocks from M0 / M1: dwell_s = 0, a full stop
    bool spindle_ccw = false;    // M4 (true) or M3 while spindle_on
    int tool = 0;                // tool in the spindle (T ... M6)
    // nurbs blocks: the curve in machine mm, from start (its first control
    // point) to end (its last); Z stays at start's (docs/CURVES.md).
    std::shared_ptr<const Nurbs> curve;
};

// An arc's plane as axis indices and its centre in those axes: the arc turns
// from `first` towards `second` for G3 (counter-clockwise seen from the
// positive end of the third axis). The remaining axes move linearly.
struct ArcFrame {
    std::size_t first = 0, second = 1;
    double center_first = 0, center_second = 0;
};
ArcFrame arc_frame(const MotionBlock& b);

struct Job {
    std::string file;
    std::vector<MotionBlock> blocks;
    // Blocks before this index were handed to a probe handler, which ran them before
    // its probe move (GcodeOptions::probe); the rest run after the program's last probe.
    std::size_t probed_blocks = 0;
    std::size_t probes = 0;  // G38.x moves handed to the probe handler
};

// A G38.2..G38.5 probe move (docs/HOST.md "Probing"): from where the program stands
// to the target, at the feed, until the probe makes (G38.2/G38.3) or breaks
// (G38.4/G38.5) contact; G38.2 and G38.4 are errors when it does not.
struct ProbeRequest {
    SourceLoc loc;                       // the G38 word
    std::string code;                    // "G38.2", ...
    bool contact = true;                 // G38.2/G38.3: trip on contact; G38.4/G38.5: on its loss
    bool must_trip = true;               // G38.2/G38.4
    PerAxis<double> from{}, to{};        // machine mm
    double feed = 0;                     // mm/s
    // The program's blocks not yet run (job.blocks from probed_blocks on): the
    // handler runs them first, then the probe move.
    std::span<const MotionBlock> before;
};
struct ProbeResult {
    bool tripped = false;
    PerAxis<double> at{};                // machine mm where the motion stopped (the trip, or the target)
    std::string error;                   // "": the move ran; else why not (the program stops there)
};
using ProbeHandler = std::function<ProbeResult(const ProbeRequest&)>;

struct GcodeOptions {
    // Machine position when the job starts (the card's counters at zero = 0 mm).
    PerAxis<double> start_position{};
    // Axes the machine has; words for others are refused (Z by z_words). Unset:
    // every axis is accepted here and the planner checks (make_step_segments).
    std::optional<PerAxis<bool>> axes_present;
    MissingZ z_words = MissingZ::refuse;
    std::optional<PerAxis<double>> g28_position;  // machine mm; unset: the origin
    std::optional<PerAxis<double>> g30_position;
    std::map<int, double> tool_lengths;           // G43 H<n>, mm
    std::size_t max_errors = 20;                  // reported; the rest are counted
    // Canned cycles (G73 ... G89) expand into blocks here: one cycle block into at
    // most max_cycle_block holes x pecks (L x depth/Q), all of a program's cycle
    // blocks together into at most max_cycle_job, so that a few kilobytes of text
    // cannot make a job of gigabytes (docs/PLANNING.md).
    double max_cycle_block = 1e5;
    double max_cycle_job = 1e6;
    // G38.2..G38.5: runs everything before the probe move and the move itself on the
    // card and says where it stopped; the program goes on from there with
    // #5061..#5064 (the trip in the coordinate system in effect, program units) and
    // #5070 (1 tripped, 0 not) set as LinuxCNC sets them. Unset: G38 is refused.
    ProbeHandler probe;
};

// The options a machine file gives (its axes, [gcode] table), starting at `start`.
GcodeOptions gcode_options(const Machine& machine, const PerAxis<double>& start = {});

// Repeated diagnostics collapsed: messages that differ only in their numbers
// become the first one with "(N times, lines A-B)". Order is kept.
std::vector<Diagnostic> summarize_repeats(std::vector<Diagnostic> diags);

// Codes that are accepted and deliberately do nothing (see docs/PLANNING.md).
std::span<const std::string_view> ignored_codes();

// True when some line of `text` has a G38.2..G38.5 word (read word by word, as the
// parser reads them; comments do not count). Builds no blocks: cheap beside parsing.
bool has_probe_words(std::string_view text);
// The same for a file read line by line (false when it cannot be read).
bool file_has_probe_words(const std::filesystem::path& path);

// Parse a whole job. Every error is collected; any error refuses the job.
Result<Job> parse_gcode(std::string_view text, std::string_view file,
                        const GcodeOptions& options = {});
Result<Job> load_gcode(const std::filesystem::path& path, const GcodeOptions& options = {});

// What one reading of a G-code file found, so that a later reading knows it
// reads the same bytes: the file's size and a hash (std::hash of the bytes) of
// each piece of kGcodePiece bytes, in order (the last piece shorter, possibly
// empty), and the file as it was opened then, kept open: a later reading reads
// that file, even when another has since been saved under its name (as editors
// and CAM programs save: a new file renamed over the old), and the hashes tell
// when the file itself was written over. A run that plans its job again from
// the file as it sends it keeps this, not the text (docs/HOST.md "Streamed").
inline constexpr std::size_t kGcodePiece = std::size_t{1} << 16;
struct GcodeFileMark {
    std::string path;
    std::uint64_t size = 0;
    std::vector<std::size_t> pieces;
    std::shared_ptr<const int> descriptor;  // the open file (closed with the last owner)
};

// A program's blocks pulled one at a time: parse_gcode()'s blocks, a line read
// as each is asked for. next() gives none at the program's end, and then
// result() holds its errors and warnings (an accepted program's Job without its
// blocks); a refused program may have given blocks before its error was read.
class GcodeBlockReader {
public:
    // From a text the caller holds (the whole text one piece).
    GcodeBlockReader(std::shared_ptr<const std::string> text, std::string file, const GcodeOptions& options = {});
    // From a file, read a piece of kGcodePiece bytes at a time; with `mark`,
    // what this reading finds is recorded there (its size and pieces' hashes).
    GcodeBlockReader(const std::filesystem::path& path, const GcodeOptions& options, GcodeFileMark* mark = nullptr);
    // From the file a mark was taken of, each piece checked against it as it is
    // read: a piece that differs (the file changed since) stops the reading, and
    // result() holds the error "the file changed after it was read", at the
    // piece's first line, with the bytes that differ.
    GcodeBlockReader(std::shared_ptr<const GcodeFileMark> mark, const GcodeOptions& options);
    ~GcodeBlockReader();
    GcodeBlockReader(const GcodeBlockReader&) = delete;
    GcodeBlockReader& operator=(const GcodeBlockReader&) = delete;
    std::optional<MotionBlock> next();
    [[nodiscard]] const Result<Job>& result() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The program read from a file a piece at a time, each block handed to `sink`
// (with its index among the program's blocks) once its line is read: the blocks
// load_gcode() gives, in memory that does not grow with the file (each block is
// made whole: a canned cycle's holes, a G5.2 curve's points). The result holds
// the program's errors and warnings, and a Job without blocks when it is
// accepted. A refused program may have handed blocks out before its error was
// read: a caller that must not act on part of a bad program reads it twice
// (docs/HOST.md "Streamed"). A program with probe moves (options.probe) is read
// whole, not this way.
Result<Job> stream_gcode(const std::filesystem::path& path, const GcodeOptions& options,
                         const std::function<void(MotionBlock&&, std::size_t)>& sink);

}  // namespace cpstep::plan
