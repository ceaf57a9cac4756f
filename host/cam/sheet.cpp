// SPDX-License-Identifier: MIT
#include "cam/sheet.h"

#include <polyclipping/clipper.hpp>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "cam/nest.h"

namespace cpstep::cam {

Box Sheet::usable() const {
  Box b;
  b.add({margin_left, margin_bottom});
  b.add({width - margin_right, height - margin_top});
  return b;
}

namespace {

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  std::string at(const toml::source_region& s) const {
    return file_ + ":" + std::to_string(s.begin.line) + ":" + std::to_string(s.begin.column) + ": ";
  }
  void error(const toml::node& n, const std::string& m) { errors.push_back(at(n.source()) + m); }
  void error_file(const std::string& m) { errors.push_back(file_ + ": " + m); }

  void only_keys(const toml::table& t, const std::string& path, std::initializer_list<std::string_view> allowed) {
    for (auto&& [k, v] : t)
      if (std::find(allowed.begin(), allowed.end(), k.str()) == allowed.end()) {
        std::string where = k.source().begin.line ? at(k.source()) : at(v.source());
        errors.push_back(where + (path.empty() ? "" : path + ".") + std::string(k.str()) + ": unknown key");
      }
  }
  std::optional<double> number(const toml::table& t, const std::string& path, std::string_view key, bool required,
                               bool (*ok)(double), const char* what) {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) errors.push_back(at(t.source()) + path + "." + std::string(key) + ": missing");
      return std::nullopt;
    }
    if (!n->is_number()) { error(*n, path + "." + std::string(key) + ": must be a number"); return std::nullopt; }
    const double v = n->value<double>().value_or(0);
    if (!std::isfinite(v) || !ok(v)) { error(*n, path + "." + std::string(key) + ": must be " + what); return std::nullopt; }
    return v;
  }
  std::optional<std::string> string(const toml::table& t, const std::string& path, std::string_view key,
                                    std::initializer_list<std::string_view> choices) {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    if (!n->is_string()) { error(*n, path + "." + std::string(key) + ": must be a string"); return std::nullopt; }
    std::string v = *n->value<std::string>();
    if (choices.size() && std::find(choices.begin(), choices.end(), v) == choices.end()) {
      std::string list;
      for (auto c : choices) list += (list.empty() ? "" : ", ") + std::string(c);
      error(*n, path + "." + std::string(key) + ": \"" + v + "\" is not one of " + list);
      return std::nullopt;
    }
    return v;
  }
  const toml::table* table(const toml::table& t, std::string_view key, bool required) {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) errors.push_back(file_ + ": [" + std::string(key) + "]: missing table");
      return nullptr;
    }
    if (!n->is_table()) { error(*n, std::string(key) + ": must be a table"); return nullptr; }
    return n->as_table();
  }
  std::vector<std::string> errors;

 private:
  std::string file_;
};

bool positive(double v) { return v > 0; }
bool non_negative(double v) { return v >= 0; }
bool any_value(double) { return true; }
bool count_ok(double v) { return v >= 0 && v <= 100000 && v == std::floor(v); }

Corner corner_of(const std::string& s) {
  if (s == "bottom-right") return Corner::bottom_right;
  if (s == "top-left") return Corner::top_left;
  if (s == "top-right") return Corner::top_right;
  return Corner::bottom_left;
}

}  // namespace

