// The two-halves build of the CDT's first bulk of points (see
// CdtOptions::splitMinPoints).
//
// The first bulk of points may be triangulated as two halves on either side
// of a vertical line x = xr, each on its own thread, and then merged by
// repairing the seam between them:
//   * a triangle of DT(left) whose circumcircle lies strictly left of every
//     right point is a triangle of DT(all) — "safe" (likewise on the right);
//   * every other triangle of DT(all) has its corners among the corners of
//     the unsafe triangles (ghosts count as unsafe): the seam set S;
//   * so DT(all) = safe left ∪ safe right ∪ the triangles of DT(S) in the
//     hole the safe ones leave. DT(S) is built with the hole's border edges
//     as constraints (they are Delaunay edges of all the points), which
//     keeps the two sides consistent on cocircular input.
// The same holds for constrained triangulations when each half carries only
// constraints with both ends on its side (they stay there, so they cannot
// cross the other side's safe triangles) and DT(S) also keeps the
// constrained edges inside the hole; constraints across the split go in
// afterwards.
// The split depends on the points only, never on the thread count, so
// neither does the mesh.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/base/error.hpp"
#include "core/cdt/constraints.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::cdt {
namespace {

/// x-extent [lo, hi] of the circumcircle of (a, b, c), CCW, widened by a
/// bound on its rounding error; false when the triangle is too flat for the
/// bound to hold (callers then treat it as unsafe).
bool circleXRange(const Point2& a, const Point2& b, const Point2& c, double& lo, double& hi) {
  constexpr double eps = 0x1p-52;
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  const double d = 2 * (bx * cy - by * cx);
  const double dErr = 16 * eps * (std::abs(bx * cy) + std::abs(by * cx));
  if (!(d > 4 * dErr)) return false;
  const double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
  // |error| of each centre coordinate: numerator rounding plus the relative
  // error of d (at most a third here), with a factor 2 to spare.
  const double uxErr = 2 * (16 * eps * (std::abs(cy) * b2 + std::abs(by) * c2) / d +
                            std::abs(ux) * dErr / (d - dErr));
  const double uyErr = 2 * (16 * eps * (std::abs(bx) * c2 + std::abs(cx) * b2) / d +
                            std::abs(uy) * dErr / (d - dErr));
  const double r = std::sqrt(ux * ux + uy * uy);
  const double slack = uxErr + uxErr + uyErr + 8 * eps * (std::abs(a.x) + std::abs(ux) + r);
  lo = a.x + ux - r - slack;
  hi = a.x + ux + r + slack;
  return std::isfinite(lo) && std::isfinite(hi);
}

/// A border edge between a safe triangle and the hole: u→v (global ids) has
/// the hole on its left; `safe` is the twin half-edge in the safe triangle
/// (in this triangulation for the left half, in `right` for the right half).
struct SeamBorder {
  VertexId u, v;
  HalfedgeId safe;
  bool rightHalf;
};

}  // namespace

IdVector<TriangleId, std::uint8_t> ConstrainedTriangulation::unsafeTriangles(
    bool leftHalf, double leftMax, double rightMin) const {
  IdVector<TriangleId, std::uint8_t> unsafe(triCount(), 0);
  IdVector<TriangleId, std::uint8_t> tested(triCount(), 0);
  std::vector<TriangleId> todo;
  for (std::uint32_t k = 0; k < triCount(); ++k) {
    const TriangleId t(k);
    if (isGhost(t)) {
      unsafe[t] = tested[t] = 1;
      todo.push_back(t);
    }
  }
  while (!todo.empty()) {
    const TriangleId t = todo.back();
    todo.pop_back();
    for (std::uint32_t i = 0; i < 3; ++i) {
      const TriangleId n = neighbour(halfedgeOf(t, i));
      if (tested[n]) continue;
      tested[n] = 1;
      double lo = 0, hi = 0;
      const bool known = circleXRange(xy[corner(n, 0)], xy[corner(n, 1)], xy[corner(n, 2)], lo, hi);
      if (!known || (leftHalf ? !(hi < rightMin) : !(lo > leftMax))) {
        unsafe[n] = 1;
        todo.push_back(n);
      }
    }
  }
  return unsafe;
}

