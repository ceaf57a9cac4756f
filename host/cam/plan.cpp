// SPDX-License-Identifier: MIT
#include "cam/plan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "cam/kerf.h"

namespace cpstep::cam {

namespace {

struct Near {
  std::size_t seg = 0;
  double t = 0;
  Vec2 p;
  double d = 1e300;
};

Near nearest_on(const std::vector<Seg>& path, Vec2 p) {
  Near best;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const double t = path[i].nearest_param(p);
    const Vec2 q = path[i].at(t);
    const double d = dist(q, p);
    if (d < best.d - 1e-12) best = {i, t, q, d};
  }
  return best;
}

double dist_to_path(const std::vector<Seg>& path, Vec2 p) { return nearest_on(path, p).d; }

struct Entry {
  Vec2 in, out;
  bool reverse = false;
};

Entry entry_of(const OrderElement& e, Vec2 pos) {
  if (e.closed) {
    const Vec2 s = nearest_on(e.path, pos).p;
    return {s, s, false};
  }
  const Vec2 a = e.path.front().a, b = e.path.back().b;
  if (dist(pos, a) <= dist(pos, b)) return {a, b, false};
  return {b, a, true};
}

bool valid_order(const std::vector<int>& order, const std::vector<std::vector<int>>& before) {
  std::vector<int> at(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) at[std::size_t(order[i])] = int(i);
  for (std::size_t e = 0; e < before.size(); ++e)
    for (int b : before[e])
      if (at[std::size_t(b)] > at[e]) return false;
  return true;
}

}  // namespace

std::vector<Seg> restart_at(const std::vector<Seg>& path, Vec2 p, double tol) {
  const Near n = nearest_on(path, p);
  const Seg& s = path[n.seg];
  std::vector<Seg> out;
  std::size_t first = n.seg;
  if (dist(n.p, s.a) <= tol) {
    first = n.seg;
  } else if (dist(n.p, s.b) <= tol) {
    first = (n.seg + 1) % path.size();
  } else {
    auto [a, b] = s.split(n.t);
    if (s.closed()) {  // a whole circle: restart it at the point
      Seg c = s;
      const double dir = s.t1 > s.t0 ? 1 : -1;
      c.t0 = n.t;
      c.t1 = n.t + dir * 2 * kPi;
      c.refresh();
      out.push_back(c);
      for (std::size_t k = 1; k < path.size(); ++k) out.push_back(path[(n.seg + k) % path.size()]);
      return out;
    }
    out.push_back(b);
    for (std::size_t k = 1; k < path.size(); ++k) out.push_back(path[(n.seg + k) % path.size()]);
    out.push_back(a);
    return out;
  }
  for (std::size_t k = 0; k < path.size(); ++k) out.push_back(path[(first + k) % path.size()]);
  return out;
}

double travel_of(const std::vector<OrderElement>& els, const std::vector<int>& order, Vec2 pos) {
  double t = 0;
  for (int i : order) {
    const Entry e = entry_of(els[std::size_t(i)], pos);
    t += dist(pos, e.in);
    pos = e.out;
  }
  return t;
}

std::vector<int> nearest_neighbour(const std::vector<OrderElement>& els, const std::vector<std::vector<int>>& before,
                                   Vec2 pos) {
  const std::size_t n = els.size();
  std::vector<bool> done(n, false);
  std::vector<int> order;
  for (std::size_t step = 0; step < n; ++step) {
    int best = -1;
    double bd = 1e300;
    Entry be;
    for (std::size_t i = 0; i < n; ++i) {
      if (done[i]) continue;
      bool ready = true;
      for (int b : before[i]) ready = ready && done[std::size_t(b)];
      if (!ready) continue;
      const Entry e = entry_of(els[i], pos);
      const double d = dist(pos, e.in);
      if (d < bd - 1e-12) { bd = d; best = int(i); be = e; }
    }
    if (best < 0) break;  // a cycle in `before`: cannot happen for containment
    done[std::size_t(best)] = true;
    order.push_back(best);
    pos = be.out;
  }
  return order;
}

