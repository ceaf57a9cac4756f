// SPDX-License-Identifier: MIT
// Reads DXF through libdxflib. To name an entity's line, the file is first read as
// text (pairs of group code and value) only to list where each entity starts and its
// handle: libdxflib reports entities in file order, so the k-th LINE it reports is
// the k-th LINE record. Nothing is parsed twice: geometry comes from libdxflib.
#include "cam/dxf.h"

#include <fmt/format.h>

#include <dxflib/dl_creationadapter.h>
#include <dxflib/dl_dxf.h>

#include <algorithm>
#include <charconv>
#include <optional>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include <Eigen/Core>

#include "plan/nurbs.h"

namespace cpstep::cam {

static_assert(DxfOptions{}.max_spline_chords == plan::Nurbs::kMaxChords);

std::string Source::where(const std::string& file) const {
  std::string s = file + ":" + std::to_string(line) + ": " + type;
  s += handle.empty() ? " (no handle)" : " handle " + handle;
  return s;
}

double insunits_mm(int code) {
  switch (code) {
    case 0: return 1;      // unitless: the caller decides
    case 1: return 25.4;   // inches
    case 2: return 304.8;  // feet
    case 4: return 1;      // millimetres
    case 5: return 10;     // centimetres
    case 6: return 1000;   // metres
    case 8: return 25.4e-6;  // microinches
    case 9: return 0.0254;   // mils
    case 10: return 914.4;   // yards
    case 13: return 1e-3;    // microns
    case 14: return 100;     // decimetres
    default: return 0;
  }
}

namespace {

// An angle past two turns (`turn`: 360 degrees or 2 pi) brought within one
// (exactly: fmod), so that turns added until the end passes the start are at
// most a few (an ARC starting at 4.4e84 degrees looped for ever). One within
// two turns is kept as written: a drawing's 2 pi end, written as 6.28318530718,
// stays a whole turn.
double within_turns(double a, double turn) { return std::abs(a) > 2 * turn ? std::fmod(a, turn) : a; }

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string kind_of(const std::string& type) {
  if (type == "LWPOLYLINE" || type == "POLYLINE") return "POLYLINE";
  return type;
}

struct Record {
  std::string type, handle;
  int line = 0;
};

// The counts a SPLINE or LWPOLYLINE declares, each with the group code of what
// it counts: libdxflib allocates what a count says and calls back as many
// times, so a count past what the entity holds is refused before it reads.
struct DeclaredCount {
  const char* type;
  const char* count_code;
  const char* item_code;
  const char* what;
};
constexpr DeclaredCount kDeclaredCounts[] = {
    {"SPLINE", "72", "40", "knots"},
    {"SPLINE", "73", "10", "control points"},
    {"SPLINE", "74", "11", "fit points"},
    {"LWPOLYLINE", "90", "10", "vertices"},
};

// Every SPLINE or LWPOLYLINE count past what its entity holds, wherever it sits:
// the pairs read as libdxflib reads them (a group code is the number its line
// starts with, 0 when none: a damaged section header does not hide an entity; and
// group 9, a header variable's name, starts an entity as 0 does: "9 / SPLINE" is a
// SPLINE to libdxflib).
std::vector<std::string> declared_count_errors(const std::string& text, const std::string& path) {
  struct Entity {
    std::string type, handle;
    int line = 0;
    std::map<std::string, std::size_t> groups;
    std::map<std::string, std::vector<std::string>> declared;  // every value given (libdxflib allocates at each)
  };
  std::vector<std::string> errors;
  auto check = [&](const Entity& e) {
    for (const DeclaredCount& c : kDeclaredCounts) {
      if (e.type != c.type || !e.declared.count(c.count_code)) continue;
      const auto it = e.groups.find(c.item_code);
      const std::size_t present = it == e.groups.end() ? 0 : it->second;
      for (const std::string& v : e.declared.at(c.count_code)) {
        long long n = -1;
        const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
        if (ec != std::errc{} || end != v.data() + v.size() || n < 0 || std::size_t(n) > present)
          errors.push_back(Source{e.type, e.handle, e.line}.where(path) + ": group " + c.count_code + " declares " +
                           v + " " + c.what + ", the entity has " + std::to_string(present));
      }
    }
  };
  std::istringstream in(text);
  std::vector<std::string> lines;
  // Each line as libdxflib sees it: a C string, ended by its first NUL byte (an
  // entity named "SPLINE\0..." is a SPLINE to it).
  for (std::string l; std::getline(in, l);) lines.push_back(trim(l.substr(0, l.find('\0'))));
  std::optional<Entity> cur;
  for (std::size_t i = 0; i + 1 < lines.size(); i += 2) {
    const std::string code = std::to_string(std::atoi(lines[i].c_str()));
    const std::string& value = lines[i + 1];
    if (code == "0" || code == "9") {
      if (cur) check(*cur);
      cur.reset();
      if (value == "SPLINE" || value == "LWPOLYLINE") cur = Entity{value, "", int(i) + 1, {}, {}};
      continue;
    }
    if (!cur) continue;
    if (code == "5" && cur->handle.empty()) cur->handle = value;
    ++cur->groups[code];
    if (code == "72" || code == "73" || code == "74" || code == "90") cur->declared[code].push_back(value);
  }
  if (cur) check(*cur);
  return errors;
}

// Where each entity record of the ENTITIES and BLOCKS sections starts.
struct PreScan {
  std::map<std::string, std::vector<Record>> by_kind;  // kind_of(type) -> records in order
  std::vector<Record> all;
  bool has_section = false;
  bool binary = false;
};

PreScan prescan(const std::string& text) {
  PreScan ps;
  if (text.rfind("AutoCAD Binary DXF", 0) == 0) {
    ps.binary = true;
    return ps;
  }
  std::istringstream in(text);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(trim(l));
  std::string section;
  bool expect_section_name = false;
  Record* cur = nullptr;
  for (std::size_t i = 0; i + 1 < lines.size(); i += 2) {
    const std::string& code = lines[i];
    const std::string& value = lines[i + 1];
    if (code == "0") {
      cur = nullptr;
      if (value == "SECTION") { expect_section_name = true; ps.has_section = true; continue; }
      if (value == "ENDSEC") { section.clear(); continue; }
      if (section != "ENTITIES" && section != "BLOCKS") continue;
      static const std::set<std::string> structural = {"BLOCK", "ENDBLK", "VERTEX", "SEQEND", "ATTRIB", "EOF"};
      if (structural.count(value)) continue;
      ps.all.push_back({value, "", int(i) + 1});
      cur = &ps.all.back();
      continue;
    }
    if (code == "2" && expect_section_name) {
      section = value;
      expect_section_name = false;
      continue;
    }
    if (code == "5" && cur && cur->handle.empty()) cur->handle = value;
  }
  for (const Record& r : ps.all) ps.by_kind[kind_of(r.type)].push_back(r);
  return ps;
}

struct InsertRef {
  std::string block;
  Affine ocs;  // OCS -> WCS of the insert
  double ipx, ipy, sx, sy, angle_deg, col_sp, row_sp;
  int cols, rows;
  int src;
};

struct BlockDef {
  Vec2 base;
  std::vector<Seg> segs;
  std::vector<InsertRef> inserts;
  int src = -1;
};

class Reader : public DL_CreationAdapter {
 public:
  Reader(const std::string& file, const PreScan& ps, const DxfOptions& o, DxfResult& out)
      : file_(file), ps_(ps), opt_(o), out_(out) {}

