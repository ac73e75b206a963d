// Point insertion into the CDT (book 4.2): the input vertices with their
// heights and features, the insertion order (BRIO rounds in Hilbert order),
// point location by a visibility walk, and the merge of (near-)duplicates.
// Internal to core/cdt; constraints are the next layer (constraints.hpp).
//
// Location and insertion are defined in the class so that they inline the
// triangle store's flips and splits on the hottest path.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/triangle_store.hpp"

namespace tinsmith::cdt {

enum class LocKind { InTriangle, OnEdge, OnVertex, Outside };
struct Location {
  LocKind kind;
  TriangleId t;  // triangle (InTriangle, Outside: the ghost)
  HalfedgeId h;  // half-edge (OnEdge), in a finite triangle
  VertexId v;    // vertex (OnVertex)
};

/// No position in an insertion order.
inline constexpr std::size_t kNoPosition = ~std::size_t{0};

/// A Delaunay triangulation of input vertices, numbered from 0 in input
/// order (their points in the store's xy). A vertex is pending until inserted,
/// then live or merged into a live one (rep).
class Triangulation : public TriangleStore {
 public:
  CdtOptions options;
  std::vector<TinFeature> features;

  // Input vertices beside xy (constraint crossings are appended).
  IdVector<VertexId, double> z;
  IdVector<VertexId, FeatureId> vfeat;
  IdVector<VertexId, VertexId> rep;  // invalid while pending; self if a vertex; else merged into
  std::size_t insertedUpTo = 0;      // vertices below this are placed (live or merged)

  CdtReport report;
  // Vertex (its id's value) → the input its z came from.
  std::unordered_map<std::uint32_t, VertexId> zSource;

  TriangleId lastTriangle{0};  // where the next walk starts
  std::uint32_t rng = 2463534242u;
  // Scratch of nearVertex(): triangles to visit, those visited, and a mark
  // per triangle (grown with the triangles; set only while nearVertex() runs,
  // which clears it again).
  std::vector<TriangleId> nearTodo, nearSeen;
  IdVector<TriangleId, std::uint8_t> nearMark;

  Triangulation() = default;
  explicit Triangulation(CdtOptions opts) : options(std::move(opts)) {}

  // ------------------------------------------------------------- input
  /// Throws what Cdt::insertPoint documents unless p can become input vertex
  /// `id` of `feature`.
  void checkPoint(const Point3& p, FeatureId feature, std::size_t id) const;
  /// Appends points as pending input vertices, all or none: every one is
  /// checked before the first goes in. Returns the id of the first.
  VertexId appendPoints(std::span<const Point3> points, FeatureId feature);

  [[nodiscard]] unsigned threadCount() const { return resolveThreads(options.threads); }
  std::uint32_t nextRandom() {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
  }
  static int priorityOf(const std::vector<TinFeature>& fs, FeatureId f) {
    return f == kNoFeature || f >= fs.size() ? -1 : constraintPriority(fs[f].kind);
  }
  /// The live vertex that input vertex v is (v itself or the one it was
  /// merged into).
  VertexId find(VertexId v) {
    VertexId r = v;
    while (rep[r] != r) r = rep[r];
    while (rep[v] != r) {
      const VertexId n = rep[v];
      rep[v] = r;
      v = n;
    }
    return r;
  }

  // ------------------------------------------------------------ location
  Location classify(TriangleId t, const Point2& p) const {
    int o[3];
    for (std::uint32_t i = 0; i < 3; ++i) o[i] = orientP(corner(t, i), corner(t, (i + 1) % 3), p);
    const int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
    if (zeros == 0) return {LocKind::InTriangle, t, {}, {}};
    if (zeros == 1) {
      for (std::uint32_t i = 0; i < 3; ++i) {
        if (o[i] == 0) return {LocKind::OnEdge, t, halfedgeOf(t, i), {}};
      }
    }
    // Two zeros: p is the corner shared by those edges.
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (o[i] == 0 && o[(i + 2) % 3] == 0) return {LocKind::OnVertex, t, {}, corner(t, i)};
    }
    return {LocKind::OnVertex, t, {}, corner(t, 0)};
  }