SheetResult parse_sheet(const std::string& text, const std::string& path) {
  SheetResult res;
  Reader r(path);
  toml::table root;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    res.errors.push_back(r.at(e.source()) + std::string(e.description()));
    return res;
  }
  SheetConfig c;
  c.file = path;
  r.only_keys(root, "", {"sheet", "start", "layout", "leads", "chart", "drawing"});
  if (const toml::table* s = r.table(root, "sheet", true)) {
    r.only_keys(*s, "sheet", {"width", "height", "margins", "invalid", "thickness", "material"});
    c.sheet.width = r.number(*s, "sheet", "width", true, positive, "positive (mm)").value_or(0);
    c.sheet.height = r.number(*s, "sheet", "height", true, positive, "positive (mm)").value_or(0);
    c.thickness = r.number(*s, "sheet", "thickness", true, positive, "positive (mm)").value_or(0);
    c.material = r.string(*s, "sheet", "material", {}).value_or("");
    if (const toml::table* m = r.table(*s, "margins", false)) {
      r.only_keys(*m, "sheet.margins", {"left", "right", "top", "bottom"});
      // negative margins are read here and refused by check_sheet with the seed's reason
      c.sheet.margin_left = r.number(*m, "sheet.margins", "left", false, any_value, "").value_or(0);
      c.sheet.margin_right = r.number(*m, "sheet.margins", "right", false, any_value, "").value_or(0);
      c.sheet.margin_top = r.number(*m, "sheet.margins", "top", false, any_value, "").value_or(0);
      c.sheet.margin_bottom = r.number(*m, "sheet.margins", "bottom", false, any_value, "").value_or(0);
    }
    if (const toml::node* inv = s->get("invalid")) {
      const toml::array* arr = inv->as_array();
      if (!arr) r.error(*inv, "sheet.invalid: must be an array of tables { x, y, width, height }");
      else
        for (const toml::node& n : *arr) {
          const toml::table* t = n.as_table();
          if (!t) { r.error(n, "sheet.invalid: each region is a table { x, y, width, height }"); continue; }
          r.only_keys(*t, "sheet.invalid", {"x", "y", "width", "height"});
          const auto x = r.number(*t, "sheet.invalid", "x", true, any_value, "");
          const auto y = r.number(*t, "sheet.invalid", "y", true, any_value, "");
          const auto w = r.number(*t, "sheet.invalid", "width", true, positive, "positive (mm)");
          const auto h = r.number(*t, "sheet.invalid", "height", true, positive, "positive (mm)");
          if (x && y && w && h) {
            Box b;
            b.add({*x, *y});
            b.add({*x + *w, *y + *h});
            c.sheet.invalid.push_back(b);
          }
        }
    }
  }
  if (const toml::table* s = r.table(root, "start", false)) {
    r.only_keys(*s, "start", {"point", "corner"});
    const auto p = r.string(*s, "start", "point", {"corner", "first-part-centre"});
    if (p == "first-part-centre") c.layout.start = StartPoint::first_part_centre;
    if (auto k = r.string(*s, "start", "corner", {"bottom-left", "bottom-right", "top-left", "top-right"}))
      c.layout.corner = corner_of(*k);
  }
  if (const toml::table* l = r.table(root, "layout", false)) {
    r.only_keys(*l, "layout", {"mode", "count", "spacing_x", "spacing_y", "rotate", "order", "gap", "rotations"});
    c.layout.mode = r.string(*l, "layout", "mode", {"array", "nest"}).value_or("array");
    c.layout.count = int(r.number(*l, "layout", "count", false, count_ok, "a whole number from 0").value_or(0));
    c.layout.spacing_x = r.number(*l, "layout", "spacing_x", false, any_value, "").value_or(0);
    c.layout.spacing_y = r.number(*l, "layout", "spacing_y", false, any_value, "").value_or(0);
    c.layout.rotate = r.string(*l, "layout", "rotate", {"none", "alternate-x", "alternate-y", "checker"}).value_or("none");
    c.layout.order = r.string(*l, "layout", "order", {"x-oneway", "x-zigzag", "y-oneway", "y-zigzag", "nearest"})
                         .value_or("x-zigzag");
    c.layout.gap = r.number(*l, "layout", "gap", false, non_negative, "0 or more (mm)").value_or(0);
    if (const toml::node* n = l->get("rotations")) {
      const toml::array* arr = n->as_array();
      if (!arr || arr->empty()) r.error(*n, "layout.rotations: must be a list of angles in degrees");
      else {
        c.layout.rotations.clear();
        for (const toml::node& a : *arr) {
          if (!a.is_number()) { r.error(a, "layout.rotations: must be numbers (degrees)"); continue; }
          c.layout.rotations.push_back(a.value<double>().value_or(0));
        }
      }
    }
  }
  if (const toml::table* l = r.table(root, "leads", false)) {
    r.only_keys(*l, "leads", {"lead_in", "lead_out", "edge_distance"});
    c.lead_in = r.number(*l, "leads", "lead_in", false, non_negative, "0 or more (mm)").value_or(c.lead_in);
    c.lead_out = r.number(*l, "leads", "lead_out", false, non_negative, "0 or more (mm)").value_or(c.lead_out);
    c.edge_distance = r.number(*l, "leads", "edge_distance", false, non_negative, "0 or more (mm)").value_or(c.edge_distance);
  }
  if (const toml::table* d = r.table(root, "drawing", false)) {
    r.only_keys(*d, "drawing", {"tolerance", "unitless_mm"});
    c.chain_tolerance = r.number(*d, "drawing", "tolerance", false, positive, "positive (mm)").value_or(c.chain_tolerance);
    c.unitless_mm = r.number(*d, "drawing", "unitless_mm", false, positive, "positive (mm)").value_or(c.unitless_mm);
  }
  std::vector<ChartRow> rows;
  const toml::node* chart = root.get("chart");
  if (!chart) r.error_file("[[chart]]: missing (the cut chart: thickness, kerf, pierce_s, pierce_edge_s, feed_mm_min)");
  else if (!chart->is_array_of_tables()) r.error(*chart, "chart: must be [[chart]] rows");
  else
    for (const toml::node& n : *chart->as_array()) {
      const toml::table& t = *n.as_table();
      r.only_keys(t, "chart", {"thickness", "kerf", "pierce_s", "pierce_edge_s", "feed_mm_min"});
      ChartRow row;
      row.thickness = r.number(t, "chart", "thickness", true, positive, "positive (mm)").value_or(0);
      row.kerf = r.number(t, "chart", "kerf", true, non_negative, "0 or more (mm)").value_or(0);
      row.pierce_s = r.number(t, "chart", "pierce_s", true, non_negative, "0 or more (s)").value_or(0);
      row.pierce_edge_s = r.number(t, "chart", "pierce_edge_s", false, non_negative, "0 or more (s)").value_or(row.pierce_s);
      row.feed_mm_min = r.number(t, "chart", "feed_mm_min", true, positive, "positive (mm/min)").value_or(0);
      if (row.pierce_edge_s > row.pierce_s)
        r.error(t, "chart.pierce_edge_s: the delay near the sheet's edge must not exceed pierce_s");
      rows.push_back(row);
    }
  if (r.errors.empty()) {
    bool found = false;
    std::string have;
    for (const ChartRow& row : rows) {
      have += (have.empty() ? "" : ", ") + fmt_num(row.thickness);
      if (std::abs(row.thickness - c.thickness) < 1e-9) { c.chart = row; found = true; }
    }
    if (!found) {
      const toml::node* n = root["sheet"]["thickness"].node();
      r.errors.push_back((n ? r.at(n->source()) : path + ": ") + "sheet.thickness: " + fmt_num(c.thickness) +
                         " mm is not in the cut chart (thicknesses: " + have + ")");
    }
  }
  if (r.errors.empty())
    for (const std::string& e : check_sheet(c.sheet)) r.errors.push_back(path + ": " + e);
  res.errors = std::move(r.errors);
  if (res.errors.empty()) res.config = c;
  return res;
}

