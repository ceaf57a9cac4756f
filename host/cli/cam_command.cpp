// SPDX-License-Identifier: MIT
#include "cli/cam_command.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <optional>
#include <fstream>
#include <sstream>

#include "cam/contour.h"
#include "cam/dxf.h"
#include "cam/output.h"
#include "cam/plan.h"
#include "cam/sheet.h"

namespace cpstep::cli {

namespace {

constexpr int kExitRefused = 2;
constexpr int kExitFailed = 1;

// "rotate:90", "scale:2", "scale:2:1", "move:5:0", "mirror:x": nullopt when malformed.
std::optional<cam::Affine> parse_transform(const std::string& spec) {
  std::vector<std::string> f;
  std::stringstream ss(spec);
  for (std::string t; std::getline(ss, t, ':');) f.push_back(t);
  if (f.empty()) return std::nullopt;
  try {
    auto d = [&](std::size_t i) {
      std::size_t used = 0;
      const double v = std::stod(f.at(i), &used);
      if (used != f[i].size() || !std::isfinite(v)) throw std::invalid_argument("number");
      return v;
    };
    if (f[0] == "rotate" && f.size() == 2) return cam::Affine::rotate_deg(d(1));
    if (f[0] == "scale" && f.size() == 2 && d(1) > 0) return cam::Affine::scale(d(1), d(1));
    if (f[0] == "scale" && f.size() == 3 && d(1) > 0 && d(2) > 0) return cam::Affine::scale(d(1), d(2));
    if (f[0] == "move" && f.size() == 3) return cam::Affine::translate(d(1), d(2));
    if (f[0] == "mirror" && f.size() == 2 && (f[1] == "x" || f[1] == "y"))
      return f[1] == "x" ? cam::Affine::scale(-1, 1) : cam::Affine::scale(1, -1);
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

bool write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  return bool(f);
}

}  // namespace

CLI::App* add_cam_command(CLI::App& app, CamOptions& o) {
  auto* c = app.add_subcommand("cam", "Plasma CAM: DXF parts on a sheet to a G-code cut job (docs/PLASMA.md)");
  c->add_option("PARTS", o.parts, "the parts: DXF drawings (one master shape each)")->required();
  c->add_option("--sheet", o.sheet, "the sheet file (sheet, margins, invalid regions, layout, leads, cut chart)")->required();
  c->add_option("-o,--out", o.out, "write the G-code job here");
  c->add_option("--svg", o.svg, "write a preview of the sheet here");
  c->add_option("--transform", o.transforms,
                "applied to every part in the order given, before the layout: rotate:DEG, scale:S, scale:SX:SY, "
                "move:DX:DY, mirror:x|y");
  c->add_option("--count", o.count, "parts of each drawing (overrides layout.count; 0: as many as fit)")
      ->check(CLI::Range(0, 100000));
  c->add_flag("--run", o.run, "run the job on the simulated card (as cpstep run does; needs --machine)");
  c->add_option("--machine", o.machine, "the machine file for --run");
  c->add_option("--report", o.report, "--run: write the JSON report here");
  c->add_option("--plots", o.plots, "--run: write plots into this directory");
  c->add_option("--vcd", o.vcd, "--run: write the pins to this VCD file");
  c->add_option("--board", o.board, "--run: the board whose card is simulated");
  c->add_flag("-q,--quiet", o.quiet, "no summary");
  return c;
}

int run_cam(const CamOptions& o, const std::function<int(const CamOptions&, const std::string&)>& run_job) {
  std::vector<std::string> errors;
  auto refuse = [&]() {
    for (const std::string& e : errors) fmt::print(stderr, "{}\n", e);
    fmt::print(stderr, "cpstep cam: refused ({} error{}); nothing written\n", errors.size(), errors.size() == 1 ? "" : "s");
    return kExitRefused;
  };
  if (o.run && o.machine.empty()) errors.push_back("cpstep cam: --run needs --machine");
  if (o.run && !run_job) errors.push_back("cpstep cam: --run needs the simulated card (a build with the RTL)");
  std::vector<cam::Affine> transforms;
  for (const std::string& t : o.transforms) {
    if (auto m = parse_transform(t)) transforms.push_back(*m);
    else errors.push_back("cpstep cam: --transform " + t + ": not rotate:DEG, scale:S, scale:SX:SY, move:DX:DY or mirror:x|y");
  }
  cam::SheetResult sr = cam::load_sheet(o.sheet);
  errors.insert(errors.end(), sr.errors.begin(), sr.errors.end());
  if (!sr.config) return refuse();
  cam::SheetConfig cfg = *sr.config;
  if (o.count >= 0) cfg.layout.count = o.count;

  std::vector<std::string> warnings;
  std::vector<cam::Shape> masters;
  for (const std::string& path : o.parts) {
    cam::DxfOptions dopt;
    dopt.unitless_mm = cfg.unitless_mm;
    cam::DxfResult d = cam::load_dxf(path, dopt);
    errors.insert(errors.end(), d.errors.begin(), d.errors.end());
    warnings.insert(warnings.end(), d.drawing.warnings.begin(), d.drawing.warnings.end());
    if (!d.ok()) continue;
    std::vector<std::string> notes;
    cam::Shape s = cam::make_shape(d.drawing, cfg.chain_tolerance, &notes);
    for (const cam::Affine& m : transforms) s = cam::transformed(s, m);
    s = cam::normalized(s);
    int contours = 0;
    for (const cam::Chain& c : s.chains) contours += c.contour() && c.depth == 0;
    if (contours == 0) errors.push_back(path + ": no closed outer contour (the chains do not close within " +
                                        cam::fmt_num(cfg.chain_tolerance) + " mm)");
    masters.push_back(std::move(s));
  }
  if (!errors.empty()) return refuse();

  cam::LayoutResult lay = cam::layout_parts(masters, cfg);
  errors.insert(errors.end(), lay.errors.begin(), lay.errors.end());
  warnings.insert(warnings.end(), lay.warnings.begin(), lay.warnings.end());
  if (!errors.empty()) return refuse();
  std::vector<cam::Shape> placed;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < lay.placed.size(); ++i) {
    const cam::Placed& p = lay.placed[i];
    placed.push_back(cam::transformed(masters[std::size_t(p.master)], p.transform()));
    names.push_back(fmt::format("part {} ({} at x {:.3f} y {:.3f} rotated {:g} deg)", i + 1,
                                std::filesystem::path(masters[std::size_t(p.master)].file).filename().string(), p.x, p.y,
                                p.theta_deg));
  }
  const auto fit = cam::check_fit(placed, cfg.sheet, cfg.chart.kerf, names);
  errors.insert(errors.end(), fit.begin(), fit.end());
  if (!errors.empty()) return refuse();