std::vector<int> order_elements(const std::vector<OrderElement>& els, const std::vector<std::vector<int>>& before,
                                Vec2 base, bool two_opt, double seconds) {
  std::vector<int> order = nearest_neighbour(els, before, base);
  if (!two_opt || order.size() < 3) return order;
  const auto t_end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  double best = travel_of(els, order, base);
  const std::size_t n = order.size();
  const std::size_t window = n > 200 ? 60 : n;
  bool improved = true;
  while (improved && std::chrono::steady_clock::now() < t_end) {
    improved = false;
    for (std::size_t i = 0; i + 1 < n; ++i)
      for (std::size_t j = i + 1; j < n && j - i <= window; ++j) {
        std::vector<int> cand = order;
        std::reverse(cand.begin() + long(i), cand.begin() + long(j) + 1);
        if (!valid_order(cand, before)) continue;
        const double c = travel_of(els, cand, base);
        if (c < best - 1e-9) {
          best = c;
          order = std::move(cand);
          improved = true;
        }
        if (std::chrono::steady_clock::now() >= t_end) break;
      }
  }
  return order;
}

namespace {

struct Element {
  int part = 0, chain = 0;
  bool contour = false, hole = false;
  OrderElement el;
  std::vector<Vec2> poly;  // contours: flattened, for the side tests of the leads
};

bool on_waste_side(const Element& e, Vec2 p) {
  const bool inside = point_in_polygon(p, e.poly);
  return e.hole ? inside : !inside;
}

// A straight lead between the contour point s and p, all of it on the waste side
// and at least half its length away from the contour at p.
bool lead_ok(const Element& e, Vec2 s, Vec2 p, double len) {
  if (!on_waste_side(e, p)) return false;
  for (int k = 1; k < 8; ++k)
    if (!on_waste_side(e, s + (p - s) * (k / 8.0))) return false;
  return dist_to_path(e.el.path, p) >= 0.5 * len - 1e-9;
}

Vec2 waste_normal(const std::vector<Seg>& path) {
  const Vec2 tout = path.front().start_tangent(), tin = path.back().end_tangent();
  Vec2 n = perp_left(tin) + perp_left(tout);
  if (norm(n) < 1e-6) n = perp_left(tout);
  return unit(n);
}

}  // namespace