  /// The finite edge u→v of ghost triangle t.
  HalfedgeId ghostEdge(TriangleId t) const {
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (corner(t, i) != kInfinite && corner(t, (i + 1) % 3) != kInfinite) return halfedgeOf(t, i);
    }
    return HalfedgeId::invalid();
  }

  /// Visibility walk from triangle `start` (stochastic edge order from a fixed
  /// seed — deterministic and it cannot cycle for ever); falls back to a scan
  /// of all triangles after too many steps.
  Location locate(const Point2& p, TriangleId start) {
    TriangleId t = start;
    HalfedgeId from;  // half-edge we entered through
    const std::size_t limit = 4 * static_cast<std::size_t>(triCount()) + 64;
    for (std::size_t steps = 0; steps < limit; ++steps) {
      if (isGhost(t)) {
        const HalfedgeId e = ghostEdge(t);
        if (orientP(origin(e), origin(nxt(e)), p) > 0) return {LocKind::Outside, t, {}, {}};
        from = twin(e);
        t = triangleOf(from);
        continue;
      }
      const std::uint32_t r = nextRandom() % 3;
      bool moved = false;
      for (std::uint32_t k = 0; k < 3; ++k) {
        const HalfedgeId h = halfedgeOf(t, (r + k) % 3);
        if (h == from) continue;
        if (orientP(origin(h), origin(nxt(h)), p) < 0) {
          from = twin(h);
          t = triangleOf(from);
          if (isGhost(t)) return {LocKind::Outside, t, {}, {}};
          moved = true;
          break;
        }
      }
      if (!moved) return classify(t, p);
    }
    return scan(p);
  }

  /// The exhaustive fallback of locate().
  Location scan(const Point2& p) const;

  // ----------------------------------------------------------- insertion
  /// Merges input vertex `dup` into live vertex `keep`, z by priority.
  void merge(VertexId dup, VertexId keep);

  /// A live vertex within snapTolerance of p near location `loc`, or invalid.
  /// Looks at the vertices of every triangle in conflict with p reachable from
  /// the located one (p's Delaunay neighbours-to-be, which contain its nearest
  /// vertex).
  VertexId nearVertex(const Point2& p, const Location& loc) {
    const double tol = options.snapTolerance;
    if (!(tol > 0)) return VertexId::invalid();
    nearTodo.assign({loc.t});
    if (loc.kind == LocKind::OnEdge) nearTodo.push_back(neighbour(loc.h));
    nearSeen.clear();
    if (nearMark.size() < triCount()) {
      nearMark.resize(std::max<std::size_t>(triCount(), 2 * nearMark.size()), 0);
    }
    VertexId best;
    double bestD = tol * tol;
    while (!nearTodo.empty() && nearSeen.size() < 4096) {
      const TriangleId t = nearTodo.back();
      nearTodo.pop_back();
      if (nearMark[t]) continue;
      nearMark[t] = 1;
      nearSeen.push_back(t);
      for (std::uint32_t i = 0; i < 3; ++i) {
        const VertexId v = corner(t, i);
        if (v == kInfinite) continue;
        const double dx = xy[v].x - p.x, dy = xy[v].y - p.y;
        const double d = dx * dx + dy * dy;
        if (d <= bestD && (!best.valid() || d < bestD || v < best)) {
          best = v;
          bestD = d;
        }
        const TriangleId n = neighbour(halfedgeOf(t, i));
        if (!nearMark[n] && inConflict(n, p)) nearTodo.push_back(n);
      }
    }
    for (const TriangleId t : nearSeen) nearMark[t] = 0;
    return best;
  }

  /// Inserts input vertex v (rep[v] invalid) into the triangulation.
  void insertVertex(VertexId v) {
    const Point2 p = xy[v];
    const Location loc = locate(p, lastTriangle);
    if (loc.kind == LocKind::OnVertex) {
      merge(v, loc.v);
      lastTriangle = loc.t;
      return;
    }
    const VertexId nearV = nearVertex(p, loc);
    if (nearV.valid()) {
      merge(v, nearV);
      lastTriangle = loc.t;
      return;
    }
    rep[v] = v;
    // After the flips, the split triangle's slot still touches v's
    // neighbourhood: a good start for the next walk.
    if (loc.kind == LocKind::OnEdge) {
      lastTriangle = triangleOf(loc.h);
      splitEdge(loc.h, v);
    } else {
      lastTriangle = loc.t;
      splitTriangle(loc.t, v);
    }
  }

  /// Positions ib, ic in `order` such that order[0], order[ib], order[ic] are
  /// distinct and not collinear; false when every point of `order` lies on
  /// one line.
  bool findFirstTriangle(const std::vector<VertexId>& order, std::size_t& ib,
                         std::size_t& ic) const;

  /// Builds the first triangle from pending vertices in `order`; returns the
  /// three used, or throws when all pending points are collinear.
  void initialTriangle(const std::vector<VertexId>& order, std::size_t& usedA, std::size_t& usedB,
                       std::size_t& usedC);

  /// The pending vertices in insertion order, the ones placed already (merged
  /// during an earlier finalize) left out. BRIO (biased randomized insertion
  /// order): vertex i goes to round k with probability 2^-(k+1), from a fixed
  /// hash of i; rounds go in from the smallest, each in Hilbert order over the
  /// bounding box. Deterministic for any thread count. Changes nothing.
  [[nodiscard]] std::vector<VertexId> insertionOrder() const;
  /// Inserts the pending vertices `order` in that order (starting the
  /// triangulation with its first non-degenerate triple if there is none).
  void insertInOrder(const std::vector<VertexId>& order);
};

}  // namespace tinsmith::cdt