  cam::CutParams cp;
  cp.kerf = cfg.chart.kerf;
  cp.lead_in = cfg.lead_in;
  cp.lead_out = cfg.lead_out;
  cp.pierce_s = cfg.chart.pierce_s;
  cp.pierce_edge_s = cfg.chart.pierce_edge_s;
  cp.edge_distance = cfg.edge_distance;
  cp.chain_tol = cfg.chain_tolerance;
  const cam::Vec2 base = cam::start_point(cfg, placed);
  std::vector<int> order;
  for (std::size_t i = 0; i < placed.size(); ++i) order.push_back(int(i));
  const cam::CutPlan plan = cam::plan_cuts(placed, base, cp, cfg.sheet.box(), lay.regular ? &order : nullptr);
  warnings.insert(warnings.end(), plan.warnings.begin(), plan.warnings.end());
  for (const std::string& w : warnings) fmt::print(stderr, "warning: {}\n", w);

  cam::GcodeInfo gi;
  gi.feed_mm_min = cfg.chart.feed_mm_min;
  gi.part_names = names;
  gi.header.push_back("cpstep cam: " + std::to_string(placed.size()) + " parts on a " + cam::fmt_num(cfg.sheet.width) +
                      " x " + cam::fmt_num(cfg.sheet.height) + " mm sheet, " + cam::fmt_num(cfg.thickness) + " mm " +
                      cfg.material);
  gi.header.push_back(fmt::format("kerf {} mm, feed {} mm/min, pierce {} s ({} s near the edge), leads {} / {} mm",
                                  cam::fmt_num(cfg.chart.kerf), cam::fmt_num(cfg.chart.feed_mm_min),
                                  cam::fmt_num(cfg.chart.pierce_s), cam::fmt_num(cfg.chart.pierce_edge_s),
                                  cam::fmt_num(cfg.lead_in), cam::fmt_num(cfg.lead_out)));
  const std::string gcode = cam::write_gcode(plan, gi);
  std::string job = o.out;
  if (job.empty() && o.run) job = (std::filesystem::temp_directory_path() / "cpstep-cam-job.ngc").string();
  if (!job.empty() && !write_file(job, gcode)) {
    fmt::print(stderr, "cpstep cam: cannot write {}\n", job);
    return kExitFailed;
  }
  if (!o.svg.empty() && !write_file(o.svg, cam::write_svg(plan, cfg.sheet))) {
    fmt::print(stderr, "cpstep cam: cannot write {}\n", o.svg);
    return kExitFailed;
  }
  if (!o.quiet) {
    double delays = 0;
    int edge = 0;
    for (const cam::Cut& c : plan.cuts) {
      delays += c.delay;
      edge += c.edge_pierce;
    }
    const double feed_s = plan.cut_mm / (cfg.chart.feed_mm_min / 60.0);
    fmt::print("sheet      {} x {} mm, usable {} x {} mm, {} invalid region{}\n", cam::fmt_num(cfg.sheet.width),
               cam::fmt_num(cfg.sheet.height), cam::fmt_num(cfg.sheet.usable().width()),
               cam::fmt_num(cfg.sheet.usable().height()), cfg.sheet.invalid.size(), cfg.sheet.invalid.size() == 1 ? "" : "s");
    fmt::print("layout     {} ({}), {} parts, sheet use {:.1f}%\n", cfg.layout.mode,
               lay.regular ? cfg.layout.order : std::string("nearest neighbour + 2-opt"), placed.size(), lay.use_percent);
    fmt::print("cuts       {} ({} pierces, {} near the edge)\n", plan.cuts.size(), plan.pierces, edge);
    fmt::print("cut        {:.1f} mm (leads {:.1f} mm)\n", plan.cut_mm, plan.lead_mm);
    fmt::print("rapid      {:.1f} mm from ({:g}, {:g})\n", plan.rapid_mm, base.x, base.y);
    fmt::print("time       {:.1f} s cutting at {} mm/min + {:.1f} s pierce delays (rapids not counted)\n", feed_s,
               cam::fmt_num(cfg.chart.feed_mm_min), delays);
    if (!job.empty()) fmt::print("job        {}\n", job);
    if (!o.svg.empty()) fmt::print("preview    {}\n", o.svg);
  }
  if (o.run) return run_job(o, job);
  return 0;
}

}  // namespace cpstep::cli
