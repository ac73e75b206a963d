// Point insertion (see point_insertion.hpp): input checks, the first
// triangle, the insertion order and the insertion loop.
#include "core/cdt/point_insertion.hpp"

#include <bit>
#include <cmath>
#include <string>

#include "core/base/error.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::cdt {

void Triangulation::checkPoint(const Point3& p, FeatureId feature, std::size_t id) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    SourceLocation where;
    if (feature != kNoFeature && feature < features.size()) {
      where.file = features[feature].source;
    }
    throw inputError("point " + std::to_string(id) + " has a non-finite coordinate (" +
                         std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                         std::to_string(p.z) + ")",
                     where, "remove NaN/infinite values from the input");
  }
  if (feature != kNoFeature && feature >= features.size()) {
    throw usageError("feature id " + std::to_string(feature) +
                     " was not registered with addFeature");
  }
  // The predicates are exact while their products neither overflow nor
  // underflow (predicates.hpp); this range keeps every case inside that.
  auto outOfRange = [](double c) {
    const double a = std::fabs(c);
    return a > 1e60 || (a != 0.0 && a < 1e-50);
  };
  if (outOfRange(p.x) || outOfRange(p.y)) {
    SourceLocation where;
    if (feature != kNoFeature) where.file = features[feature].source;
    throw inputError("point " + std::to_string(id) +
                         " has a coordinate outside the "
                         "supported range (0 or 1e-50 to 1e60 in magnitude)",
                     where, "check the coordinate units and CRS");
  }
  if (id >= kInfinite.value - 1) throw inputError("too many points (at most 2^32 - 3)");
}

VertexId Triangulation::appendPoints(std::span<const Point3> points, FeatureId feature) {
  const auto first = VertexId(static_cast<std::uint32_t>(xy.size()));
  for (std::size_t i = 0; i < points.size(); ++i) checkPoint(points[i], feature, xy.size() + i);
  // Grow geometrically: many small polylines must not reallocate each time.
  const std::size_t need = xy.size() + points.size();
  if (need > xy.capacity()) {
    const std::size_t cap = std::max(need, 2 * xy.capacity());
    xy.reserve(cap);
    z.reserve(cap);
    vfeat.reserve(cap);
    rep.reserve(cap);
  }
  for (const Point3& p : points) {
    xy.push_back(p.xy());
    z.push_back(p.z);
    vfeat.push_back(feature);
    rep.push_back(VertexId::invalid());
  }
  return first;
}

Location Triangulation::scan(const Point2& p) const {
  for (std::uint32_t k = 0; k < triCount(); ++k) {
    const TriangleId t(k);
    if (isGhost(t)) continue;
    bool inside = true;
    for (std::uint32_t i = 0; i < 3 && inside; ++i) {
      inside = orientP(corner(t, i), corner(t, (i + 1) % 3), p) >= 0;
    }
    if (inside) return classify(t, p);
  }
  for (std::uint32_t k = 0; k < triCount(); ++k) {
    const TriangleId t(k);
    if (!isGhost(t)) continue;
    const HalfedgeId e = ghostEdge(t);
    if (orientP(origin(e), origin(nxt(e)), p) > 0) return {LocKind::Outside, t, {}, {}};
  }
  throw internalError("point location failed: the point is in no triangle");
}

void Triangulation::merge(VertexId dup, VertexId keep) {
  rep[dup] = keep;
  CdtReport::Merge m;
  m.at = xy[keep];
  m.kept = keep;
  m.merged = dup;
  const int pd = priorityOf(features, vfeat[dup]), pk = priorityOf(features, vfeat[keep]);
  double droppedZ = z[dup];
  FeatureId droppedF = vfeat[dup];
  // Which input the kept z came from (ties go to the earlier input).
  auto src = zSource.find(keep.value);
  const VertexId from = src == zSource.end() ? keep : src->second;
  if (pd > pk || (pd == pk && dup < from)) {
    droppedZ = z[keep];
    droppedF = vfeat[keep];
    z[keep] = z[dup];
    vfeat[keep] = vfeat[dup];
    zSource[keep.value] = dup;
  }
  m.keptZ = z[keep];
  m.droppedZ = droppedZ;
  m.keptFeature = vfeat[keep];
  m.droppedFeature = droppedF;
  report.merges.push_back(m);
}

bool Triangulation::findFirstTriangle(const std::vector<VertexId>& order, std::size_t& ib,
                                      std::size_t& ic) const {
  const VertexId a = order[0];
  ib = kNoPosition;
  ic = kNoPosition;
  for (std::size_t i = 1; i < order.size(); ++i) {
    if (!(xy[order[i]] == xy[a])) {
      ib = i;
      break;
    }
  }
  if (ib == kNoPosition) return false;
  for (std::size_t i = ib + 1; i < order.size(); ++i) {
    if (orient(a, order[ib], order[i]) != 0) {
      ic = i;
      return true;
    }
  }
  return false;
}

