// Crossing resolution (see constraints.hpp): where a segment being inserted
// meets a constrained edge, a vertex goes in at the crossing, or an existing
// one takes its place, or the crossed constraint is rerouted. The choice is a
// chain of named steps (CrossingStep), each a function that changes nothing,
// tried in order by placeCrossing(); crossingVertex() then carries it out.
//
// The constraint cur→tgt crosses constrained edge e (R→L, in the
// triangle on cur's side). Makes a vertex at the crossing and returns it:
// R, L or an apex beside e when the crossing is within the tolerance of
// one, else a new vertex at the rounded crossing X. Returns invalid when it
// rerouted e's constraint instead: the caller walks cur→tgt again.
//
// When X is within the tolerance of an end of cur→tgt that is not beside e
// (slivers between), e's constraint is rerouted through that end if the
// segments to it cross nothing (rerouteThrough).
//
// X splits e into four strictly counter-clockwise triangles unless a
// triangle beside e is a sliver and X, rounded, falls outside it. Then, in
// order of preference:
// - X lies strictly inside the other triangle beside e, or does so when
//   moved a few ulps across e (it fell on e or beyond by rounding): X goes
//   in there and e's constraint runs R→X→L, bent by rounding only. Both new
//   edges lie inside that triangle, so the reroute crosses nothing.
// - X lies in a triangle farther off (beyond a sliver) and the segments from
//   R and L to X cross no constrained edge and pass through no vertex: X
//   goes in there and e's constraint is recovered as R→X→L by flips alone.
// - An apex of a sliver lies on e within the tolerance, or nearer to e than
//   X to any vertex: it is taken into e's constraint (R→apex→L). That adds
//   no vertex and no crossing (its edges to R and L exist). Each feature's
//   chain gains the apex or drops e where it already runs through the apex
//   (sliverApexOnEdge); the walk's guard would stop a cycle of such steps.
// - Otherwise the crossing is moved to the nearest of R, L and the apexes,
//   reported as `forced` when that bends a constraint beyond the tolerance.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/base/error.hpp"
#include "core/cdt/constraints.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::cdt {

using geometry::orient2d;

double ConstrainedTriangulation::zAlong(VertexId u, VertexId w, const Point2& p) const {
  const double dx = xy[w].x - xy[u].x, dy = xy[w].y - xy[u].y;
  const double l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((p.x - xy[u].x) * dx + (p.y - xy[u].y) * dy) / l2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return z[u] + t * (z[w] - z[u]);
}

bool ConstrainedTriangulation::outranks(FeatureId f, FeatureId g) const {
  const int pf = priorityOf(features, f), pg = priorityOf(features, g);
  return pf > pg || (pf == pg && f < g);
}

FeatureId ConstrainedTriangulation::edgeWinner(VertexId u, VertexId w) const {
  FeatureId best = kNoFeature;
  for (FeatureId f : edgeFeatures.find(edgeKey(u, w))) {
    if (best == kNoFeature || outranks(f, best)) best = f;
  }
  return best;
}

double ConstrainedTriangulation::constructionTolerance(const Point2& p) {
  return std::ldexp(std::max(std::fabs(p.x), std::fabs(p.y)), -40);
}

double ConstrainedTriangulation::distanceToSegment(VertexId v, VertexId a, VertexId b) const {
  const Point2 &p = xy[v], &pa = xy[a], &pb = xy[b];
  const double dx = pb.x - pa.x, dy = pb.y - pa.y, l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((p.x - pa.x) * dx + (p.y - pa.y) * dy) / l2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (pa.x + t * dx), p.y - (pa.y + t * dy));
}

bool ConstrainedTriangulation::chainsStayOpen(VertexId R, VertexId L, VertexId u) const {
  const auto ru = edgeFeatures.find(edgeKey(R, u)), ul = edgeFeatures.find(edgeKey(u, L));
  for (const FeatureId g : edgeFeatures.find(edgeKey(R, L))) {
    const bool onRu = std::find(ru.begin(), ru.end(), g) != ru.end();
    const bool onUl = std::find(ul.begin(), ul.end(), g) != ul.end();
    if (onRu != onUl) return false;
  }
  return true;
}

void ConstrainedTriangulation::addBend(VertexId R, VertexId L, FeatureId except, double by) {
  for (const FeatureId g : edgeFeatures.find(edgeKey(R, L))) {
    if (g == except) continue;
    if (g >= bend.size()) bend.resize(g + 1, 0.0);
    bend[g] += by;
  }
}