CutPlan plan_cuts(const std::vector<Shape>& parts, Vec2 base, const CutParams& p, const Box& sheet,
                  const std::vector<int>* part_order) {
  CutPlan plan;
  plan.base = base;
  std::vector<Element> els;
  std::map<std::pair<int, int>, int> index;  // (part, chain) -> element
  for (std::size_t pi = 0; pi < parts.size(); ++pi) {
    const Shape& sh = parts[pi];
    for (std::size_t ci = 0; ci < sh.chains.size(); ++ci) {
      Chain c = sh.chains[ci];
      std::vector<Seg> segs;
      for (const Seg& s : c.segs)
        for (const Seg& q : to_circular(s, p.arc_tol)) segs.push_back(q);
      c.segs = segs;
      Element e;
      e.part = int(pi);
      e.chain = int(ci);
      e.contour = c.contour();
      e.hole = c.hole();
      e.el.closed = c.closed;
      const std::string name = "part " + std::to_string(pi + 1) + (e.hole ? " hole " : " chain ") + std::to_string(ci + 1);
      if (e.contour) {
        orient_for_cut(c);
        OffsetResult o = offset_left(c.segs, p.kerf / 2, 1e-4);
        for (const std::string& n : o.notes) plan.warnings.push_back(name + ": " + n);
        if (o.segs.empty()) continue;
        e.el.path = std::move(o.segs);
        Chain tmp;
        tmp.segs = e.el.path;
        tmp.closed = true;
        e.poly = tmp.polygon(0.01);
      } else {
        e.el.path = c.segs;
      }
      index[{int(pi), int(ci)}] = int(els.size());
      els.push_back(std::move(e));
    }
  }
  std::vector<std::vector<int>> before(els.size());
  for (std::size_t i = 0; i < els.size(); ++i) {
    const int parent = parts[std::size_t(els[i].part)].chains[std::size_t(els[i].chain)].parent;
    if (parent < 0) continue;
    auto it = index.find({els[i].part, parent});
    if (it != index.end()) before[std::size_t(it->second)].push_back(int(i));
  }
  std::vector<OrderElement> oe;
  for (const Element& e : els) oe.push_back(e.el);
  std::vector<int> order;
  if (part_order) {
    Vec2 pos = base;
    for (int part : *part_order) {
      std::vector<int> ids;
      for (std::size_t i = 0; i < els.size(); ++i)
        if (els[i].part == part) ids.push_back(int(i));
      std::map<int, int> local;
      for (std::size_t k = 0; k < ids.size(); ++k) local[ids[k]] = int(k);
      std::vector<OrderElement> sub;
      std::vector<std::vector<int>> sb(ids.size());
      for (std::size_t k = 0; k < ids.size(); ++k) {
        sub.push_back(oe[std::size_t(ids[k])]);
        for (int b : before[std::size_t(ids[k])]) sb[k].push_back(local[b]);
      }
      const std::vector<int> so = order_elements(sub, sb, pos, p.two_opt, p.two_opt_seconds);
      for (int k : so) {
        order.push_back(ids[std::size_t(k)]);
        pos = entry_of(sub[std::size_t(k)], pos).out;
      }
    }
  } else {
    order = order_elements(oe, before, base, p.two_opt, p.two_opt_seconds);
  }

  Vec2 pos = base;
  for (int idx : order) {
    const Element& e = els[std::size_t(idx)];
    Cut cut;
    cut.part = e.part;
    cut.chain = e.chain;
    cut.contour = e.contour;
    cut.hole = e.hole;
    const std::string name = "part " + std::to_string(e.part + 1) + (e.hole ? " hole " : " chain ") + std::to_string(e.chain + 1);
    if (e.el.closed) {
      std::vector<Seg> path = restart_at(e.el.path, pos, p.chain_tol);
      if (e.contour && p.lead_in > 0) {
        // the nearest point first, then the middles of the segments nearest the torch
        std::vector<Vec2> starts{path.front().a};
        std::vector<std::pair<double, Vec2>> mids;
        for (const Seg& s : e.el.path) {
          const Vec2 m = s.kind == SegKind::line ? s.at(0.5) : s.at(0.5 * (s.t0 + s.t1));
          mids.push_back({dist(m, pos), m});
        }
        std::sort(mids.begin(), mids.end(), [](auto& a, auto& b) { return a.first < b.first; });
        for (std::size_t k = 0; k < mids.size() && k < 12; ++k) starts.push_back(mids[k].second);
        bool found = false;
        for (double frac : {1.0, 0.5, 0.25}) {
          for (Vec2 s0 : starts) {
            std::vector<Seg> cand = restart_at(e.el.path, s0, p.chain_tol);
            const Vec2 s = cand.front().a;
            const double len = p.lead_in * frac;
            const Vec2 pp = s + waste_normal(cand) * len;
            if (!lead_ok(e, s, pp, len)) continue;
            path = cand;
            cut.lead_in = Seg::line(pp, s);
            if (frac < 1.0)
              plan.warnings.push_back(name + ": lead-in shortened to " + fmt_num(len) + " mm (no room for " +
                                      fmt_num(p.lead_in) + " mm)");
            found = true;
            break;
          }
          if (found) break;
        }
        if (!found) plan.warnings.push_back(name + ": no room for a lead-in: pierced on the contour");
      }
      if (e.contour && p.lead_out > 0) {
        const Vec2 s = path.back().b;
        const Vec2 dir = unit(waste_normal(path) + path.back().end_tangent());
        for (double frac : {1.0, 0.5, 0.25}) {
          const double len = p.lead_out * frac;
          const Vec2 q = s + dir * len;
          if (lead_ok(e, s, q, len)) {
            cut.lead_out = Seg::line(s, q);
            break;
          }
        }
      }
      cut.path = std::move(path);
    } else {
      const Entry en = entry_of(e.el, pos);
      cut.path = e.el.path;
      if (en.reverse) {
        std::reverse(cut.path.begin(), cut.path.end());
        for (Seg& s : cut.path) s = s.reversed();
      }
    }
    cut.pierce = cut.lead_in ? cut.lead_in->a : cut.path.front().a;
    const double edge = std::min({cut.pierce.x - sheet.lo.x, sheet.hi.x - cut.pierce.x, cut.pierce.y - sheet.lo.y,
                                  sheet.hi.y - cut.pierce.y});
    cut.edge_pierce = !sheet.empty() && edge < p.edge_distance;
    cut.delay = cut.edge_pierce ? p.pierce_edge_s : p.pierce_s;
    plan.rapid_mm += dist(pos, cut.pierce);
    double len = 0;
    for (const Seg& s : cut.path) len += s.length();
    const double leads = (cut.lead_in ? cut.lead_in->length() : 0) + (cut.lead_out ? cut.lead_out->length() : 0);
    plan.cut_mm += len + leads;
    plan.lead_mm += leads;
    plan.pierces++;
    pos = cut.lead_out ? cut.lead_out->b : cut.path.back().b;
    plan.cuts.push_back(std::move(cut));
  }
  return plan;
}

}  // namespace cpstep::cam
