// SPDX-License-Identifier: MIT
#include "cam/contour.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

namespace cpstep::cam {

Box Chain::box() const {
  Box b;
  for (const Seg& s : segs) b.add_box(s.box());
  return b;
}

double Chain::length() const {
  double l = 0;
  for (const Seg& s : segs) l += s.length();
  return l;
}

std::vector<Vec2> Chain::polygon(double tol) const {
  std::vector<Vec2> pts;
  for (std::size_t i = 0; i < segs.size(); ++i) segs[i].flatten(tol, pts, i == 0);
  if (closed && pts.size() > 1 && dist(pts.front(), pts.back()) < 1e-9) pts.pop_back();
  return pts;
}

Vec2 Chain::inner_point() const {
  const Seg& s = segs.front();
  return s.kind == SegKind::line ? s.at(0.5) : s.at(0.5 * (s.t0 + s.t1));
}

void Chain::reverse() {
  std::reverse(segs.begin(), segs.end());
  for (Seg& s : segs) s = s.reversed();
}

Box Shape::box() const {
  Box b;
  for (const Chain& c : chains) b.add_box(c.box());
  return b;
}

double Shape::area(double tol) const {
  double a = 0;
  for (const Chain& c : chains)
    if (c.contour()) a += (c.hole() ? -1 : 1) * std::abs(signed_area(c.polygon(tol)));
  return a;
}

namespace {

struct Dsu {
  std::vector<int> p;
  explicit Dsu(std::size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) { return p[std::size_t(x)] == x ? x : p[std::size_t(x)] = find(p[std::size_t(x)]); }
  void unite(int a, int b) { p[std::size_t(find(a))] = find(b); }
};

// Splits segments where another segment's end point lies on them (not at their ends).
std::vector<Seg> split_at_junctions(std::vector<Seg> segs, double tol, std::vector<std::string>* notes) {
  std::vector<Vec2> ends;
  for (const Seg& s : segs) {
    if (s.closed()) continue;  // where a whole circle starts is arbitrary: it splits nothing
    ends.push_back(s.a);
    ends.push_back(s.b);
  }
  bool changed = true;
  for (int pass = 0; changed && pass < 4; ++pass) {
    changed = false;
    std::vector<Seg> out;
    for (const Seg& s : segs) {
      Box bx = s.box();
      std::vector<double> cuts;
      for (Vec2 e : ends) {
        if (e.x < bx.lo.x - tol || e.x > bx.hi.x + tol || e.y < bx.lo.y - tol || e.y > bx.hi.y + tol) continue;
        if (dist(e, s.a) <= tol || dist(e, s.b) <= tol) continue;
        const double t = s.nearest_param(e);
        if (dist(s.at(t), e) > tol) continue;
        cuts.push_back(t);
      }
      if (cuts.empty()) { out.push_back(s); continue; }
      changed = true;
      Seg rest = s;
      if (s.closed()) {
        // a full circle or ellipse touched at a point: start it there instead of splitting
        const double t = cuts.front();
        const double dir = s.t1 > s.t0 ? 1 : -1;
        rest.t0 = t;
        rest.t1 = t + dir * 2 * kPi;
        rest.refresh();
        out.push_back(rest);
        if (notes) notes->push_back("a closed curve starts where another entity touches it");
        continue;
      }
      std::sort(cuts.begin(), cuts.end());
      if (s.t1 < s.t0 && s.kind == SegKind::arc) std::reverse(cuts.begin(), cuts.end());
      double prev = s.kind == SegKind::line ? 0.0 : s.t0;
      for (double t : cuts) {
        if (std::abs(t - prev) < 1e-12) continue;
        if (s.kind == SegKind::line) {
          // re-express t on what is left of the line
          const double tl = (t - prev) / (1 - prev);
          auto [p, q] = rest.split(tl);
          out.push_back(p);
          rest = q;
        } else {
          auto [p, q] = rest.split(t);
          out.push_back(p);
          rest = q;
        }
        prev = t;
      }
      out.push_back(rest);
      if (notes) notes->push_back("an entity split where another one ends on it");
    }
    segs = std::move(out);
  }
  return segs;
}

}  // namespace

std::vector<Chain> build_chains(std::vector<Seg> segs, double tol, std::vector<std::string>* notes) {
  segs = split_at_junctions(std::move(segs), tol, notes);
  // nodes: end points merged within tol
  std::vector<Vec2> nodes;
  auto node_of = [&](Vec2 p) {
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (dist(nodes[i], p) <= tol) return int(i);
    nodes.push_back(p);
    return int(nodes.size()) - 1;
  };
  struct Edge { int a, b; bool virt; };
  std::vector<Edge> edges;
  for (const Seg& s : segs) {
    const int a = node_of(s.a), b = s.closed() ? a : node_of(s.b);
    edges.push_back({a, b, false});
  }
  const std::size_t nreal = edges.size();
  Dsu dsu(nodes.size());
  std::vector<int> degree(nodes.size(), 0);
  for (const Edge& e : edges) {
    dsu.unite(e.a, e.b);
    degree[std::size_t(e.a)]++;
    degree[std::size_t(e.b)]++;
  }
  // pair the odd vertices of each component with virtual edges (nearest first)
  std::map<int, std::vector<int>> odd;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (degree[i] % 2) odd[dsu.find(int(i))].push_back(int(i));
  for (auto& [root, vs] : odd) {
    std::vector<bool> used(vs.size(), false);
    for (std::size_t i = 0; i < vs.size(); ++i) {
      if (used[i]) continue;
      used[i] = true;
      std::size_t best = i;
      double bd = 1e300;
      for (std::size_t j = 0; j < vs.size(); ++j)
        if (!used[j] && dist(nodes[std::size_t(vs[i])], nodes[std::size_t(vs[j])]) < bd) {
          bd = dist(nodes[std::size_t(vs[i])], nodes[std::size_t(vs[j])]);
          best = j;
        }
      used[best] = true;
      edges.push_back({vs[i], vs[best], true});
    }
  }
  std::vector<std::vector<std::pair<int, int>>> adj(nodes.size());  // (edge, other end)
  for (std::size_t i = 0; i < edges.size(); ++i) {
    adj[std::size_t(edges[i].a)].push_back({int(i), edges[i].b});
    if (edges[i].a != edges[i].b) adj[std::size_t(edges[i].b)].push_back({int(i), edges[i].a});
    else adj[std::size_t(edges[i].a)].push_back({int(i), edges[i].a});
  }
  std::vector<bool> used(edges.size(), false), node_done(nodes.size(), false);
  std::vector<std::size_t> ptr(nodes.size(), 0);
  std::vector<Chain> chains;
  for (std::size_t start = 0; start < nodes.size(); ++start) {
    if (node_done[std::size_t(dsu.find(int(start)))] || degree[start] == 0) continue;
    node_done[std::size_t(dsu.find(int(start)))] = true;
    // start at an end of a virtual edge when there is one, so trails begin at odd vertices
    int s0 = int(start);
    if (odd.count(dsu.find(int(start)))) s0 = odd[dsu.find(int(start))].front();
    // Hierholzer: the circuit as (edge, direction) in order
    std::vector<std::pair<int, int>> stack{{s0, -1}};  // (node, edge used to get here)
    std::vector<int> circuit_edges;                   // edges, reversed order of the circuit
    std::vector<int> circuit_nodes;
    while (!stack.empty()) {
      const int v = stack.back().first;
      auto& p = ptr[std::size_t(v)];
      while (p < adj[std::size_t(v)].size() && used[std::size_t(adj[std::size_t(v)][p].first)]) ++p;
      if (p == adj[std::size_t(v)].size()) {
        circuit_nodes.push_back(v);
        circuit_edges.push_back(stack.back().second);
        stack.pop_back();
      } else {
        const auto [e, w] = adj[std::size_t(v)][p];
        used[std::size_t(e)] = true;
        stack.push_back({w, e});
      }
    }
    // circuit_nodes is the circuit backwards: node k+1 -> node k via circuit_edges[k]
    std::reverse(circuit_nodes.begin(), circuit_nodes.end());
    std::reverse(circuit_edges.begin(), circuit_edges.end());
    // now circuit_edges[k] leads from circuit_nodes[k-1] to circuit_nodes[k]
    std::vector<std::vector<Seg>> trails(1);
    std::vector<std::vector<int>> trail_nodes(1);
    trail_nodes.back().push_back(circuit_nodes.front());
    for (std::size_t k = 1; k < circuit_nodes.size(); ++k) {
      const int e = circuit_edges[k];
      const int from = circuit_nodes[k - 1], to = circuit_nodes[k];
      if (edges[std::size_t(e)].virt) {
        trails.emplace_back();
        trail_nodes.emplace_back(1, to);
        continue;
      }
      Seg sg = segs[std::size_t(e)];
      if (edges[std::size_t(e)].a != from || (edges[std::size_t(e)].a == edges[std::size_t(e)].b && false)) sg = sg.reversed();
      (void)to;
      trails.back().push_back(sg);
      trail_nodes.back().push_back(to);
    }
    // a circuit that starts inside a trail: the last and first trail are one
    if (trails.size() > 1 && !trails.front().empty() && !trails.back().empty() &&
        trail_nodes.back().back() == trail_nodes.front().front()) {
      trails.back().insert(trails.back().end(), trails.front().begin(), trails.front().end());
      trail_nodes.back().insert(trail_nodes.back().end(), trail_nodes.front().begin() + 1, trail_nodes.front().end());
      trails.erase(trails.begin());
      trail_nodes.erase(trail_nodes.begin());
    }
    for (std::size_t t = 0; t < trails.size(); ++t) {
      if (trails[t].empty()) continue;
      Chain c;
      c.segs = std::move(trails[t]);
      const auto& tn = trail_nodes[t];
      c.closed = tn.front() == tn.back();
      std::vector<int> inner(tn.begin(), tn.end() - (c.closed ? 1 : 0));
      std::sort(inner.begin(), inner.end());
      c.simple = c.closed && std::adjacent_find(inner.begin(), inner.end()) == inner.end();
      // snap the joints: each segment starts exactly where the previous ends
      for (std::size_t i = 1; i < c.segs.size(); ++i) c.segs[i].a = c.segs[i - 1].b;
      if (c.closed && c.segs.size() > 1) c.segs.back().b = c.segs.front().a;
      if (c.closed && !c.simple && notes)
        notes->push_back("a closed chain touches itself: cut along the drawing, without kerf or leads");
      chains.push_back(std::move(c));
    }
  }
  (void)nreal;
  return chains;
}

void classify(std::vector<Chain>& chains, double tol) {
  std::vector<std::vector<Vec2>> polys(chains.size());
  std::vector<double> areas(chains.size(), 0);
  for (std::size_t i = 0; i < chains.size(); ++i)
    if (chains[i].contour()) {
      polys[i] = chains[i].polygon(tol);
      areas[i] = std::abs(signed_area(polys[i]));
    }
  for (std::size_t i = 0; i < chains.size(); ++i) {
    chains[i].depth = 0;
    chains[i].parent = -1;
    const Vec2 p = chains[i].inner_point();
    double best = 1e300;
    for (std::size_t j = 0; j < chains.size(); ++j) {
      if (i == j || !chains[j].contour()) continue;
      if (chains[i].contour() && areas[j] <= areas[i]) continue;
      if (!point_in_polygon(p, polys[j])) continue;
      chains[i].depth++;
      if (areas[j] < best) { best = areas[j]; chains[i].parent = int(j); }
    }
  }
}

Shape make_shape(const Drawing& d, double tol, std::vector<std::string>* notes) {
  Shape s;
  s.file = d.file;
  s.sources = d.sources;
  s.chains = build_chains(d.segs, tol, notes);
  classify(s.chains, tol);
  return s;
}

Shape transformed(const Shape& s, const Affine& m) {
  Shape r = s;
  for (Chain& c : r.chains)
    for (Seg& g : c.segs) g = g.transformed(m);
  return r;
}

Shape normalized(const Shape& s) {
  const Box b = s.box();
  return transformed(s, Affine::translate(-b.lo.x, -b.lo.y));
}

void orient_for_cut(Chain& c) {
  if (!c.contour()) return;
  std::vector<Vec2> poly = c.polygon(0.05);
  const bool ccw = signed_area(poly) > 0;
  const bool want_ccw = c.hole();
  if (ccw != want_ccw) c.reverse();
}

}  // namespace cpstep::cam