Crossing ConstrainedTriangulation::crossingAt(VertexId cur, VertexId tgt, HalfedgeId e) const {
  Crossing x{};
  x.cur = cur;
  x.tgt = tgt;
  x.e = e;
  x.R = origin(e);
  x.L = origin(nxt(e));
  x.X = geometry::intersectionPoint(xy[cur], xy[tgt], xy[x.R], xy[x.L]);
  x.c = origin(prv(e));
  x.d = origin(prv(twin(e)));
  auto dist2 = [&](VertexId v) { return squaredDistance(v, x.X); };
  x.nearest = dist2(x.R) <= dist2(x.L) ? x.R : x.L;
  // The apexes count too: with nearly collinear constraints the crossing
  // can be at cur itself (c) or at the vertex beyond (d).
  for (const VertexId u : {x.c, x.d}) {
    if (u != kInfinite && dist2(u) < dist2(x.nearest)) x.nearest = u;
  }
  // X is rounded, and R or L may itself be a rounded crossing of the same
  // lines (three constraints through one point): a constructed point this
  // close to a vertex is that vertex, even with snapTolerance 0.
  // The rounding error of X scales with the coordinates it is computed
  // from, not with X (which may be near the origin).
  double magnitude = 0.0;
  for (const VertexId u : {cur, tgt, x.R, x.L}) {
    magnitude = std::max({magnitude, std::fabs(xy[u].x), std::fabs(xy[u].y)});
  }
  x.tol = std::max(options.snapTolerance, constructionTolerance({magnitude, magnitude}));
  return x;
}

CrossingPlacement ConstrainedTriangulation::placeCrossing(const Crossing& x) const {
  if (auto p = atSegmentEnd(x)) return *p;
  if (auto p = atNearVertex(x)) return *p;
  if (auto p = splittingEdge(x)) return *p;
  if (auto p = besideEdge(x)) return *p;
  if (auto p = nudgedBesideEdge(x)) return *p;
  if (auto p = beyondSliver(x)) return *p;
  if (auto p = atSliverApex(x)) return *p;
  return atNearestVertex(x);
}

// The crossing at an end of cur→tgt that is no corner beside e (slivers
// between them): e's constraint runs through that end if it can by flips.
std::optional<CrossingPlacement> ConstrainedTriangulation::atSegmentEnd(const Crossing& x) const {
  VertexId end;
  for (const VertexId u : {x.cur, x.tgt}) {
    if (u != x.R && u != x.L && u != x.c && u != x.d && squaredDistance(u, x.X) <= x.tol * x.tol &&
        squaredDistance(u, x.X) < squaredDistance(x.nearest, x.X) &&
        clearPathEnd(x.R, xy[u], u).valid() && clearPathEnd(x.L, xy[u], u).valid()) {
      end = u;
    }
  }
  if (!end.valid()) return std::nullopt;
  CrossingPlacement p;
  p.step = CrossingStep::SegmentEnd;
  p.vertex = end;
  return p;
}

std::optional<CrossingPlacement> ConstrainedTriangulation::atNearVertex(const Crossing& x) const {
  if (!(squaredDistance(x.nearest, x.X) <= x.tol * x.tol)) return std::nullopt;
  CrossingPlacement p;
  p.step = CrossingStep::NearVertex;
  p.vertex = x.nearest;
  return p;
}

// X splits e into four strictly counter-clockwise triangles.
std::optional<CrossingPlacement> ConstrainedTriangulation::splittingEdge(const Crossing& x) const {
  if (!strictlyInside(x.R, x.L, x.c, x.X) || !strictlyInside(x.L, x.R, x.d, x.X)) {
    return std::nullopt;
  }
  CrossingPlacement p;
  p.step = CrossingStep::SplitEdge;
  p.at = x.X;
  return p;
}

// X is strictly inside the triangle beside e on the side it fell on.
std::optional<CrossingPlacement> ConstrainedTriangulation::besideEdge(const Crossing& x) const {
  const int side = geometry::orient2d(xy[x.R], xy[x.L], x.X);  // > 0: c's side
  CrossingPlacement p;
  p.step = CrossingStep::BesideEdge;
  p.at = x.X;
  if (side > 0 && strictlyInside(x.R, x.L, x.c, x.X)) {
    p.triangle = triangleOf(x.e);
  } else if (side < 0 && strictlyInside(x.L, x.R, x.d, x.X)) {
    p.triangle = neighbour(x.e);
  } else {
    return std::nullopt;
  }
  return p;
}

// X was on e or just across it, by rounding: a few ulps move it into the
// triangle beside e that holds it strictly.
std::optional<CrossingPlacement> ConstrainedTriangulation::nudgedBesideEdge(
    const Crossing& x) const {
  CrossingPlacement p;
  p.step = CrossingStep::Nudged;
  if (strictlyInside(x.R, x.L, x.c, x.X)) {
    if (const auto P = nudgedInto(x.R, x.L, x.c, x.X)) {
      p.triangle = triangleOf(x.e);
      p.at = *P;
      return p;
    }
  }
  if (strictlyInside(x.L, x.R, x.d, x.X)) {
    if (const auto Q = nudgedInto(x.L, x.R, x.d, x.X)) {
      p.triangle = neighbour(x.e);
      p.at = *Q;
      return p;
    }
  }
  return std::nullopt;
}

