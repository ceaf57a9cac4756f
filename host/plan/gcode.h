// The G-code subset CAM post-processors emit, parsed into motion blocks in
// machine millimetres with every modal state resolved.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "plan/common.h"

namespace cpstep::plan {

enum class MotionKind {
    rapid,    // G0: at the machine's limits
    linear,   // G1 at the feed rate
    arc_cw,   // G2 in the XY plane (helical when Z/A move too)
    arc_ccw,  // G3
    dwell,    // G4 P<seconds>: zero motion, a real pause
};

struct MotionBlock {
    MotionKind kind = MotionKind::linear;
    SourceLoc loc;               // the block's first word
    PerAxis<double> start{};     // machine mm
    PerAxis<double> end{};       // machine mm
    double center_x = 0;         // arcs: centre in machine mm
    double center_y = 0;
    double feed = 0;             // mm/s (G1/G2/G3); 0 for G0 and G4
    double dwell_s = 0;          // G4 only
    bool spindle_on = false;     // M3/M4 ... M5 state while this block runs
    double spindle_speed = 0;    // last S word (recorded, not interpreted)
};

struct Job {
    std::string file;
    std::vector<MotionBlock> blocks;
};

struct GcodeOptions {
    // Machine position when the job starts (the card's counters at zero = 0 mm).
    PerAxis<double> start_position{};
};

// Codes that are accepted and deliberately do nothing (see docs/PLANNING.md).
std::span<const std::string_view> ignored_codes();

// Parse a whole job. Every error is collected; any error refuses the job.
Result<Job> parse_gcode(std::string_view text, std::string_view file,
                        const GcodeOptions& options = {});
Result<Job> load_gcode(const std::filesystem::path& path, const GcodeOptions& options = {});

}  // namespace cpstep::plan