SheetResult load_sheet(const std::string& path) {
  std::ifstream f(path);
  if (!f) return {std::nullopt, {path + ": cannot read the file"}};
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_sheet(ss.str(), path);
}

std::vector<std::string> check_sheet(const Sheet& s) {
  std::vector<std::string> e;
  if (!(s.width > 0) || !(s.height > 0)) e.push_back("the sheet needs a positive width and height");
  const std::pair<const char*, double> m[] = {{"left", s.margin_left}, {"right", s.margin_right},
                                              {"top", s.margin_top}, {"bottom", s.margin_bottom}};
  for (auto [name, v] : m)
    if (v < 0) e.push_back(std::string("the ") + name + " margin is negative (" + fmt_num(v) + " mm): it would lie outside the sheet");
  if (s.margin_left + s.margin_right >= s.width)
    e.push_back("the left and right margins together (" + fmt_num(s.margin_left + s.margin_right) +
                " mm) leave nothing of the sheet's width (" + fmt_num(s.width) + " mm)");
  if (s.margin_top + s.margin_bottom >= s.height)
    e.push_back("the top and bottom margins together (" + fmt_num(s.margin_top + s.margin_bottom) +
                " mm) leave nothing of the sheet's height (" + fmt_num(s.height) + " mm)");
  for (std::size_t i = 0; i < s.invalid.size(); ++i) {
    const Box& a = s.invalid[i];
    if (a.lo.x < 0 || a.lo.y < 0 || a.hi.x > s.width || a.hi.y > s.height)
      e.push_back("invalid region " + std::to_string(i + 1) + " reaches outside the sheet");
    for (std::size_t j = 0; j < s.invalid.size(); ++j) {
      if (i == j) continue;
      const Box& b = s.invalid[j];
      const bool inside = a.lo.x >= b.lo.x && a.lo.y >= b.lo.y && a.hi.x <= b.hi.x && a.hi.y <= b.hi.y;
      if (inside && (j < i || !(b.lo.x >= a.lo.x && b.lo.y >= a.lo.y && b.hi.x <= a.hi.x && b.hi.y <= a.hi.y)))
        e.push_back("invalid region " + std::to_string(i + 1) + " lies inside invalid region " + std::to_string(j + 1) +
                    ": it adds nothing (remove it)");
    }
  }
  return e;
}