// X lies in a triangle beyond a sliver that the segments from R and L reach
// crossing nothing.
std::optional<CrossingPlacement> ConstrainedTriangulation::beyondSliver(const Crossing& x) const {
  const TriangleId t = clearPathEnd(x.R, x.X);
  if (!t.valid() || clearPathEnd(x.L, x.X) != t) return std::nullopt;
  CrossingPlacement p;
  p.step = CrossingStep::BeyondSliver;
  p.triangle = t;
  p.at = x.X;
  return p;
}

namespace {
// The apex of a sliver beside e that may join e's constraint (see
// sliverApexOnEdge), looked for among the apexes whose triangle does not hold
// X strictly.
std::pair<VertexId, double> sliverApexOf(const ConstrainedTriangulation& t, const Crossing& x) {
  const bool cOk = t.strictlyInside(x.R, x.L, x.c, x.X);
  const bool dOk = t.strictlyInside(x.L, x.R, x.d, x.X);
  return t.sliverApexOnEdge(x.e, !cOk ? x.c : kInfinite, !dOk ? x.d : kInfinite,
                            std::max(x.tol, std::sqrt(t.squaredDistance(x.nearest, x.X))));
}
}  // namespace

std::optional<CrossingPlacement> ConstrainedTriangulation::atSliverApex(const Crossing& x) const {
  const auto [apex, bendBy] = sliverApexOf(*this, x);
  if (!apex.valid() || apex == x.cur || apex == x.tgt) return std::nullopt;
  CrossingPlacement p;
  p.step = CrossingStep::SliverApex;
  p.vertex = apex;
  p.bendBy = bendBy;
  return p;
}

// The fallback: an apex at an end of cur→tgt is where the crossing is; else
// the nearest of R, L and the apexes.
CrossingPlacement ConstrainedTriangulation::atNearestVertex(const Crossing& x) const {
  const VertexId apex = sliverApexOf(*this, x).first;
  CrossingPlacement p;
  p.step = CrossingStep::NearestVertex;
  p.vertex = apex.valid() ? apex : x.nearest;
  return p;
}

VertexId ConstrainedTriangulation::crossingVertex(VertexId cur, VertexId tgt, HalfedgeId e,
                                                  FeatureId f) {
  const Crossing x = crossingAt(cur, tgt, e);
  const CrossingPlacement place = placeCrossing(x);
  ++crossingSteps[static_cast<std::size_t>(place.step)];
  const VertexId R = x.R, L = x.L;
  if (place.step == CrossingStep::SliverApex) {
    addBend(R, L, kNoFeature, place.bendBy);
    rerouteThrough(R, L, place.vertex);
    return VertexId::invalid();
  }
  const FeatureId existing = edgeWinner(R, L);
  const bool insertedWins = outranks(f, existing);
  CdtReport::Intersection ev;
  ev.existing = existing;
  ev.inserted = f;
  ev.zExisting = zAlong(R, L, x.X);
  ev.zInserted = zAlong(cur, tgt, x.X);
  VertexId v;
  if (place.vertex.valid()) {
    v = place.vertex;
    if (place.step == CrossingStep::SegmentEnd) rerouteThrough(R, L, v);
    // Both constraints now run through v: each bends by v's distance from
    // it (the distance from X is no measure where the lines nearly overlap).
    ev.moved = std::max(distanceToSegment(v, cur, tgt), distanceToSegment(v, R, L));
    ev.forced = ev.moved > x.tol;
    if (v == x.c || v == x.d) {
      // Every feature of e bends, not only the one the event names.
      addBend(R, L, existing, ev.moved);
      rerouteThrough(R, L, v);
    }
  } else {
    v = xy.endId();
    xy.push_back(place.at);
    z.push_back(insertedWins ? ev.zInserted : ev.zExisting);
    vfeat.push_back(insertedWins ? f : existing);
    rep.push_back(v);
    vhe.push_back(HalfedgeId::invalid());
    insertedUpTo = xy.size();
    if (place.step == CrossingStep::SplitEdge) {
      splitEdge(e, v);
    } else {
      splitTriangle(place.triangle, v);  // e stays constrained, so it is not flipped
      rerouteThrough(R, L, v);
    }
    lopAround(v);
  }
  ev.vertex = v;
  ev.at = {xy[v].x, xy[v].y, z[v]};
  report.intersections.push_back(ev);
  return v;
}