  void setVariableInt(const std::string& key, int value, int) override {
    if (key == "$INSUNITS") insunits_ = value;
  }

  void addBlock(const DL_BlockData& d) override {
    flush();
    cur_block_ = d.name;
    auto& b = blocks_[d.name];
    b.base = {d.bpx, d.bpy};
  }
  void endBlock() override {
    flush();
    cur_block_.reset();
  }

  void addLine(const DL_LineData& d) override {
    flush();
    const int src = source("LINE");
    if (skip()) return;
    if (!finite({d.x1, d.y1, d.x2, d.y2}, src)) return;
    const Vec2 a{d.x1, d.y1}, b{d.x2, d.y2};
    if (dist(a, b) <= 1e-12) { warn(src, "a line of zero length, left out"); return; }
    emit(Seg::line(a, b, src));
  }

  void addArc(const DL_ArcData& d) override {
    flush();
    const int src = source("ARC");
    if (skip()) return;
    Affine ocs;
    if (!finite({d.cx, d.cy, d.radius, d.angle1, d.angle2}, src) || !plane(src, ocs)) return;
    if (d.radius <= 0) { error(src, "radius " + fmt_num(d.radius) + " is not positive"); return; }
    const double t0 = within_turns(d.angle1, 360.0) * kPi / 180;
    double t1 = within_turns(d.angle2, 360.0) * kPi / 180;
    while (t1 <= t0) t1 += 2 * kPi;
    if (t1 - t0 > 2 * kPi) t1 -= 2 * kPi;
    emit(Seg::circle_arc({d.cx, d.cy}, d.radius, t0, t1, src).transformed(ocs));
  }