void Triangulation::initialTriangle(const std::vector<VertexId>& order, std::size_t& usedA,
                                    std::size_t& usedB, std::size_t& usedC) {
  const VertexId a = order[0];
  std::size_t ib = kNoPosition, ic = kNoPosition;
  if (!findFirstTriangle(order, ib, ic)) {
    throw geometryError("the input has fewer than 3 non-collinear distinct points (" +
                            std::to_string(order.size()) + " points given)",
                        {}, "give at least three points that do not lie on one line");
  }
  VertexId b = order[ib], c = order[ic];
  if (orient(a, b, c) < 0) std::swap(b, c);
  usedA = 0;
  usedB = ib;
  usedC = ic;
  for (VertexId v : {a, b, c}) rep[v] = v;
  const TriangleId t = newTriangle(), g0 = newTriangle(), g1 = newTriangle(), g2 = newTriangle();
  setTri(g0, b, a, kInfinite);
  setTri(g1, c, b, kInfinite);
  setTri(g2, a, c, kInfinite);
  setTri(t, a, b, c);
  link(halfedgeOf(t, 0), halfedgeOf(g0, 0));
  link(halfedgeOf(t, 1), halfedgeOf(g1, 0));
  link(halfedgeOf(t, 2), halfedgeOf(g2, 0));
  link(halfedgeOf(g0, 1), halfedgeOf(g2, 2));
  link(halfedgeOf(g0, 2), halfedgeOf(g1, 1));
  link(halfedgeOf(g1, 2), halfedgeOf(g2, 1));
  lastTriangle = t;
}

std::vector<VertexId> Triangulation::insertionOrder() const {
  const std::size_t n = xy.size();
  if (insertedUpTo >= n) return {};
  const unsigned threads = threadCount();
  const std::size_t count = n - insertedUpTo;
  std::vector<Box> boxes(threads);
  parallelParts(count, threads, threads, [&](std::size_t b, std::size_t e, unsigned k) {
    for (std::size_t i = insertedUpTo + b; i < insertedUpTo + e; ++i) {
      const VertexId v(static_cast<std::uint32_t>(i));
      if (!rep[v].valid()) boxes[k].add(xy[v]);
    }
  }, kSerialBelow);
  Box box;
  for (const Box& bx : boxes) box.add(bx);
  // BRIO (biased randomized insertion order): point i goes to round k with
  // probability 2^-(k+1) (from a fixed hash of i, so deterministic); rounds
  // go in from the smallest, each in Hilbert order on a 2^13 grid over the
  // bounding box (ties keep input order). Random rounds keep the number of
  // flips per insertion near the random-order expectation; the Hilbert order
  // keeps walks short.
  const HilbertGrid hilbert(box);
  std::uint32_t rounds = 0;
  while (rounds < 20 && (std::size_t{1000} << rounds) < count) ++rounds;
  // Points already placed (merged during an earlier finalize) get the key
  // 0xffffffff: they sort last and are cut off.
  constexpr std::uint64_t kSkip = 0xffffffffull << 32;
  std::vector<std::uint64_t> keys(count);
  parallelParts(count, threads, threads, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t j = b; j < e; ++j) {
      const std::size_t i = insertedUpTo + j;
      const VertexId v(static_cast<std::uint32_t>(i));
      if (rep[v].valid()) {
        keys[j] = kSkip | i;
        continue;
      }
      std::uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 31;
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 29;
      const auto round = static_cast<std::uint32_t>(
          std::min<int>(std::countr_zero(h | (std::uint64_t{1} << 40)), static_cast<int>(rounds)));
      const std::uint32_t key = ((rounds - round) << 26) | hilbert(xy[v]);
      keys[j] = (static_cast<std::uint64_t>(key) << 32) | i;
    }
  }, kSerialBelow);
  radixSortHigh32(keys, threads);
  std::vector<VertexId> order;
  order.reserve(count);
  for (std::uint64_t k : keys) {
    if ((k & kSkip) == kSkip) break;
    order.emplace_back(static_cast<std::uint32_t>(k & 0xffffffffu));
  }
  return order;
}

void Triangulation::insertInOrder(const std::vector<VertexId>& order) {
  std::size_t skipA = kNoPosition, skipB = kNoPosition, skipC = kNoPosition;
  if (!triangulated()) initialTriangle(order, skipA, skipB, skipC);
  // The insertion order jumps around the input arrays: fetch ahead.
  constexpr std::size_t kAhead = 8;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i + kAhead < order.size()) {
      __builtin_prefetch(&xy[order[i + kAhead]]);
      __builtin_prefetch(&rep[order[i + kAhead]], 1);
    }
    if (i == skipA || i == skipB || i == skipC) continue;
    insertVertex(order[i]);
  }
}

}  // namespace tinsmith::cdt
