// SPDX-License-Identifier: MIT
// Test helper: DXF text written entity by entity (a writer, not a parser), every
// entity with a handle, and files for it in a fresh temporary directory.
#pragma once

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace camtest {

class DxfText {
 public:
  explicit DxfText(int insunits = 4) : insunits_(insunits) {}
  int hnd = 0x200;
  std::string next_handle() {
    char b[16];
    std::snprintf(b, sizeof b, "%X", ++hnd);
    return b;
  }
  static std::string n(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.12g", v);
    return b;
  }
  std::string& target(bool in_block) { return in_block ? blocks_.back().body : ents_; }
  std::string line(double x1, double y1, double x2, double y2, bool blk = false) {
    const std::string h = next_handle();
    target(blk) += "0\nLINE\n5\n" + h + "\n8\n0\n10\n" + n(x1) + "\n20\n" + n(y1) + "\n11\n" + n(x2) + "\n21\n" + n(y2) + "\n";
    return h;
  }
  std::string arc(double cx, double cy, double r, double a0, double a1, bool blk = false, double ez = 1) {
    const std::string h = next_handle();
    target(blk) += "0\nARC\n5\n" + h + "\n8\n0\n10\n" + n(cx) + "\n20\n" + n(cy) + "\n40\n" + n(r) + "\n" +
                   (ez < 0 ? "210\n0\n220\n0\n230\n-1\n" : "") + "50\n" + n(a0) + "\n51\n" + n(a1) + "\n";
    return h;
  }
  std::string circle(double cx, double cy, double r, bool blk = false) {
    const std::string h = next_handle();
    target(blk) += "0\nCIRCLE\n5\n" + h + "\n8\n0\n10\n" + n(cx) + "\n20\n" + n(cy) + "\n40\n" + n(r) + "\n";
    return h;
  }
  std::string ellipse(double cx, double cy, double mx, double my, double ratio, double p0 = 0, double p1 = 2 * M_PI) {
    const std::string h = next_handle();
    ents_ += "0\nELLIPSE\n5\n" + h + "\n100\nAcDbEntity\n8\n0\n100\nAcDbEllipse\n10\n" + n(cx) + "\n20\n" + n(cy) +
             "\n11\n" + n(mx) + "\n21\n" + n(my) + "\n40\n" + n(ratio) + "\n41\n" + n(p0) + "\n42\n" + n(p1) + "\n";
    return h;
  }
  struct V { double x, y, bulge; };
  std::string lwpolyline(const std::vector<V>& v, bool closed) {
    const std::string h = next_handle();
    ents_ += "0\nLWPOLYLINE\n5\n" + h + "\n100\nAcDbEntity\n8\n0\n100\nAcDbPolyline\n90\n" + std::to_string(v.size()) +
             "\n70\n" + (closed ? "1" : "0") + "\n";
    for (const V& p : v) {
      ents_ += "10\n" + n(p.x) + "\n20\n" + n(p.y) + "\n";
      if (p.bulge != 0) ents_ += "42\n" + n(p.bulge) + "\n";
    }
    return h;
  }
  std::string polyline_r12(const std::vector<V>& v, bool closed) {
    const std::string h = next_handle();
    ents_ += "0\nPOLYLINE\n5\n" + h + "\n8\n0\n66\n1\n70\n" + (closed ? "1" : "0") + "\n";
    for (const V& p : v) {
      ents_ += "0\nVERTEX\n5\n" + next_handle() + "\n8\n0\n10\n" + n(p.x) + "\n20\n" + n(p.y) + "\n";
      if (p.bulge != 0) ents_ += "42\n" + n(p.bulge) + "\n";
    }
    ents_ += "0\nSEQEND\n5\n" + next_handle() + "\n8\n0\n";
    return h;
  }
  std::string spline(int degree, const std::vector<double>& knots, const std::vector<std::pair<double, double>>& ctrl,
                     const std::vector<double>& weights = {}) {
    const std::string h = next_handle();
    ents_ += "0\nSPLINE\n5\n" + h + "\n100\nAcDbEntity\n8\n0\n100\nAcDbSpline\n70\n" + std::string(weights.empty() ? "8" : "12") +
             "\n71\n" + std::to_string(degree) + "\n72\n" + std::to_string(knots.size()) + "\n73\n" +
             std::to_string(ctrl.size()) + "\n74\n0\n";
    for (double k : knots) ents_ += "40\n" + n(k) + "\n";
    for (std::size_t i = 0; i < ctrl.size(); ++i) {
      ents_ += "10\n" + n(ctrl[i].first) + "\n20\n" + n(ctrl[i].second) + "\n30\n0\n";
      if (!weights.empty()) ents_ += "41\n" + n(weights[i]) + "\n";
    }
    return h;
  }
  void begin_block(const std::string& name, double bx = 0, double by = 0) { blocks_.push_back({name, bx, by, ""}); }
  std::string insert(const std::string& name, double x, double y, double sx = 1, double sy = 1, double angle = 0,
                     int cols = 1, int rows = 1, double csp = 0, double rsp = 0, bool blk = false) {
    const std::string h = next_handle();
    target(blk) += "0\nINSERT\n5\n" + h + "\n8\n0\n2\n" + name + "\n10\n" + n(x) + "\n20\n" + n(y) + "\n41\n" + n(sx) +
                   "\n42\n" + n(sy) + "\n50\n" + n(angle) + "\n" +
                   (cols > 1 || rows > 1 ? "70\n" + std::to_string(cols) + "\n71\n" + std::to_string(rows) + "\n44\n" +
                                               n(csp) + "\n45\n" + n(rsp) + "\n"
                                         : "");
    return h;
  }
  std::string raw(const std::string& pairs) { ents_ += pairs; return ""; }
  std::string text() const {
    std::string s = "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1015\n";
    if (insunits_ >= 0) s += "9\n$INSUNITS\n70\n" + std::to_string(insunits_) + "\n";
    s += "0\nENDSEC\n0\nSECTION\n2\nBLOCKS\n";
    for (const Block& b : blocks_)
      s += "0\nBLOCK\n5\n1F" + b.name.substr(0, 1) + "\n8\n0\n2\n" + b.name + "\n70\n0\n10\n" + n(b.bx) + "\n20\n" + n(b.by) +
           "\n3\n" + b.name + "\n" + b.body + "0\nENDBLK\n8\n0\n";
    s += "0\nENDSEC\n0\nSECTION\n2\nENTITIES\n" + ents_ + "0\nENDSEC\n0\nEOF\n";
    return s;
  }
  // The 1-based line where the record holding handle h starts (its "0" line): found by
  // searching the written text, independently of the CAM's reading.
  int line_of(const std::string& h) const {
    const std::string t = text();
    std::vector<std::string> lines;
    std::size_t p = 0;
    while (p < t.size()) {
      const std::size_t e = t.find('\n', p);
      lines.push_back(t.substr(p, e - p));
      p = e + 1;
    }
    for (std::size_t i = 0; i + 1 < lines.size(); ++i)
      if (lines[i] == "5" && lines[i + 1] == h) return int(i) - 1;  // the record's "0" line is i-2 (0-based): i-1 counted from 1
    return -1;
  }

 private:
  struct Block { std::string name; double bx, by; std::string body; };
  int insunits_;
  std::string ents_;
  std::vector<Block> blocks_;
};

inline std::filesystem::path temp_dir(const std::string& name) {
  auto d = std::filesystem::temp_directory_path() / ("cpstep-cam-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

inline std::string write(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

}  // namespace camtest