  void addCircle(const DL_CircleData& d) override {
    flush();
    const int src = source("CIRCLE");
    if (skip()) return;
    Affine ocs;
    if (!finite({d.cx, d.cy, d.radius}, src) || !plane(src, ocs)) return;
    if (d.radius <= 0) { error(src, "radius " + fmt_num(d.radius) + " is not positive"); return; }
    emit(Seg::circle_arc({d.cx, d.cy}, d.radius, 0, 2 * kPi, src).transformed(ocs));
  }

  void addEllipse(const DL_EllipseData& d) override {
    flush();
    const int src = source("ELLIPSE");
    if (skip()) return;
    if (!finite({d.cx, d.cy, d.mx, d.my, d.ratio, d.angle1, d.angle2}, src)) return;
    const double* n = getExtrusion()->getDirection();
    if (std::abs(n[0]) > 1e-9 || std::abs(n[1]) > 1e-9) { error(src, "not in the XY plane (extrusion " + dir_text() + ")"); return; }
    const Vec2 m{d.mx, d.my};
    if (norm(m) <= 0 || d.ratio <= 0 || d.ratio > 1 + 1e-9) {
      error(src, "major axis " + fmt_num(norm(m)) + " and ratio " + fmt_num(d.ratio) + " do not make an ellipse");
      return;
    }
    const Vec2 minor = n[2] >= 0 ? perp_left(m) * d.ratio : perp_left(m) * -d.ratio;
    double t0 = within_turns(d.angle1, 2 * kPi), t1 = within_turns(d.angle2, 2 * kPi);
    while (t1 <= t0) t1 += 2 * kPi;
    if (t1 - t0 > 2 * kPi + 1e-12) t1 -= 2 * kPi;
    emit(Seg::conic_arc({d.cx, d.cy}, m, minor, t0, t1, src));
  }

  void addPolyline(const DL_PolylineData& d) override {
    flush();
    const int src = source("POLYLINE");
    if (skip()) return;
    if (d.flags & (16 | 64)) { error(src, "polygon meshes and polyface meshes are not 2D contours"); return; }
    Affine ocs;
    if (!plane(src, ocs)) return;
    poly_ = Poly{src, (d.flags & 1) != 0, ocs, {}};
  }
  void addVertex(const DL_VertexData& d) override {
    if (!poly_) return;
    if (!finite({d.x, d.y, d.bulge}, poly_->src)) { poly_.reset(); return; }
    poly_->verts.push_back({d.x, d.y, d.bulge});
  }

  void addSpline(const DL_SplineData& d) override {
    flush();
    const int src = source("SPLINE");
    if (skip()) return;
    spline_ = Spline{src, int(d.degree), int(d.nKnots), int(d.nControl), int(d.nFit), {}, {}, {}};
  }
  void addControlPoint(const DL_ControlPointData& d) override {
    if (spline_) spline_->ctrl.push_back({d.x, d.y, d.w});
  }
  void addKnot(const DL_KnotData& d) override {
    if (spline_) spline_->knots.push_back(d.k);
  }
  void addFitPoint(const DL_FitPointData& d) override {
    if (spline_) spline_->fit.push_back({d.x, d.y});
  }

  void addInsert(const DL_InsertData& d) override {
    flush();
    const int src = source("INSERT");
    if (skip()) return;
    Affine ocs;
    if (!finite({d.ipx, d.ipy, d.sx, d.sy, d.angle, d.colSp, d.rowSp}, src) || !plane(src, ocs)) return;
    if (d.sx == 0 || d.sy == 0) { error(src, "block " + d.name + " scaled by zero"); return; }
    InsertRef r{d.name, ocs, d.ipx, d.ipy, d.sx, d.sy, d.angle, d.colSp, d.rowSp,
                std::max(1, d.cols), std::max(1, d.rows), src};
    if (cur_block_) blocks_[*cur_block_].inserts.push_back(r);
    else inserts_.push_back(r);
  }