TriangleId ConstrainedTriangulation::clearPathEnd(VertexId a, const Point2& p,
                                                  VertexId target) const {
  // The wedge at a that the segment leaves through: a→u→w, u right, w left.
  HalfedgeId e;
  const HalfedgeId start = vhe[a];
  HalfedgeId h = start;
  do {
    const VertexId u = origin(nxt(h)), w = origin(prv(h));
    if (target.valid() && (u == target || w == target)) return triangleOf(h);
    if (u != kInfinite && w != kInfinite) {
      const int ou = orient2d(xy[a], p, xy[u]), ow = orient2d(xy[a], p, xy[w]);
      if (ou == 0 || ow == 0) return TriangleId::invalid();
      if (ou < 0 && ow > 0) {
        e = nxt(h);
        break;
      }
    }
    h = twin(prv(h));
  } while (h != start);
  if (!e.valid()) return TriangleId::invalid();
  for (std::size_t steps = 0; steps < tv.size(); ++steps) {
    const int o = orient2d(xy[origin(e)], xy[origin(nxt(e))], p);
    if (o > 0) return triangleOf(e);  // p is on this side of e: inside e's triangle
    if (o == 0 || cons[e]) return TriangleId::invalid();
    const HalfedgeId g = twin(e);
    const VertexId x = origin(prv(g));
    if (x == kInfinite) return TriangleId::invalid();
    if (x == target) return triangleOf(g);
    const int ox = orient2d(xy[a], p, xy[x]);
    if (ox == 0) return TriangleId::invalid();
    e = ox > 0 ? nxt(g) : prv(g);
  }
  return TriangleId::invalid();
}

void ConstrainedTriangulation::rerouteThrough(VertexId R, VertexId L, VertexId w) {
  const HalfedgeId h = findHalfedge(R, L);
  if (!h.valid()) throw internalError("the constrained edge to reroute is missing");
  if (rerouteDepth >= rerouteDepthLimit) {
    throw internalError("constraint reroutes nested more than " +
                        std::to_string(rerouteDepthLimit) + " deep (at " + std::to_string(xy[R].x) +
                        ", " + std::to_string(xy[R].y) + ")");
  }
  struct Nesting {
    std::size_t& depth;
    explicit Nesting(std::size_t& d) : depth(d) { ++depth; }
    ~Nesting() { --depth; }
    Nesting(const Nesting&) = delete;
    Nesting& operator=(const Nesting&) = delete;
  } nesting(rerouteDepth);
  deepestReroute = std::max(deepestReroute, rerouteDepth);
  const auto view = edgeFeatures.find(edgeKey(R, L));
  const std::vector<FeatureId> fs(view.begin(), view.end());
  cons[h] = cons[twin(h)] = 0;
  edgeFeatures.erase(edgeKey(R, L));
  for (const FeatureId g : fs) {
    insertSegment(R, w, g);
    insertSegment(w, L, g);
  }
  std::vector<std::pair<VertexId, VertexId>> todo{{R, L}};
  lop(todo);
}

std::optional<Point2> ConstrainedTriangulation::nudgedInto(VertexId a, VertexId b, VertexId u,
                                                           const Point2& X) const {
  if (u == kInfinite) return std::nullopt;
  const double dx = xy[b].x - xy[a].x, dy = xy[b].y - xy[a].y, len = std::hypot(dx, dy);
  if (!(len > 0)) return std::nullopt;
  double magnitude = std::max(std::fabs(X.x), std::fabs(X.y));
  for (const VertexId w : {a, b}) {
    magnitude = std::max({magnitude, std::fabs(xy[w].x), std::fabs(xy[w].y)});
  }
  const double ulp = std::ldexp(magnitude, -52);
  for (int k = 1; k <= 8; ++k) {
    const double step = k * ulp / len;
    const Point2 P{X.x - dy * step, X.y + dx * step};  // left of a→b
    if (orient2d(xy[a], xy[b], P) > 0 && orient2d(xy[b], xy[u], P) > 0 &&
        orient2d(xy[u], xy[a], P) > 0) {
      return P;
    }
  }
  return std::nullopt;
}

std::pair<VertexId, double> ConstrainedTriangulation::sliverApexOnEdge(HalfedgeId e, VertexId c,
                                                                       VertexId d,
                                                                       double maxDistance) const {
  const VertexId R = origin(e), L = origin(nxt(e));
  std::pair<VertexId, double> best{VertexId::invalid(), maxDistance};
  for (const VertexId u : {c, d}) {
    if (u == kInfinite || !chainsStayOpen(R, L, u)) continue;
    const double du = distanceToSegment(u, R, L);
    if (du <= best.second) best = {u, du};
  }
  return best;
}

}  // namespace tinsmith::cdt
