// SPDX-License-Identifier: MIT
#include "cam/nest.h"

#include <libnest2d/libnest2d.hpp>

#include <cmath>

namespace cpstep::cam::nest {

namespace {
constexpr double kUnits = 10000.0;  // libnest2d's integer coordinates: 0.1 µm
ClipperLib::cInt to_i(double mm) { return ClipperLib::cInt(std::llround(mm * kUnits)); }

libnest2d::Item make_item(const std::vector<std::pair<double, double>>& pts) {
  // libnest2d's clipper backend wants clockwise outlines, closed by a repeated point
  double area = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& a = pts[i];
    const auto& b = pts[(i + 1) % pts.size()];
    area += a.first * b.second - b.first * a.second;
  }
  ClipperLib::Path path;
  for (const auto& p : pts) path.push_back({to_i(p.first), to_i(p.second)});
  if (area > 0) std::reverse(path.begin(), path.end());
  path.push_back(path.front());
  return libnest2d::Item(path);
}
}  // namespace

std::vector<Placement> run(const Request& r) {
  using namespace libnest2d;
  std::vector<Item> items;
  for (const Outline& o : r.items) items.push_back(make_item(o.pts));
  for (const Rect& f : r.forbidden) {
    Item it = make_item({{f.x0, f.y0}, {f.x1, f.y0}, {f.x1, f.y1}, {f.x0, f.y1}});
    it.markAsFixedInBin(0);
    items.push_back(it);
  }
  Box bin(PointImpl{to_i(r.bin.x0), to_i(r.bin.y0)}, PointImpl{to_i(r.bin.x1), to_i(r.bin.y1)});
  NestConfig<NfpPlacer, FirstFitSelection> cfg;
  cfg.placer_config.rotations.clear();
  for (double a : r.rotations) cfg.placer_config.rotations.push_back(Radians(a));
  // The final alignment moves the whole pile, fixed invalid regions too: with
  // regions, the pile stays where the placer put it (the caller checks every part
  // against the sheet).
  cfg.placer_config.alignment = r.forbidden.empty() ? NfpPlacer::Config::Alignment::BOTTOM_LEFT
                                                    : NfpPlacer::Config::Alignment::DONT_ALIGN;
  cfg.placer_config.starting_point = NfpPlacer::Config::Alignment::BOTTOM_LEFT;
  libnest2d::nest(items, bin, to_i(r.gap), cfg);
  std::vector<Placement> out;
  for (std::size_t i = 0; i < r.items.size(); ++i) {
    const Item& it = items[i];
    const auto t = it.translation();
    out.push_back({it.binId(), double(getX(t)) / kUnits, double(getY(t)) / kUnits, double(it.rotation())});
  }
  return out;
}

}  // namespace cpstep::cam::nest