  void endEntity() override { flush(); }
  void endSequence() override { flush(); }

  // After libdxflib: blocks expanded into model space, units applied.
  void finish() {
    flush();
    for (const InsertRef& r : inserts_) {
      // Arrays of arrays multiply: count what the insert places before placing it.
      const std::uint64_t n = placed(r);
      if (model_.size() + n > opt_.max_segments) {
        const std::string count =
            n > opt_.max_segments ? fmt::format("more than {}", opt_.max_segments) : std::to_string(n);
        error(r.src, fmt::format("block \"{}\" inserted {} x {} times places {} segments; a drawing holds at most {}",
                                 r.block, r.cols, r.rows, count, opt_.max_segments));
        continue;
      }
      expand(r, Affine{}, 0);
    }
    int code = insunits_.value_or(0);
    double mm = insunits_mm(code);
    if (mm == 0) {
      out_.errors.push_back(file_ + ": $INSUNITS " + std::to_string(code) + " is not a unit of length");
      return;
    }
    if (code == 0) {
      mm = opt_.unitless_mm;
      if (!insunits_) warn(-1, "no $INSUNITS in the header: drawing units taken as " + fmt_num(mm) + " mm");
    }
    out_.drawing.unit_mm = mm;
    if (mm != 1)
      for (Seg& s : model_) s = s.transformed(Affine::scale(mm, mm));
    // Finite inputs can still give points that are not: a spline's control
    // points times its weights, an insert's scale, the drawing's unit
    // (fuzz finding 13: a spline's control point of 2e26044 read as finite
    // but huge). The entity is named once and the drawing refused.
    std::set<int> named;
    for (const Seg& s : model_) {
      const bool ok = std::isfinite(s.a.x) && std::isfinite(s.a.y) && std::isfinite(s.b.x) && std::isfinite(s.b.y) &&
                      std::isfinite(s.c.x) && std::isfinite(s.c.y) && std::isfinite(s.u.x) && std::isfinite(s.u.y) &&
                      std::isfinite(s.v.x) && std::isfinite(s.v.y);
      if (!ok && named.insert(s.src).second)
        error(s.src, "a point of its geometry is not a finite number (coordinates, weights, insert scales or "
                     "the drawing's unit too large)");
    }
    out_.drawing.segs = std::move(model_);
  }

 private:
  struct Poly {
    int src;
    bool closed;
    Affine ocs;
    struct V { double x, y, bulge; };
    std::vector<V> verts;
  };
  struct Spline {
    int src, degree, nknots, nctrl, nfit;
    struct C { double x, y, w; };
    std::vector<C> ctrl;
    std::vector<double> knots;
    std::vector<Vec2> fit;
  };

  int source(const std::string& type) {
    const std::string kind = kind_of(type);
    const std::size_t k = counters_[kind]++;
    Source s{type, "", 0};
    auto it = ps_.by_kind.find(kind);
    if (it != ps_.by_kind.end() && k < it->second.size()) {
      s.type = it->second[k].type;
      s.handle = it->second[k].handle;
      s.line = it->second[k].line;
    } else if (k == (it == ps_.by_kind.end() ? 0 : it->second.size())) {
      // libdxflib reads entities wherever a line reads as group 0 or 9 before their
      // name; a drawing's are the "0 / TYPE" records of its ENTITIES and BLOCKS
      // sections. One more than those is a damaged file: refused, not cut.
      out_.errors.push_back(file_ + ": libdxflib read a " + type +
                            " that is not an entity record of the ENTITIES or BLOCKS sections (" +
                            std::to_string(k) + " found there): the file is damaged");
    }
    out_.drawing.sources.push_back(s);
    return int(out_.drawing.sources.size()) - 1;
  }
  bool skip() { return !cur_block_ && getAttributes().isInPaperSpace(); }
  std::string where(int src) const {
    return src < 0 ? file_ : out_.drawing.sources[std::size_t(src)].where(file_);
  }
  void error(int src, const std::string& msg) { out_.errors.push_back(where(src) + ": " + msg); }
  void warn(int src, const std::string& msg) { out_.drawing.warnings.push_back(where(src) + ": " + msg); }
  bool finite(std::initializer_list<double> vs, int src) {
    for (double v : vs)
      if (!std::isfinite(v)) { error(src, "a coordinate is not a finite number"); return false; }
    return true;
  }
  std::string dir_text() {
    const double* n = getExtrusion()->getDirection();
    return fmt_num(n[0]) + ", " + fmt_num(n[1]) + ", " + fmt_num(n[2]);
  }
  // The OCS of the current entity as a 2D map: +Z is the identity, -Z mirrors X
  // (the arbitrary axis algorithm); any other extrusion is not a flat drawing.
  bool plane(int src, Affine& ocs) {
    const double* n = getExtrusion()->getDirection();
    if (std::abs(n[0]) > 1e-9 || std::abs(n[1]) > 1e-9 || n[2] == 0) {
      error(src, "not in the XY plane (extrusion " + dir_text() + ")");
      return false;
    }
    ocs = n[2] > 0 ? Affine{} : Affine::scale(-1, 1);
    return true;
  }
  void emit(const Seg& s) {
    if (cur_block_) blocks_[*cur_block_].segs.push_back(s);
    else model_.push_back(s);
  }

