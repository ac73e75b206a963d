// Constraint insertion (see constraints.hpp): the pending input in its
// order, and each segment walked from its start, through the vertices on it,
// across the edges it crosses (swapped away, book 6.5), splitting at
// constraints it meets (crossing_resolution.cpp).
#include <deque>
#include <string>

#include "core/base/error.hpp"
#include "core/cdt/constraints.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::cdt {

ConstrainedTriangulation::ConstrainedTriangulation(double snapTolerance, std::size_t rerouteLimit,
                                                   std::vector<TinFeature> featureList,
                                                   std::vector<Point2> points,
                                                   std::vector<double> heights,
                                                   std::vector<FeatureId> vertexFeatures,
                                                   std::vector<Segment> segmentList)
    : segments(std::move(segmentList)), rerouteDepthLimit(rerouteLimit) {
  options.snapTolerance = snapTolerance;
  options.splitMinPoints = 0;
  features = std::move(featureList);
  xy = std::move(points);
  z = std::move(heights);
  vfeat = std::move(vertexFeatures);
  rep.assign(xy.size(), VertexId::invalid());
}

void ConstrainedTriangulation::insertPendingPoints() {
  if (insertedUpTo >= xy.size()) return;
  std::vector<VertexId> order = insertionOrder();
  trackVhe = false;
  insertedUpTo = xy.size();
  if (order.empty()) return;

  if (!triangulated()) {
    reserveTriangles(trianglesFor(order.size(), segments.size() - segmentsDone));
    edgeFeatures.reserve(segments.size() - segmentsDone);
    if (options.splitMinPoints > 0 && order.size() >= options.splitMinPoints &&
        insertAsTwoHalves(order)) {
      return;
    }
  }
  insertInOrder(order);
}

void ConstrainedTriangulation::insertPendingSegments() {
  if (segmentsDone >= segments.size()) return;
  std::vector<std::uint32_t> pending(segments.size() - segmentsDone);
  for (std::size_t k = 0; k < pending.size(); ++k) {
    pending[k] = static_cast<std::uint32_t>(segmentsDone + k);
  }
  insertSegments(pending);
  segmentsDone = segments.size();
}

void ConstrainedTriangulation::insertSegments(const std::vector<std::uint32_t>& which) {
  if (which.empty()) return;
  startTrackingVhe();
  std::vector<std::uint32_t> runStart;  // positions in `which`
  for (std::size_t k = 0; k < which.size(); ++k) {
    const bool continues =
        k > 0 && k - runStart.back() < 64 && segments[which[k]].a == segments[which[k - 1]].b;
    if (!continues) runStart.push_back(static_cast<std::uint32_t>(k));
  }
  auto midpoint = [&](std::uint32_t k) {
    const Point2 &p = xy[segments[which[k]].a], &q = xy[segments[which[k]].b];
    return Point2{0.5 * p.x + 0.5 * q.x, 0.5 * p.y + 0.5 * q.y};
  };
  Box box;
  for (const std::uint32_t k : runStart) box.add(midpoint(k));
  const HilbertGrid hilbert(box);
  std::vector<std::uint64_t> keys(runStart.size());
  for (std::size_t r = 0; r < runStart.size(); ++r) {
    keys[r] = (static_cast<std::uint64_t>(hilbert(midpoint(runStart[r]))) << 32) | r;
  }
  radixSortHigh32(keys, threadCount());
  for (const std::uint64_t key : keys) {
    const std::size_t r = key & 0xffffffffu;
    const std::size_t end = r + 1 < runStart.size() ? runStart[r + 1] : which.size();
    for (std::size_t k = runStart[r]; k < end; ++k) {
      const Segment sg = segments[which[k]];
      const VertexId a = find(sg.a), b = find(sg.b);
      if (a == b) {
        report.dropped.push_back({CdtReport::Dropped::What::ZeroLengthSegment, sg.feature, xy[a]});
        continue;
      }
      insertSegment(a, b, sg.feature);
    }
  }
}

void ConstrainedTriangulation::addEdgeFeature(VertexId p, VertexId q, FeatureId f) {
  const HalfedgeId h = findHalfedge(p, q);
  if (!h.valid()) throw internalError("constraint edge missing after insertion");
  cons[h] = cons[twin(h)] = 1;
  edgeFeatures.add(edgeKey(p, q), f);
}

bool ConstrainedTriangulation::onRay(VertexId a, VertexId b, VertexId c) const {
  const Point2 &pa = xy[a], &pb = xy[b], &pc = xy[c];
  if (pb.x > pa.x) return pc.x > pa.x;
  if (pb.x < pa.x) return pc.x < pa.x;
  return pb.y > pa.y ? pc.y > pa.y : pc.y < pa.y;
}

