// SPDX-License-Identifier: MIT
#include "plan/common.h"

#include <fmt/format.h>

namespace cpstep::plan {

std::string Diagnostic::str() const {
    if (loc.line > 0) {
        return fmt::format("{}:{}:{}: {}", file, loc.line, loc.col, message);
    }
    return fmt::format("{}: {}", file, message);
}

std::string join(const std::vector<Diagnostic>& diags) {
    std::string out;
    for (const auto& d : diags) {
        if (!out.empty()) out += '\n';
        out += d.str();
    }
    return out;
}

}  // namespace cpstep::plan