  void flush() {
    if (poly_) {
      Poly p = std::move(*poly_);
      poly_.reset();
      finish_poly(p);
    }
    if (spline_) {
      Spline s = std::move(*spline_);
      spline_.reset();
      finish_spline(s);
    }
  }

  void finish_poly(const Poly& p) {
    const std::size_t n = p.verts.size();
    if (n < 2) { error(p.src, "a polyline needs two vertices, it has " + std::to_string(n)); return; }
    const std::size_t edges = p.closed ? n : n - 1;
    for (std::size_t i = 0; i < edges; ++i) {
      const auto& v0 = p.verts[i];
      const auto& v1 = p.verts[(i + 1) % n];
      const Vec2 a{v0.x, v0.y}, b{v1.x, v1.y};
      const double chord = dist(a, b);
      if (chord <= 1e-12) continue;  // repeated vertex
      if (std::abs(v0.bulge) < 1e-12) {
        emit(Seg::line(a, b, p.src).transformed(p.ocs));
        continue;
      }
      const double theta = 4 * std::atan(v0.bulge);  // signed included angle, ccw > 0
      const double r = chord / (2 * std::sin(std::abs(theta) / 2));
      const Vec2 m = (a + b) * 0.5;
      const double h = (chord / 2) / std::tan(theta / 2);  // signed: centre left of the chord for ccw
      const Vec2 c = m + perp_left(unit(b - a)) * h;
      const double t0 = std::atan2(a.y - c.y, a.x - c.x);
      Seg s = Seg::circle_arc(c, r, t0, t0 + theta, p.src);
      s.a = a;
      s.b = b;
      emit(s.transformed(p.ocs));
    }
  }