double ConstrainedTriangulation::splitValue(const std::vector<VertexId>& order) const {
  std::vector<double> xs(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) xs[i] = xy[order[i]].x;
  const std::size_t mid = xs.size() / 2;
  std::nth_element(xs.begin(), xs.begin() + static_cast<std::ptrdiff_t>(mid), xs.end());
  const double median = xs[mid];
  const double tol = options.snapTolerance;
  if (!(tol > 0)) return median;
  // The gap wider than tol in x nearest to the median, from the sorted
  // values around it.
  for (double window = 64 * tol; window <= 1e6 * tol; window *= 64) {
    std::vector<double> near;
    for (double x : xs) {
      if (std::abs(x - median) <= window) near.push_back(x);
    }
    if (near.size() > xs.size() / 4) break;  // too dense around the median
    std::sort(near.begin(), near.end());
    double best = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t i = 0; i + 1 < near.size(); ++i) {
      if (near[i + 1] - near[i] > tol &&
          !(std::abs(near[i + 1] - median) >= std::abs(best - median))) {
        best = near[i + 1];
      }
    }
    if (!std::isnan(best)) return best;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

bool ConstrainedTriangulation::insertAsTwoHalves(std::vector<VertexId>& order) {
  const double split = splitValue(order);
  if (std::isnan(split)) return false;
  std::vector<VertexId> leftOrder, rightOrder;
  leftOrder.reserve(order.size() / 2 + 1);
  rightOrder.reserve(order.size() / 2 + 1);
  double leftMax = -INFINITY, rightMin = INFINITY;
  for (VertexId v : order) {
    const double x = xy[v].x;
    if (x < split) {
      leftOrder.push_back(v);
      leftMax = std::max(leftMax, x);
    } else {
      rightOrder.push_back(v);
      rightMin = std::min(rightMin, x);
    }
  }
  std::size_t ib = 0, ic = 0;
  if (leftOrder.size() < order.size() / 8 || rightOrder.size() < order.size() / 8 ||
      !findFirstTriangle(leftOrder, ib, ic) || !findFirstTriangle(rightOrder, ib, ic)) {
    return false;
  }
  std::vector<VertexId>().swap(order);

  // The right half in a triangulation of its own, its vertices numbered in input
  // order (so that merge ties still go to the earlier input).
  IdVector<VertexId, VertexId> localOf(xy.size(), VertexId::invalid());  // global → right
  for (VertexId v : rightOrder) localOf[v] = VertexId(0);
  IdVector<VertexId, VertexId> rightGlobal;  // right → global
  rightGlobal.reserve(rightOrder.size());
  for (std::uint32_t k = 0; k < localOf.size(); ++k) {
    const VertexId g(k);
    if (!localOf[g].valid()) continue;
    localOf[g] = rightGlobal.endId();
    rightGlobal.push_back(g);
  }
  for (VertexId& v : rightOrder) v = localOf[v];
  // Segments with both ends on one side go in with that half (a segment
  // lies on the side of its ends); the rest after the merge.
  std::vector<std::uint32_t> leftSegments, rightSegments, seamSegments;
  for (auto k = static_cast<std::uint32_t>(segmentsDone); k < segments.size(); ++k) {
    const bool leftA = xy[segments[k].a].x < split, leftB = xy[segments[k].b].x < split;
    (leftA && leftB ? leftSegments : !leftA && !leftB ? rightSegments : seamSegments).push_back(k);
  }
  std::vector<Segment> rightSegmentList;
  rightSegmentList.reserve(rightSegments.size());
  for (std::uint32_t k : rightSegments) {
    Segment sg = segments[k];
    sg.a = localOf[sg.a];
    sg.b = localOf[sg.b];
    rightSegmentList.push_back(sg);
  }
  std::vector<VertexId>().swap(localOf);
  std::vector<Point2> rightXy(rightGlobal.size());
  std::vector<double> rightZ(rightGlobal.size());
  std::vector<FeatureId> rightFeature(rightGlobal.size());
  for (std::uint32_t j = 0; j < rightGlobal.size(); ++j) {
    const VertexId g = rightGlobal[VertexId(j)];
    rightXy[j] = xy[g];
    rightZ[j] = z[g];
    rightFeature[j] = vfeat[g];
  }
  ConstrainedTriangulation right(options.snapTolerance, rerouteDepthLimit, features,
                                 std::move(rightXy), std::move(rightZ), std::move(rightFeature),
                                 std::move(rightSegmentList));
  right.insertedUpTo = rightGlobal.size();  // inserted below, in rightOrder
  right.reserveTriangles(trianglesFor(rightOrder.size(), rightSegments.size()));
  right.edgeFeatures.reserve(rightSegments.size());

  // Each half is triangulated and classified on its own thread.
  // The left half on the calling thread; with one thread, left then right.
  // An exception of the left half wins over one of the right.
  IdVector<TriangleId, std::uint8_t> unsafeLeft, unsafeRight;
  parallelParts(2, 2, threadCount(), [&](std::size_t, std::size_t, unsigned half) {
    if (half == 0) {
      insertInOrder(leftOrder);
      insertSegments(leftSegments);
      unsafeLeft = unsafeTriangles(true, leftMax, rightMin);
    } else {
      right.insertInOrder(rightOrder);
      right.insertPendingSegments();
      unsafeRight = right.unsafeTriangles(false, leftMax, rightMin);
    }
  });
  std::vector<VertexId>().swap(leftOrder);
  std::vector<VertexId>().swap(rightOrder);

  // The right half's vertices (its crossings get new global ids), merges,
  // crossings and constrained edges, in global ids.
  for (std::uint32_t j = static_cast<std::uint32_t>(rightGlobal.size()); j < right.xy.size(); ++j) {
    rightGlobal.push_back(xy.endId());
    xy.push_back(right.xy[VertexId(j)]);
    z.push_back(0);
    vfeat.push_back(kNoFeature);
    rep.push_back(VertexId::invalid());
  }
  insertedUpTo = xy.size();
  for (std::uint32_t k = 0; k < rightGlobal.size(); ++k) {
    const VertexId j(k), g = rightGlobal[j];
    rep[g] = rightGlobal[right.rep[j]];
    z[g] = right.z[j];
    vfeat[g] = right.vfeat[j];
  }
  for (const auto& [keep, from] : right.zSource) {
    zSource[rightGlobal[VertexId(keep)].value] = rightGlobal[from];
  }
  for (CdtReport::Merge mg : right.report.merges) {
    mg.kept = rightGlobal[mg.kept];
    mg.merged = rightGlobal[mg.merged];
    report.merges.push_back(mg);
  }
  for (CdtReport::Intersection ev : right.report.intersections) {
    ev.vertex = rightGlobal[ev.vertex];
    report.intersections.push_back(ev);
  }
  deepestReroute = std::max(deepestReroute, right.deepestReroute);
  for (std::size_t k = 0; k < kCrossingSteps; ++k) crossingSteps[k] += right.crossingSteps[k];
  if (bend.size() < right.bend.size()) bend.resize(right.bend.size(), 0.0);
  for (std::size_t g = 0; g < right.bend.size(); ++g) bend[g] += right.bend[g];
  report.dropped.insert(report.dropped.end(), right.report.dropped.begin(),
                        right.report.dropped.end());
  right.edgeFeatures.forEach([&](std::uint64_t key, EdgeFeatureMap::View fs) {
    const auto [u, w] = edgeOfKey(key);
    const std::uint64_t global = edgeKey(rightGlobal[u], rightGlobal[w]);
    for (FeatureId f : fs) edgeFeatures.add(global, f);
  });
  // Only the right half's triangles are needed from here on.
  std::vector<Point2>().swap(right.xy);
  std::vector<double>().swap(right.z);
  std::vector<FeatureId>().swap(right.vfeat);
  std::vector<VertexId>().swap(right.rep);
  std::vector<HalfedgeId>().swap(right.vhe);
  right.edgeFeatures = EdgeFeatureMap();
  right.report = CdtReport();

  mergeHalves(right, rightGlobal, unsafeLeft, unsafeRight);
  // Vertex half-edges are recomputed when next needed.
  trackVhe = false;
  insertSegments(seamSegments);
  segmentsDone = segments.size();
  return true;
}

namespace {

/// The seam between the two halves: the set S of the unsafe triangles'
/// corners (global ids, ascending — input order), the border edges of the
/// hole they leave, and the constrained edges inside the hole.
struct Seam {
  IdVector<VertexId, VertexId> global;                // seam vertex → global vertex
  std::unordered_map<std::uint32_t, VertexId> local;  // global vertex (value) → seam vertex
  std::vector<SeamBorder> borders;
  std::vector<std::pair<VertexId, VertexId>> inner;  // global ids
  [[nodiscard]] VertexId vertex(VertexId g) { return local[g.value]; }
};

/// Part 1 of the merge. The seam of the two halves, from the unsafe
/// triangles of each (`left` in global ids; `right` in local ids, which
/// rightGlobal maps). Borders and inner edges come in triangle order, the
/// left half's first. Changes nothing.
Seam collectSeam(const TriangleStore& left, const TriangleStore& right,
                 const IdVector<VertexId, VertexId>& rightGlobal,
                 const IdVector<TriangleId, std::uint8_t>& unsafeLeft,
                 const IdVector<TriangleId, std::uint8_t>& unsafeRight) {
  Seam seam;
  auto collect = [&](const TriangleStore& half, const IdVector<TriangleId, std::uint8_t>& unsafe,
                     bool rightHalf) {
    auto global = [&](VertexId v) { return rightHalf && v != kInfinite ? rightGlobal[v] : v; };
    for (std::uint32_t k = 0; k < unsafe.size(); ++k) {
      const TriangleId t(k);
      if (!unsafe[t]) continue;
      for (std::uint32_t i = 0; i < 3; ++i) {
        const HalfedgeId h = halfedgeOf(t, i), g = half.twin(h);
        if (half.origin(h) == kInfinite) continue;
        const VertexId v = global(half.origin(h));
        if (seam.local.try_emplace(v.value, VertexId(0)).second) seam.global.push_back(v);
        const VertexId w = global(half.origin(nxt(h)));
        if (!unsafe[triangleOf(g)]) {
          seam.borders.push_back({v, w, g, rightHalf});
        } else if (half.cons[h] && h < g) {
          seam.inner.emplace_back(v, w);
        }
      }
    }
  };
  collect(left, unsafeLeft, false);
  collect(right, unsafeRight, true);
  std::sort(seam.global.begin(), seam.global.end());
  for (std::uint32_t j = 0; j < seam.global.size(); ++j) {
    seam.local[seam.global[VertexId(j)].value] = VertexId(j);
  }
  return seam;
}

/// The triangles that fill the hole between the halves' safe triangles:
/// DT(S) in seam ids, which of its triangles lie in the hole, and per border
/// edge (in Seam::borders' order) its half-edge in DT(S), the hole on its left.
struct HoleFill {
  ConstrainedTriangulation dt;
  IdVector<TriangleId, std::uint8_t> inHole;
  std::vector<HalfedgeId> borderHalfedge;
};

/// Part 2 of the merge. DT(S), with the border edges (feature 0) and the
/// constrained edges in the hole (feature 1) as constraints, on `xy` (the
/// global points); the hole is what is reachable from the border without
/// crossing it (with no border, no safe triangle at all: everything).
/// Throws internalError when DT(S) had to change its input (merge, split or
/// drop), lacks a border edge, or the border does not close the hole.
HoleFill fillHole(Seam& seam, const IdVector<VertexId, Point2>& xy) {
  std::vector<Point2> seamXy;
  seamXy.reserve(seam.global.size());
  for (VertexId g : seam.global) seamXy.push_back(xy[g]);
  std::vector<Segment> segments;
  segments.reserve(seam.borders.size() + seam.inner.size());
  for (const SeamBorder& b : seam.borders) {
    segments.push_back({seam.vertex(b.u), seam.vertex(b.v), 0});
  }
  for (const auto& [u, w] : seam.inner) segments.push_back({seam.vertex(u), seam.vertex(w), 1});
  HoleFill fill{ConstrainedTriangulation(
                    0.0, kRerouteDepthLimit,
                    {{FeatureKind::Other, "seam border"}, {FeatureKind::Other, "constraint"}},
                    std::move(seamXy), std::vector<double>(seam.global.size(), 0.0),
                    std::vector<FeatureId>(seam.global.size(), kNoFeature), std::move(segments)),
                {},
                {}};
  ConstrainedTriangulation& dt = fill.dt;
  dt.insertPendingPoints();
  dt.insertPendingSegments();
  if (!dt.report.merges.empty() || !dt.report.intersections.empty() || !dt.report.dropped.empty() ||
      !dt.bend.empty()) {
    throw internalError("the seam between the two halves changed its input");
  }

  IdVector<TriangleId, std::uint8_t>& inHole = fill.inHole;
  inHole.assign(dt.triCount(), seam.borders.empty() ? 1 : 0);
  fill.borderHalfedge.resize(seam.borders.size());
  std::vector<TriangleId> todo;
  for (std::size_t k = 0; k < seam.borders.size(); ++k) {
    const HalfedgeId h =
        dt.findHalfedge(seam.vertex(seam.borders[k].u), seam.vertex(seam.borders[k].v));
    if (!h.valid()) throw internalError("a seam border edge is missing");
    fill.borderHalfedge[k] = h;
    if (!inHole[triangleOf(h)]) {
      inHole[triangleOf(h)] = 1;
      todo.push_back(triangleOf(h));
    }
  }
  while (!todo.empty()) {
    const TriangleId t = todo.back();
    todo.pop_back();
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId h = halfedgeOf(t, i);
      if (dt.cons[h]) {
        const auto fs = dt.edgeFeatures.find(edgeKey(dt.origin(h), dt.origin(nxt(h))));
        if (std::find(fs.begin(), fs.end(), FeatureId{0}) != fs.end()) continue;  // border
      }
      const TriangleId n = dt.neighbour(h);
      if (!inHole[n]) {
        inHole[n] = 1;
        todo.push_back(n);
      }
    }
  }
  for (HalfedgeId h : fill.borderHalfedge) {
    if (inHole[dt.neighbour(h)]) throw internalError("the seam hole is not closed");
  }
  return fill;
}

/// Moves the last triangles of `store` into its free slots freeSlots[from..]
/// (ascending; a free slot has an invalid first corner) and drops the free
/// slots left at the end, so that the triangles are contiguous again.
void closeFreeSlots(TriangleStore& store, const std::vector<TriangleId>& freeSlots,
                    std::size_t from) {
  auto isFree = [&](TriangleId t) { return !store.corner(t, 0).valid(); };
  std::uint32_t end = store.triCount();
  for (std::size_t k = from; k < freeSlots.size(); ++k) {
    const TriangleId f = freeSlots[k];
    while (end > 0 && isFree(TriangleId(end - 1))) --end;
    if (f.value >= end) break;
    const TriangleId t(--end);
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId to = halfedgeOf(f, i), moved = halfedgeOf(t, i);
      store.tv[to.value] = store.tv[moved.value];
      store.cons[to] = store.cons[moved];
      store.link(to, store.twin(moved));
    }
    store.tv[halfedgeOf(t, 0).value] = VertexId::kInvalid;
  }
  while (end > 0 && isFree(TriangleId(end - 1))) --end;
  store.tv.resize(3 * static_cast<std::size_t>(end));
  store.opp.resize(3 * static_cast<std::size_t>(end));
  store.cons.resize(3 * static_cast<std::size_t>(end));
}