std::vector<std::pair<int, int>> traversal(int cols, int rows, const std::string& order, Corner) {
  // (col, row) counted from the starting corner; the corner only mirrors the grid (layout_parts)
  std::vector<std::pair<int, int>> out;
  const bool along_x = order[0] == 'x';
  const bool zigzag = order.find("zigzag") != std::string::npos;
  const int outer = along_x ? rows : cols, inner = along_x ? cols : rows;
  for (int o = 0; o < outer; ++o)
    for (int k = 0; k < inner; ++k) {
      const int i = zigzag && o % 2 ? inner - 1 - k : k;
      out.push_back(along_x ? std::pair{i, o} : std::pair{o, i});
    }
  return out;
}

namespace {

constexpr double kClip = 10000.0;  // clipper units per mm
ClipperLib::Path to_path(const std::vector<Vec2>& pts) {
  ClipperLib::Path p;
  for (Vec2 v : pts) p.push_back({ClipperLib::cInt(std::llround(v.x * kClip)), ClipperLib::cInt(std::llround(v.y * kClip))});
  return p;
}
double area_of(const ClipperLib::Paths& ps) {
  double a = 0;
  for (const auto& p : ps) a += ClipperLib::Area(p);
  return a / (kClip * kClip);
}

// The part's outer outlines widened by w (round joins), in clipper units.
ClipperLib::Paths widened(const Shape& s, double w) {
  ClipperLib::Paths in;
  for (const Chain& c : s.chains)
    if (c.contour() && c.depth == 0) {
      ClipperLib::Path p = to_path(c.polygon(0.01));
      if (!ClipperLib::Orientation(p)) ClipperLib::ReversePath(p);
      in.push_back(p);
    }
  if (w <= 0) return in;
  ClipperLib::ClipperOffset off;
  off.ArcTolerance = 0.005 * kClip;
  off.AddPaths(in, ClipperLib::jtRound, ClipperLib::etClosedPolygon);
  ClipperLib::Paths out;
  off.Execute(out, w * kClip);
  return out;
}

Box box_of(const ClipperLib::Paths& ps) {
  Box b;
  for (const auto& p : ps)
    for (const auto& q : p) b.add({double(q.X) / kClip, double(q.Y) / kClip});
  return b;
}

ClipperLib::Paths rect_path(const Box& b) {
  return {to_path({b.lo, {b.hi.x, b.lo.y}, b.hi, {b.lo.x, b.hi.y}})};
}

double overlap(const ClipperLib::Paths& a, const ClipperLib::Paths& b) {
  ClipperLib::Clipper c;
  c.AddPaths(a, ClipperLib::ptSubject, true);
  c.AddPaths(b, ClipperLib::ptClip, true);
  ClipperLib::Paths out;
  c.Execute(ClipperLib::ctIntersection, out, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
  return area_of(out);
}

std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](Vec2 a, Vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  if (p.size() < 3) return p;
  std::vector<Vec2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 1] - h[k - 2], p[i - 1] - h[k - 2]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace

std::vector<std::string> check_fit(const std::vector<Shape>& placed, const Sheet& sheet, double kerf,
                                   const std::vector<std::string>& names) {
  std::vector<std::string> e;
  const Box u = sheet.usable();
  std::vector<ClipperLib::Paths> outl;
  std::vector<Box> boxes;
  for (const Shape& s : placed) {
    outl.push_back(widened(s, kerf / 2));
    boxes.push_back(box_of(outl.back()));
  }
  const double eps = 1e-6;
  for (std::size_t i = 0; i < placed.size(); ++i) {
    const Box& b = boxes[i];
    if (b.lo.x < u.lo.x - eps || b.lo.y < u.lo.y - eps || b.hi.x > u.hi.x + eps || b.hi.y > u.hi.y + eps)
      e.push_back(names[i] + " does not fit inside the margins: with half the kerf it spans x " + fmt_num(b.lo.x) +
                  "..." + fmt_num(b.hi.x) + ", y " + fmt_num(b.lo.y) + "..." + fmt_num(b.hi.y) + " mm; the usable area is x " +
                  fmt_num(u.lo.x) + "..." + fmt_num(u.hi.x) + ", y " + fmt_num(u.lo.y) + "..." + fmt_num(u.hi.y));
    for (std::size_t k = 0; k < sheet.invalid.size(); ++k)
      if (overlap(outl[i], rect_path(sheet.invalid[k])) > 1e-4)
        e.push_back(names[i] + " lies on invalid region " + std::to_string(k + 1));
    for (std::size_t j = i + 1; j < placed.size(); ++j) {
      const Box& c = boxes[j];
      if (b.hi.x < c.lo.x || c.hi.x < b.lo.x || b.hi.y < c.lo.y || c.hi.y < b.lo.y) continue;
      if (overlap(outl[i], outl[j]) > 1e-4)
        e.push_back(names[i] + " and " + names[j] + " overlap (their outlines with half the kerf each meet)");
    }
  }
  return e;
}

LayoutResult layout_parts(const std::vector<Shape>& masters, const SheetConfig& cfg) {
  LayoutResult res;
  const Layout& L = cfg.layout;
  const Sheet& S = cfg.sheet;
  const Box full = S.usable();
  double usable_area = full.width() * full.height();
  if (masters.empty()) { res.errors.push_back("no parts"); return res; }
  if (L.mode == "array") {
    double w = 0, h = 0;
    for (const Shape& m : masters) {
      w = std::max(w, m.box().width());
      h = std::max(h, m.box().height());
    }
    const double px = w + L.spacing_x, py = h + L.spacing_y;
    // the kerf's half around every part stays inside the margins and off the invalid regions
    const double k2 = cfg.chart.kerf / 2;
    Box u;
    u.add(full.lo + Vec2{k2, k2});
    u.add(full.hi - Vec2{k2, k2});
    if (px <= 0) res.errors.push_back(cfg.file + ": layout.spacing_x " + fmt_num(L.spacing_x) + " leaves no pitch (the part is " + fmt_num(w) + " mm wide)");
    if (py <= 0) res.errors.push_back(cfg.file + ": layout.spacing_y " + fmt_num(L.spacing_y) + " leaves no pitch (the part is " + fmt_num(h) + " mm high)");
    if (!res.errors.empty()) return res;
    const int cols = u.width() >= w ? int(std::floor((u.width() - w) / px + 1e-9)) + 1 : 0;
    const int rows = u.height() >= h ? int(std::floor((u.height() - h) / py + 1e-9)) + 1 : 0;
    const bool right = L.corner == Corner::bottom_right || L.corner == Corner::top_right;
    const bool top = L.corner == Corner::top_left || L.corner == Corner::top_right;
    std::vector<int> left(masters.size(), L.count > 0 ? L.count : 1 << 30);
    int next = 0;
    const auto cells = traversal(cols, rows, L.order == "nearest" ? "x-oneway" : L.order, L.corner);
    int skipped = 0;
    for (auto [c, r] : cells) {
      int m = -1;
      for (std::size_t k = 0; k < masters.size(); ++k) {
        const int cand = (next + int(k)) % int(masters.size());
        if (left[std::size_t(cand)] > 0) { m = cand; break; }
      }
      if (m < 0) break;
      const Box mb = masters[std::size_t(m)].box();
      const double x0 = right ? u.hi.x - w - c * px : u.lo.x + c * px;
      const double y0 = top ? u.hi.y - h - r * py : u.lo.y + r * py;
      Box cell;
      cell.add({x0, y0});
      cell.add({x0 + mb.width(), y0 + mb.height()});
      bool blocked = false;
      for (const Box& iv : S.invalid)
        if (cell.lo.x - k2 < iv.hi.x && iv.lo.x < cell.hi.x + k2 && cell.lo.y - k2 < iv.hi.y && iv.lo.y < cell.hi.y + k2)
          blocked = true;
      if (blocked) { ++skipped; continue; }
      bool turned = false;
      if (L.rotate == "alternate-x") turned = c % 2 == 1;
      else if (L.rotate == "alternate-y") turned = r % 2 == 1;
      else if (L.rotate == "checker") turned = (c + r) % 2 == 1;
      Placed p{m, x0, y0, 0};
      if (turned) p = {m, x0 + mb.width(), y0 + mb.height(), 180};
      res.placed.push_back(p);
      left[std::size_t(m)]--;
      next = m + 1;
    }
    if (skipped) res.warnings.push_back(std::to_string(skipped) + " cells of the array lie on invalid regions: left empty");
    if (L.count > 0)
      for (std::size_t k = 0; k < masters.size(); ++k)
        if (left[k] > 0)
          res.errors.push_back(masters[k].file + ": " + std::to_string(L.count) + " parts asked, only " +
                               std::to_string(L.count - left[k]) + " fit on the sheet (" + std::to_string(cols) + " x " +
                               std::to_string(rows) + " cells of " + fmt_num(px) + " x " + fmt_num(py) + " mm)");
    if (res.placed.empty() && res.errors.empty())
      res.errors.push_back("no part fits in the usable area (" + fmt_num(u.width()) + " x " + fmt_num(u.height()) + " mm)");
    res.regular = L.order != "nearest";
  } else {
    nest::Request rq;
    rq.bin = {full.lo.x, full.lo.y, full.hi.x, full.hi.y};
    for (const Box& iv : S.invalid) rq.forbidden.push_back({iv.lo.x, iv.lo.y, iv.hi.x, iv.hi.y});
    rq.gap = L.gap;
    rq.rotations.clear();
    for (double d : L.rotations) rq.rotations.push_back(d * kPi / 180);
    std::vector<int> which;
    const int count = std::max(1, L.count);
    for (std::size_t k = 0; k < masters.size(); ++k) {
      // the convex hull of the outline with half the kerf: libnest2d's placer is exact for convex outlines
      ClipperLib::Paths w = widened(masters[k], cfg.chart.kerf / 2);
      std::vector<Vec2> pts;
      for (const auto& p : w)
        for (const auto& q : p) pts.push_back({double(q.X) / kClip, double(q.Y) / kClip});
      nest::Outline o;
      for (Vec2 v : convex_hull(pts)) o.pts.push_back({v.x, v.y});
      for (int i = 0; i < count; ++i) { rq.items.push_back(o); which.push_back(int(k)); }
    }
    const auto pl = nest::run(rq);
    std::map<int, int> missing;
    for (std::size_t i = 0; i < pl.size(); ++i) {
      if (pl[i].bin != 0) { missing[which[i]]++; continue; }
      const Placed p{which[i], pl[i].x, pl[i].y, pl[i].rot * 180 / kPi};
      const Box b = transformed(masters[std::size_t(p.master)], p.transform()).box();
      const double k2 = cfg.chart.kerf / 2 - 1e-6;
      if (b.lo.x - k2 < full.lo.x || b.lo.y - k2 < full.lo.y || b.hi.x + k2 > full.hi.x || b.hi.y + k2 > full.hi.y) {
        missing[which[i]]++;  // the placer left it outside the usable area: not placed
        continue;
      }
      res.placed.push_back(p);
    }
    for (auto [k, n] : missing)
      res.errors.push_back(masters[std::size_t(k)].file + ": " + std::to_string(n) + " of " + std::to_string(count) +
                           " parts do not fit on the sheet");
    res.regular = false;
  }
  double parts_area = 0;
  for (const Placed& p : res.placed) parts_area += masters[std::size_t(p.master)].area();
  for (const Box& iv : S.invalid) usable_area -= iv.width() * iv.height();
  res.use_percent = usable_area > 0 ? 100.0 * parts_area / usable_area : 0;
  return res;
}

Vec2 start_point(const SheetConfig& cfg, const std::vector<Shape>& placed) {
  if (cfg.layout.start == StartPoint::first_part_centre && !placed.empty()) {
    const Box b = placed.front().box();
    return (b.lo + b.hi) * 0.5;
  }
  const Sheet& s = cfg.sheet;
  switch (cfg.layout.corner) {
    case Corner::bottom_left: return {0, 0};
    case Corner::bottom_right: return {s.width, 0};
    case Corner::top_left: return {0, s.height};
    case Corner::top_right: return {s.width, s.height};
  }
  return {0, 0};
}

}  // namespace cpstep::cam