bool ConstrainedTriangulation::onInputSegment(VertexId a0, VertexId b0, VertexId cur, VertexId tgt,
                                              VertexId u,
                                              const std::vector<VertexId>& passed) const {
  if (u == kInfinite || u == cur || u == tgt || orient(a0, b0, u) != 0) return false;
  if (std::find(passed.begin(), passed.end(), u) != passed.end()) return false;
  const Point2 &pc = xy[cur], &pt = xy[tgt], &pu = xy[u];
  return (pu.x - pc.x) * (pt.x - pc.x) + (pu.y - pc.y) * (pt.y - pc.y) > 0 &&
         (pu.x - pt.x) * (pc.x - pt.x) + (pu.y - pt.y) * (pc.y - pt.y) > 0;
}

void ConstrainedTriangulation::insertSegment(VertexId a, VertexId b, FeatureId f) {
  const VertexId a0 = a, b0 = b;
  std::vector<VertexId> passed{a};  // vertices this segment already runs through
  std::vector<VertexId> targets{b};
  VertexId cur = a;
  const std::size_t guardLimit = 64 + 8 * xy.size();
  std::size_t guard = 0;
  std::vector<std::pair<VertexId, VertexId>> crossed;
  while (!targets.empty()) {
    if (++guard > guardLimit) {
      throw internalError("constraint insertion did not terminate");
    }
    const VertexId tgt = targets.back();
    if (cur == tgt) {
      targets.pop_back();
      continue;
    }
    // Find the wedge at cur that holds the direction to tgt.
    HalfedgeId firstCross;
    VertexId onLine;
    {
      const HalfedgeId start = vhe[cur];
      HalfedgeId h = start;
      std::size_t turns = 0;
      do {
        const VertexId u = origin(nxt(h)), w = origin(prv(h));
        if (u != kInfinite) {
          if (u == tgt) {
            onLine = u;
            break;
          }
          const int ou = orient(cur, tgt, u);
          if ((ou == 0 && onRay(cur, tgt, u)) || onInputSegment(a0, b0, cur, tgt, u, passed)) {
            onLine = u;
            break;
          }
          if (w != kInfinite && ou < 0 && orient(cur, tgt, w) > 0) {
            if (onInputSegment(a0, b0, cur, tgt, w, passed)) {
              onLine = w;
            } else {
              firstCross = nxt(h);  // u→w, u right of cur→tgt, w left
            }
            break;
          }
        }
        h = twin(prv(h));
      } while (h != start && ++turns < 1u << 30);
    }
    if (onLine.valid()) {
      addEdgeFeature(cur, onLine, f);
      cur = onLine;
      passed.push_back(cur);
      continue;
    }
    if (!firstCross.valid()) throw internalError("constraint direction found in no triangle");

    // Walk the crossed edges.
    crossed.clear();
    HalfedgeId e = firstCross;
    VertexId end, onInput;
    bool hitConstraint = false;
    for (;;) {
      if (cons[e]) {
        hitConstraint = true;
        break;
      }
      crossed.emplace_back(origin(e), origin(nxt(e)));
      const HalfedgeId g = twin(e);
      const VertexId x = origin(prv(g));
      if (x == kInfinite) throw internalError("constraint leaves the convex hull");
      if (x == tgt) {
        end = tgt;
        break;
      }
      const int ox = orient(cur, tgt, x);
      if (ox == 0) {
        end = x;
        break;
      }
      if (onInputSegment(a0, b0, cur, tgt, x, passed)) {
        onInput = x;  // route through it: walk cur→x on its own line
        break;
      }
      e = ox > 0 ? nxt(g) : prv(g);
    }
    if (onInput.valid()) {
      targets.push_back(onInput);
      continue;
    }
    if (hitConstraint) {
      const VertexId v = crossingVertex(cur, tgt, e, f);
      if (v.valid()) targets.push_back(v);
      continue;
    }
    removeCrossings(cur, end, crossed, f);
    cur = end;
    passed.push_back(cur);
  }
}

void ConstrainedTriangulation::removeCrossings(
    VertexId a, VertexId b, const std::vector<std::pair<VertexId, VertexId>>& crossed,
    FeatureId f) {
  std::deque<std::pair<VertexId, VertexId>> queue(crossed.begin(), crossed.end());
  std::vector<std::pair<VertexId, VertexId>> fresh;
  std::size_t guard = 0;
  const std::size_t limit = 64 + 16 * crossed.size() * crossed.size();
  while (!queue.empty()) {
    if (++guard > limit) throw internalError("constraint edge recovery did not terminate");
    const auto [p, q] = queue.front();
    queue.pop_front();
    const HalfedgeId h = findHalfedge(p, q);
    if (!h.valid()) throw internalError("crossing edge vanished");
    const VertexId c = origin(prv(h)), d = origin(prv(twin(h)));
    if (orient(c, d, p) * orient(c, d, q) >= 0) {  // not strictly convex
      queue.emplace_back(p, q);
      continue;
    }
    flip(h);
    const bool endC = c == a || c == b, endD = d == a || d == b;
    if (!endC && !endD && orient(a, b, c) * orient(a, b, d) < 0) {
      queue.emplace_back(c, d);
    } else {
      fresh.emplace_back(c, d);
    }
  }
  addEdgeFeature(a, b, f);  // constrained before the LOP so it is never flipped
  lop(fresh);
}

}  // namespace tinsmith::cdt
