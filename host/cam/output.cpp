// SPDX-License-Identifier: MIT
#include "cam/output.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <string_view>

namespace cpstep::cam {

namespace {

std::string num(double v) {
  if (std::abs(v) < 5e-5) v = 0;  // no "-0.0000"
  return fmt::format("{:.4f}", v);
}

void move(std::string& out, const Seg& s, bool first_feed, double feed) {
  const std::string f = first_feed ? fmt::format(" F{:.0f}", feed) : "";
  if (s.kind == SegKind::line) {
    out += fmt::format("G1 X{} Y{}{}\n", num(s.b.x), num(s.b.y), f);
    return;
  }
  const Vec2 ij = s.c - s.a;
  out += fmt::format("{} X{} Y{} I{} J{}{}\n", s.ccw() ? "G3" : "G2", num(s.b.x), num(s.b.y), num(ij.x), num(ij.y), f);
}

// A comment the G-code reader takes as it is: no parentheses, commas or other
// punctuation inside it.
std::string comment(const std::string& text) {
  std::string out;
  for (char ch : text) {
    const bool ok = std::isalnum(static_cast<unsigned char>(ch)) || std::string_view(" .:_-/=+%").find(ch) != std::string_view::npos;
    out += ok ? ch : ' ';
  }
  return "(" + out + ")\n";
}

}  // namespace

std::string write_gcode(const CutPlan& plan, const GcodeInfo& info) {
  std::string out = "%\n";
  for (const std::string& h : info.header) out += comment(h);
  out += "G21 G90 G17 G94\n";
  int n = 0;
  for (const Cut& c : plan.cuts) {
    ++n;
    const std::string part = c.part < int(info.part_names.size()) ? info.part_names[std::size_t(c.part)]
                                                                  : "part " + std::to_string(c.part + 1);
    out += comment(fmt::format("cut {}: {} {} {}", n, part, c.contour ? (c.hole ? "hole" : "outline") : "open chain",
                               c.chain + 1));
    out += fmt::format("G0 X{} Y{}\n", num(c.pierce.x), num(c.pierce.y));
    out += "M3\n";
    if (c.delay > 0) out += fmt::format("G4 P{:.3f}\n", c.delay);
    bool first = true;
    if (c.lead_in) { move(out, *c.lead_in, first, info.feed_mm_min); first = false; }
    for (const Seg& s : c.path) { move(out, s, first, info.feed_mm_min); first = false; }
    if (c.lead_out) move(out, *c.lead_out, false, info.feed_mm_min);
    out += "M5\n";
  }
  out += "M30\n%\n";
  return out;
}

namespace {

struct SvgMap {
  double h;
  std::string p(Vec2 v) const { return fmt::format("{:.3f},{:.3f}", v.x, h - v.y); }
};

std::string path_d(const std::vector<Seg>& segs, const SvgMap& m) {
  std::string d;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Seg& s = segs[i];
    if (i == 0 || dist(segs[i - 1].b, s.a) > 1e-6) d += "M" + m.p(s.a) + " ";
    if (s.kind == SegKind::line) { d += "L" + m.p(s.b) + " "; continue; }
    if (!s.is_circular()) {
      std::vector<Vec2> pts;
      s.flatten(0.01, pts, false);
      for (Vec2 q : pts) d += "L" + m.p(q) + " ";
      continue;
    }
    // SVG arcs cannot close a circle in one command: two halves
    const double r = s.radius();
    const int pieces = s.sweep() > kPi ? 2 : 1;
    for (int k = 1; k <= pieces; ++k) {
      const Vec2 e = s.at(s.t0 + (s.t1 - s.t0) * k / pieces);
      // y is flipped: counter-clockwise in the plane is sweep-flag 0 in SVG
      d += fmt::format("A{:.3f},{:.3f} 0 0 {} {} ", r, r, s.ccw() ? 0 : 1, m.p(e));
    }
  }
  return d;
}

}  // namespace

std::string write_svg(const CutPlan& plan, const Sheet& sheet) {
  const SvgMap m{sheet.height};
  std::string o = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.1f}mm\" height=\"{1:.1f}mm\" viewBox=\"-5 -5 {2:.3f} {3:.3f}\">\n",
      sheet.width + 10, sheet.height + 10, sheet.width + 10, sheet.height + 10);
  o += "<style>.sheet{fill:#eef0f2;stroke:#555;stroke-width:0.4}.margin{fill:none;stroke:#999;stroke-width:0.3;stroke-dasharray:2,1}"
       ".invalid{fill:#f4c7c3;stroke:#c0392b;stroke-width:0.3}.cut{fill:none;stroke:#111;stroke-width:0.35}"
       ".lead{fill:none;stroke:#1e8449;stroke-width:0.35}.rapid{fill:none;stroke:#2e86c1;stroke-width:0.25;stroke-dasharray:1.5,1}"
       ".pierce{fill:#c0392b}.num{font:3px sans-serif;fill:#c0392b}</style>\n";
  o += fmt::format("<rect class=\"sheet\" x=\"0\" y=\"0\" width=\"{:.3f}\" height=\"{:.3f}\"/>\n", sheet.width, sheet.height);
  const Box u = sheet.usable();
  o += fmt::format("<rect class=\"margin\" x=\"{:.3f}\" y=\"{:.3f}\" width=\"{:.3f}\" height=\"{:.3f}\"/>\n", u.lo.x,
                   sheet.height - u.hi.y, u.width(), u.height());
  for (const Box& b : sheet.invalid)
    o += fmt::format("<rect class=\"invalid\" x=\"{:.3f}\" y=\"{:.3f}\" width=\"{:.3f}\" height=\"{:.3f}\"/>\n", b.lo.x,
                     sheet.height - b.hi.y, b.width(), b.height());
  Vec2 pos = plan.base;
  std::string rapids, cuts, leads, marks;
  int n = 0;
  for (const Cut& c : plan.cuts) {
    ++n;
    rapids += "M" + m.p(pos) + " L" + m.p(c.pierce) + " ";
    cuts += path_d(c.path, m);
    if (c.lead_in) leads += path_d({*c.lead_in}, m);
    if (c.lead_out) leads += path_d({*c.lead_out}, m);
    marks += fmt::format("<circle class=\"pierce\" cx=\"{:.3f}\" cy=\"{:.3f}\" r=\"0.6\"/><text class=\"num\" x=\"{:.3f}\" y=\"{:.3f}\">{}</text>\n",
                         c.pierce.x, sheet.height - c.pierce.y, c.pierce.x + 0.8, sheet.height - c.pierce.y - 0.8, n);
    pos = c.lead_out ? c.lead_out->b : c.path.back().b;
  }
  o += "<path class=\"cut\" d=\"" + cuts + "\"/>\n";
  o += "<path class=\"lead\" d=\"" + leads + "\"/>\n";
  o += "<path class=\"rapid\" d=\"" + rapids + "\"/>\n";
  o += marks;
  o += "</svg>\n";
  return o;
}

}  // namespace cpstep::cam
