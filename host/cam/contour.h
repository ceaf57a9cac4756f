// SPDX-License-Identifier: MIT
// Contours: entities chained end to end within a tolerance into closed and open
// chains (split where an end point lies on another entity, merged through shared
// vertices so that each connected group is cut with as few pierces as its graph
// allows: one when every vertex has an even degree), then the hierarchy of outer
// contours and holes. A Shape is one drawing's chains; transforms keep it exact.
#pragma once

#include <string>
#include <vector>

#include "cam/dxf.h"
#include "cam/geom.h"

namespace cpstep::cam {

struct Chain {
  std::vector<Seg> segs;
  bool closed = false;
  bool simple = true;   // closed and touching itself nowhere: a contour (kerf and leads apply)
  int depth = 0;        // how many closed simple chains contain it
  int parent = -1;      // the innermost closed simple chain containing it (-1: none)

  bool contour() const { return closed && simple; }
  bool hole() const { return contour() && depth % 2 == 1; }
  Vec2 start() const { return segs.front().a; }
  Vec2 end() const { return segs.back().b; }
  Box box() const;
  double length() const;
  std::vector<Vec2> polygon(double tol) const;  // flattened, without the closing point
  Vec2 inner_point() const;                     // a point of the chain away from its ends
  void reverse();
};

struct Shape {
  std::string file;
  std::vector<Chain> chains;
  std::vector<Source> sources;
  Box box() const;
  double area(double tol = 0.01) const;  // outers minus holes
};

// Every segment in at most one chain; `tol` joins end points closer than it.
// Notes (one line each) describe T-junction splits and chains that are not simple.
std::vector<Chain> build_chains(std::vector<Seg> segs, double tol, std::vector<std::string>* notes = nullptr);
// depth and parent of every chain (containment of flattened contours).
void classify(std::vector<Chain>& chains, double tol);
// A drawing as a shape: chains built and classified.
Shape make_shape(const Drawing& d, double tol, std::vector<std::string>* notes = nullptr);
// The shape mapped by m (exact: arcs under uneven scaling become elliptical arcs).
Shape transformed(const Shape& s, const Affine& m);
// Moved so that its bounding box starts at the origin.
Shape normalized(const Shape& s);
// Closed contours oriented for cutting: outer contours clockwise, holes
// counter-clockwise, so that the waste is always on the left of the torch.
void orient_for_cut(Chain& c);

}  // namespace cpstep::cam
