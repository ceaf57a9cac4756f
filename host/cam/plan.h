// SPDX-License-Identifier: MIT
// The cut plan: every chain of every placed part as a cut (kerf-compensated when it
// is a closed contour), its start point, lead-in and lead-out, pierce point and
// delay, in an order that cuts whatever lies inside a contour before the contour,
// starts each closed contour at its point nearest the torch, reverses open chains
// when their other end is nearer, and shortens the rapid travel: nearest neighbour
// from the base point, then 2-opt.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cam/contour.h"
#include "cam/geom.h"

namespace cpstep::cam {

struct CutParams {
  double kerf = 0;              // mm; each contour moves by half of it to its waste side
  double lead_in = 0;           // mm, whatever the part's scale
  double lead_out = 0;          // mm
  double pierce_s = 0;          // pierce (preheat) delay at the start of each chain
  double pierce_edge_s = 0;     // the delay when the pierce is within edge_distance of the sheet's edge
  double edge_distance = 0;     // mm
  double chain_tol = 0.01;      // mm: end points this close are joined
  double arc_tol = 0.002;       // mm: ellipses as circular arcs
  bool two_opt = true;
  double two_opt_seconds = 3;   // time budget of the 2-opt passes
};

struct Cut {
  int part = 0, chain = 0;      // placed part and its chain
  bool contour = false, hole = false;
  std::vector<Seg> path;        // as cut: starts at the start point
  std::optional<Seg> lead_in, lead_out;
  Vec2 pierce;
  double delay = 0;
  bool edge_pierce = false;
};

struct CutPlan {
  std::vector<Cut> cuts;        // in cut order
  Vec2 base;                    // where the torch starts
  double rapid_mm = 0;          // base -> first pierce -> ... -> last cut's end
  double cut_mm = 0;            // path length, leads included
  double lead_mm = 0;
  int pierces = 0;
  std::vector<std::string> warnings;
};

// Parts in sheet coordinates (already placed). `groups`, when given, fixes the order
// of the parts (a regular traversal): each part's chains are ordered within it.
CutPlan plan_cuts(const std::vector<Shape>& parts, Vec2 base, const CutParams& p, const Box& sheet,
                  const std::vector<int>* part_order = nullptr);

// The order alone, for tests: elements are the chains (prepared as plan_cuts does);
// `before[i]` lists elements that must come before element i. Returns the order and its travel.
struct OrderElement {
  std::vector<Seg> path;
  bool closed = false;          // closed: starts anywhere; open: at either end
};
double travel_of(const std::vector<OrderElement>& els, const std::vector<int>& order, Vec2 base);
std::vector<int> order_elements(const std::vector<OrderElement>& els, const std::vector<std::vector<int>>& before,
                                Vec2 base, bool two_opt, double seconds = 3);
std::vector<int> nearest_neighbour(const std::vector<OrderElement>& els, const std::vector<std::vector<int>>& before,
                                   Vec2 base);

// The point of a closed path nearest p and the path restarted there.
std::vector<Seg> restart_at(const std::vector<Seg>& path, Vec2 p, double tol);

}  // namespace cpstep::cam