  void finish_spline(const Spline& s) {
    const int p = s.degree, n = int(s.ctrl.size());
    if (n == 0) {
      error(s.src, s.fit.empty() ? "a spline without control points"
                                 : "a spline given by fit points only (no control points) is not supported");
      return;
    }
    if (p < 1 || n < p + 1) { error(s.src, "degree " + std::to_string(p) + " with " + std::to_string(n) + " control points"); return; }
    if (int(s.knots.size()) != n + p + 1) {
      error(s.src, std::to_string(s.knots.size()) + " knots; degree " + std::to_string(p) + " with " +
                       std::to_string(n) + " control points needs " + std::to_string(n + p + 1));
      return;
    }
    for (std::size_t i = 1; i < s.knots.size(); ++i)
      if (s.knots[i] < s.knots[i - 1]) { error(s.src, "knots decrease at knot " + std::to_string(i)); return; }
    for (const auto& c : s.ctrl)
      if (!(c.w > 0) || !std::isfinite(c.x) || !std::isfinite(c.y)) { error(s.src, "a control point with a weight that is not positive or a coordinate that is not finite"); return; }
    const double lo = s.knots[std::size_t(p)], hi = s.knots[std::size_t(n)];
    if (!(hi > lo)) { error(s.src, "the knot vector spans no parameter range"); return; }
    // The curve over [lo, hi] as a clamped NURBS (DXF allows unclamped knots,
    // e.g. a closed periodic spline): knot insertion at both ends, then the
    // shared curve code (host/plan/nurbs.h) evaluates and samples it.
    std::vector<Eigen::Vector4d> hom;
    for (const auto& c : s.ctrl) hom.emplace_back(c.x * c.w, c.y * c.w, 0.0, c.w);
    std::vector<double> knots = s.knots;
    clamp_at(lo, p, knots, hom, false);
    clamp_at(hi, p, knots, hom, true);
    const auto first = std::size_t(std::lower_bound(knots.begin(), knots.end(), lo) - knots.begin());
    const auto last = std::size_t(std::upper_bound(knots.begin(), knots.end(), hi) - knots.begin()) - 1;
    std::vector<double> kn(knots.begin() + std::ptrdiff_t(first), knots.begin() + std::ptrdiff_t(last) + 1);
    const std::size_t count = kn.size() - std::size_t(p) - 1;
    std::vector<Eigen::Vector3d> pts;
    std::vector<double> weights;
    for (std::size_t i = first; i < first + count; ++i) {
      weights.push_back(hom[i][3]);
      pts.emplace_back(hom[i][0] / hom[i][3], hom[i][1] / hom[i][3], 0.0);
    }
    if (auto why = plan::Nurbs::validate(p + 1, pts.size(), weights, kn)) { error(s.src, *why); return; }
    const plan::Nurbs curve(p + 1, std::move(pts), std::move(weights), std::move(kn));
    const int code = insunits_.value_or(0);
    const double unit = code == 0 || insunits_mm(code) == 0 ? opt_.unitless_mm : insunits_mm(code);
    const std::vector<double> us = curve.chord_parameters(opt_.spline_tolerance_mm / unit, opt_.max_spline_chords);
    if (us.empty()) {
      error(s.src, fmt::format("sampling the spline within {:g} mm takes more than {} chords (control points "
                               "too far apart, or too far from the origin, for the tolerance)",
                               opt_.spline_tolerance_mm, opt_.max_spline_chords));
      return;
    }
    Vec2 prev{};
    bool have = false;
    for (double u : us) {
      const Eigen::Vector3d c = curve.point(u);
      const Vec2 q{c.x(), c.y()};
      if (have && dist(prev, q) > 1e-12) emit(Seg::line(prev, q, s.src));
      prev = q;
      have = true;
    }
  }

  // Inserts knot u into (knots, homogeneous points) of degree p until it is
  // there p + 1 times (Boehm's algorithm, one insertion at a time).
  // `end`: u is the end of the curve's range, knots[n] (n control points): its
  // span is the last one before it, knots[k] < u <= knots[k + 1], so the points
  // it takes stay within the control polygon (with knots after u, the span
  // knots[k] <= u < knots[k + 1] would reach past it: the dxf fuzz target's
  // heap overflow, fuzz/corpus/dxf/regress_spline_end_knots.dxf.in). At the
  // start, u = knots[p]: knots[k] <= u < knots[k + 1].
  static void clamp_at(double u, int p, std::vector<double>& knots, std::vector<Eigen::Vector4d>& hom, bool end) {
    auto multiplicity = [&] { return int(std::count(knots.begin(), knots.end(), u)); };
    while (multiplicity() < p + 1) {
      auto k = std::size_t((end ? std::lower_bound(knots.begin(), knots.end(), u)
                                : std::upper_bound(knots.begin(), knots.end(), u)) -
                           knots.begin()) -
               1;
      k = std::min(k, knots.size() - 2);
      std::vector<Eigen::Vector4d> q(hom.size() + 1);
      for (std::size_t i = 0; i < q.size(); ++i) {
        if (i + std::size_t(p) <= k) {
          q[i] = hom[i];
        } else if (i > k) {
          q[i] = hom[i - 1];
        } else {
          // Knots equal to u (already inserted) leave their point as it was.
          const double al = knots[i] < u ? (u - knots[i]) / (knots[i + std::size_t(p)] - knots[i]) : 0.0;
          q[i] = al * hom[i] + (1 - al) * hom[i - 1];
        }
      }
      knots.insert(knots.begin() + std::ptrdiff_t(k) + 1, u);
      hom = std::move(q);
    }
  }