/// Part 3 of the merge. The left half's unsafe triangles make way for the
/// right half's safe ones and the hole's (fill): both are copied into
/// `left`, into the freed slots first, then appended, their ids made global
/// (the hole's edges constrained where `left.edgeFeatures` has the edge),
/// linked to the safe triangles along the border, and the slots left free
/// are closed. Frees the triangle arrays of `right` and `fill.dt` as it
/// copies them. Throws internalError when a copied triangle is left without
/// a twin.
void stitch(ConstrainedTriangulation& left, ConstrainedTriangulation& right,
            const IdVector<VertexId, VertexId>& rightGlobal,
            const IdVector<TriangleId, std::uint8_t>& unsafeLeft,
            const IdVector<TriangleId, std::uint8_t>& unsafeRight, const Seam& seam,
            HoleFill& fill) {
  // New slots: freed left slots first, then appended. A freed slot is marked
  // by an invalid first corner.
  std::vector<TriangleId> freeSlots;
  for (std::uint32_t k = 0; k < unsafeLeft.size(); ++k) {
    const TriangleId t(k);
    if (unsafeLeft[t]) {
      freeSlots.push_back(t);
      left.tv[halfedgeOf(t, 0).value] = VertexId::kInvalid;
    }
  }
  std::size_t used = 0;
  std::uint32_t appended = left.triCount();
  auto takeSlot = [&] {
    return used < freeSlots.size() ? freeSlots[used++] : TriangleId(appended++);
  };
  IdVector<TriangleId, TriangleId> rightSlot(right.triCount(), TriangleId::invalid());
  for (std::uint32_t k = 0; k < right.triCount(); ++k) {
    if (!unsafeRight[TriangleId(k)]) rightSlot[TriangleId(k)] = takeSlot();
  }
  IdVector<TriangleId, TriangleId> holeSlot(fill.dt.triCount(), TriangleId::invalid());
  for (std::uint32_t k = 0; k < fill.dt.triCount(); ++k) {
    if (fill.inHole[TriangleId(k)]) holeSlot[TriangleId(k)] = takeSlot();
  }
  // Copies the kept triangles of another triangulation array by array, freeing each
  // source array once copied (two full copies of the right half's arrays
  // never coexist); twins outside the kept set are linked through the
  // borders below. The raw arrays are copied as such, ids translated.
  const std::size_t size = 3 * static_cast<std::size_t>(appended);
  auto copyKept = [&](ConstrainedTriangulation& from, const IdVector<TriangleId, TriangleId>& slot,
                      const IdVector<VertexId, VertexId>& global) {
    auto each = [&](const auto& f) {
      parallelParts(
          slot.size(), left.threadCount(), left.threadCount(),
          [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t k = b; k < e; ++k) {
              const TriangleId t(static_cast<std::uint32_t>(k));
              if (!slot[t].valid()) continue;
              for (std::uint32_t i = 0; i < 3; ++i) f(halfedgeOf(t, i), halfedgeOf(slot[t], i));
            }
          },
          kSerialBelow);
    };
    left.tv.resize(size);
    each([&](HalfedgeId h, HalfedgeId out) {
      const VertexId v = from.origin(h);
      left.tv[out.value] = (v == kInfinite ? kInfinite : global[v]).value;
    });
    std::vector<std::uint32_t>().swap(from.tv);
    left.opp.resize(size);
    each([&](HalfedgeId h, HalfedgeId out) {
      const HalfedgeId g = from.twin(h);
      const TriangleId s = slot[triangleOf(g)];
      left.opp[out.value] = s.valid() ? halfedgeOf(s, cornerOf(g)).value : HalfedgeId::kInvalid;
    });
    std::vector<std::uint32_t>().swap(from.opp);
    left.cons.resize(size);
    each([&](HalfedgeId h, HalfedgeId out) { left.cons[out] = from.cons[h]; });
    std::vector<std::uint8_t>().swap(from.cons);
  };
  copyKept(right, rightSlot, rightGlobal);
  copyKept(fill.dt, holeSlot, seam.global);
  // DT(S)'s constraints include the hole's border: take the flags from the
  // real constrained edges instead.
  for (const TriangleId t : holeSlot) {
    if (!t.valid()) continue;
    for (std::uint32_t i = 0; i < 3; ++i) {
      const VertexId u = left.corner(t, i), w = left.corner(t, (i + 1) % 3);
      left.cons[halfedgeOf(t, i)] =
          u != kInfinite && w != kInfinite && !left.edgeFeatures.find(edgeKey(u, w)).empty();
    }
  }
  for (std::size_t k = 0; k < seam.borders.size(); ++k) {
    const SeamBorder& b = seam.borders[k];
    const HalfedgeId h = fill.borderHalfedge[k];
    const HalfedgeId safe =
        b.rightHalf ? halfedgeOf(rightSlot[triangleOf(b.safe)], cornerOf(b.safe)) : b.safe;
    left.link(safe, halfedgeOf(holeSlot[triangleOf(h)], cornerOf(h)));
  }
  for (const TriangleId t : holeSlot) {
    if (!t.valid()) continue;
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId h = halfedgeOf(t, i);
      if (left.opp[h.value] >= left.opp.size() || left.twin(left.twin(h)) != h) {
        throw internalError("merging the two halves left a broken triangle");
      }
    }
  }
  closeFreeSlots(left, freeSlots, used);
}

}  // namespace

void ConstrainedTriangulation::mergeHalves(ConstrainedTriangulation& right,
                                           const IdVector<VertexId, VertexId>& rightGlobal,
                                           const IdVector<TriangleId, std::uint8_t>& unsafeLeft,
                                           const IdVector<TriangleId, std::uint8_t>& unsafeRight) {
  Seam seam = collectSeam(*this, right, rightGlobal, unsafeLeft, unsafeRight);
  HoleFill fill = fillHole(seam, xy);
  stitch(*this, right, rightGlobal, unsafeLeft, unsafeRight, seam, fill);
  lastTriangle = TriangleId(0);
}

}  // namespace tinsmith::cdt