  // The segments one insert places, nested inserts counted (its block's count
  // memoized), saturating just past max_segments; undefined or recursive blocks
  // count nothing here (expand() refuses them).
  std::uint64_t placed(const InsertRef& r, int depth = 0) {
    const std::uint64_t cap = std::uint64_t(opt_.max_segments) + 1;
    const std::uint64_t one = block_segments(r.block, depth);
    const std::uint64_t copies = std::uint64_t(r.rows) * std::uint64_t(r.cols);
    return one == 0 ? 0 : copies > cap / one ? cap : std::min(cap, copies * one);
  }
  std::uint64_t block_segments(const std::string& name, int depth) {
    const auto memo = placed_.find(name);
    if (memo != placed_.end()) return memo->second;
    const auto it = blocks_.find(name);
    if (it == blocks_.end() || depth > 16) return 0;
    placed_[name] = 0;  // (while counting it: a block inside itself counts nothing)
    const std::uint64_t cap = std::uint64_t(opt_.max_segments) + 1;
    std::uint64_t n = it->second.segs.size();
    for (const InsertRef& inner : it->second.inserts) n = std::min(cap, n + placed(inner, depth + 1));
    placed_[name] = n;
    return n;
  }

  void expand(const InsertRef& r, const Affine& outer, int depth) {
    auto it = blocks_.find(r.block);
    if (it == blocks_.end()) { error(r.src, "block \"" + r.block + "\" is not defined"); return; }
    if (depth > 16 || std::find(stack_.begin(), stack_.end(), r.block) != stack_.end()) {
      error(r.src, "block \"" + r.block + "\" inserts itself");
      return;
    }
    stack_.push_back(r.block);
    const BlockDef& b = it->second;
    // A block that places nothing is gone through once (for its nested errors),
    // not once a copy: an empty array of 10^10 copies is no work.
    const bool empty = block_segments(r.block, depth) == 0;
    const int rows = empty ? 1 : r.rows, cols = empty ? 1 : r.cols;
    for (int row = 0; row < rows; ++row)
      for (int col = 0; col < cols; ++col) {
        const Affine m = outer * r.ocs * Affine::translate(r.ipx, r.ipy) * Affine::rotate_deg(r.angle_deg) *
                         Affine::translate(col * r.col_sp, row * r.row_sp) * Affine::scale(r.sx, r.sy) *
                         Affine::translate(-b.base.x, -b.base.y);
        for (const Seg& s : b.segs) model_.push_back(s.transformed(m));
        for (const InsertRef& inner : b.inserts) expand(inner, m, depth + 1);
      }
    stack_.pop_back();
  }

  const std::string& file_;
  const PreScan& ps_;
  const DxfOptions& opt_;
  DxfResult& out_;
  std::map<std::string, std::size_t> counters_;
  std::optional<int> insunits_;
  std::optional<std::string> cur_block_;
  std::map<std::string, BlockDef> blocks_;
  std::map<std::string, std::uint64_t> placed_;  // block_segments()'s memo
  std::vector<InsertRef> inserts_;
  std::vector<Seg> model_;
  std::optional<Poly> poly_;
  std::optional<Spline> spline_;
  std::vector<std::string> stack_;
};

}  // namespace

DxfResult load_dxf(const std::string& path, const DxfOptions& options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    DxfResult out;
    out.drawing.file = path;
    out.errors.push_back(path + ": cannot read the file");
    return out;
  }
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_dxf(ss.str(), path, options);
}

DxfResult parse_dxf(const std::string& text, const std::string& path, const DxfOptions& options) {
  DxfResult out;
  out.drawing.file = path;
  const PreScan ps = prescan(text);
  if (ps.binary) {
    out.errors.push_back(path + ": binary DXF is not supported (save it as ASCII DXF)");
    return out;
  }
  if (!ps.has_section) {
    out.errors.push_back(path + ":1: not a DXF file (no SECTION)");
    return out;
  }
  out.errors = declared_count_errors(text, path);
  if (!out.errors.empty()) return out;  // (before libdxflib allocates for them)
  static const std::set<std::string> supported = {"LINE", "ARC", "CIRCLE", "ELLIPSE", "LWPOLYLINE",
                                                   "POLYLINE", "SPLINE", "INSERT"};
  for (const Record& r : ps.all)
    if (!supported.count(r.type))
      out.drawing.warnings.push_back(Source{r.type, r.handle, r.line}.where(path) + ": not cut geometry, left out");
  Reader reader(path, ps, options, out);
  DL_Dxf dxf;
  std::istringstream in(text);
  if (!dxf.in(in, &reader)) {
    out.errors.push_back(path + ": libdxflib could not read it");
    return out;
  }
  reader.finish();
  if (out.errors.empty() && out.drawing.segs.empty())
    out.errors.push_back(path + ": no LINE, ARC, CIRCLE, ELLIPSE, POLYLINE, SPLINE or INSERT in model space");
  return out;
}

}  // namespace cpstep::cam
