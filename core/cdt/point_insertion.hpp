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
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/triangle_store.hpp"

namespace tinsmith::cdt {

enum class LocKind { InTriangle, OnEdge, OnVertex, Outside };
struct Location {
  LocKind kind;
  std::uint32_t t;  // triangle (InTriangle, Outside: the ghost)
  std::uint32_t h;  // half-edge (OnEdge), in a finite triangle
  std::uint32_t v;  // vertex (OnVertex)
};

/// A Delaunay triangulation of input vertices, numbered from 0 in input
/// order (their points in the store's xy). A vertex is pending until inserted,
/// then live or merged into a live one (rep).
class Triangulation : public TriangleStore {
 public:
  CdtOptions options;
  std::vector<TinFeature> features;

  // Input vertices beside xy (constraint crossings are appended).
  std::vector<double> z;
  std::vector<FeatureId> vfeat;
  std::vector<std::uint32_t> rep;  // kNone while pending; self if a vertex; else merged into
  std::size_t insertedUpTo = 0;    // vertices below this are placed (live or merged)

  CdtReport report;
  std::unordered_map<std::uint32_t, std::uint32_t> zSource;  // vertex → input its z came from

  std::uint32_t lastTriangle = 0;  // where the next walk starts
  std::uint32_t rng = 2463534242u;
  // Scratch of nearVertex(): triangles to visit, those visited, and a mark
  // per triangle (grown with the triangles; set only while nearVertex() runs,
  // which clears it again).
  std::vector<std::uint32_t> nearTodo, nearSeen;
  std::vector<std::uint8_t> nearMark;

  Triangulation() = default;
  explicit Triangulation(CdtOptions opts) : options(std::move(opts)) {}

  // ------------------------------------------------------------- input
  /// Throws what Cdt::insertPoint documents unless p can become input vertex
  /// `id` of `feature`.
  void checkPoint(const Point3& p, FeatureId feature, std::size_t id) const;
  /// Appends points as pending input vertices, all or none: every one is
  /// checked before the first goes in. Returns the id of the first.
  VertexId appendPoints(std::span<const Point3> points, FeatureId feature);

  [[nodiscard]] unsigned threadCount() const {
    if (options.threads != 0) return options.threads;
    return std::max(1u, std::thread::hardware_concurrency());
  }
  std::uint32_t nextRandom() {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
  }
  static int priorityOf(const std::vector<TinFeature>& fs, FeatureId f) {
    return f == kNoFeature || f >= fs.size() ? -1 : constraintPriority(fs[f].kind);
  }
  std::uint32_t find(std::uint32_t v) {
    std::uint32_t r = v;
    while (rep[r] != r) r = rep[r];
    while (rep[v] != r) {
      const std::uint32_t n = rep[v];
      rep[v] = r;
      v = n;
    }
    return r;
  }

  // ------------------------------------------------------------ location
  Location classify(std::uint32_t t, const Point2& p) const {
    const std::uint32_t base = 3 * t;
    int o[3];
    for (int i = 0; i < 3; ++i) o[i] = orientP(tv[base + i], tv[base + (i + 1) % 3], p);
    const int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
    if (zeros == 0) return {LocKind::InTriangle, t, kNone, kNone};
    if (zeros == 1) {
      for (std::uint32_t i = 0; i < 3; ++i) {
        if (o[i] == 0) return {LocKind::OnEdge, t, base + i, kNone};
      }
    }
    // Two zeros: p is the corner shared by those edges.
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (o[i] == 0 && o[(i + 2) % 3] == 0) return {LocKind::OnVertex, t, kNone, tv[base + i]};
    }
    return {LocKind::OnVertex, t, kNone, tv[base]};
  }

  /// The finite edge u→v of ghost triangle t.
  std::uint32_t ghostEdge(std::uint32_t t) const {
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (tv[3 * t + i] != kInf && tv[3 * t + (i + 1) % 3] != kInf) return 3 * t + i;
    }
    return kNone;
  }

  /// Visibility walk from triangle `start` (stochastic edge order from a fixed
  /// seed — deterministic and it cannot cycle for ever); falls back to a scan
  /// of all triangles after too many steps.
  Location locate(const Point2& p, std::uint32_t start) {
    std::uint32_t t = start;
    std::uint32_t from = kNone;  // half-edge we entered through
    const std::size_t limit = 4 * static_cast<std::size_t>(triCount()) + 64;
    for (std::size_t steps = 0; steps < limit; ++steps) {
      if (isGhost(t)) {
        const std::uint32_t e = ghostEdge(t);
        if (orientP(tv[e], tv[nxt(e)], p) > 0) return {LocKind::Outside, t, kNone, kNone};
        from = opp[e];
        t = from / 3;
        continue;
      }
      const std::uint32_t r = nextRandom() % 3;
      bool moved = false;
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t h = 3 * t + (r + k) % 3;
        if (h == from) continue;
        if (orientP(tv[h], tv[nxt(h)], p) < 0) {
          from = opp[h];
          t = from / 3;
          if (isGhost(t)) return {LocKind::Outside, t, kNone, kNone};
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
  void merge(std::uint32_t dup, std::uint32_t keep);

  /// A live vertex within snapTolerance of p near location `loc`, or kNone.
  /// Looks at the vertices of every triangle in conflict with p reachable from
  /// the located one (p's Delaunay neighbours-to-be, which contain its nearest
  /// vertex).
  std::uint32_t nearVertex(const Point2& p, const Location& loc) {
    const double tol = options.snapTolerance;
    if (!(tol > 0)) return kNone;
    nearTodo.assign({loc.t});
    if (loc.kind == LocKind::OnEdge) nearTodo.push_back(opp[loc.h] / 3);
    nearSeen.clear();
    if (nearMark.size() < triCount()) {
      nearMark.resize(std::max<std::size_t>(triCount(), 2 * nearMark.size()), 0);
    }
    std::uint32_t best = kNone;
    double bestD = tol * tol;
    while (!nearTodo.empty() && nearSeen.size() < 4096) {
      const std::uint32_t t = nearTodo.back();
      nearTodo.pop_back();
      if (nearMark[t]) continue;
      nearMark[t] = 1;
      nearSeen.push_back(t);
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t v = tv[3 * t + i];
        if (v == kInf) continue;
        const double dx = xy[v].x - p.x, dy = xy[v].y - p.y;
        const double d = dx * dx + dy * dy;
        if (d <= bestD && (best == kNone || d < bestD || v < best)) {
          best = v;
          bestD = d;
        }
        const std::uint32_t n = opp[3 * t + i] / 3;
        if (!nearMark[n] && inConflict(n, p)) nearTodo.push_back(n);
      }
    }
    for (const std::uint32_t t : nearSeen) nearMark[t] = 0;
    return best;
  }

  /// Inserts input vertex v (rep[v] == kNone) into the triangulation.
  void insertVertex(std::uint32_t v) {
    const Point2 p = xy[v];
    const Location loc = locate(p, lastTriangle);
    if (loc.kind == LocKind::OnVertex) {
      merge(v, loc.v);
      lastTriangle = loc.t;
      return;
    }
    const std::uint32_t nearV = nearVertex(p, loc);
    if (nearV != kNone) {
      merge(v, nearV);
      lastTriangle = loc.t;
      return;
    }
    rep[v] = v;
    // After the flips, the split triangle's slot still touches v's
    // neighbourhood: a good start for the next walk.
    if (loc.kind == LocKind::OnEdge) {
      lastTriangle = loc.h / 3;
      splitEdge(loc.h, v);
    } else {
      lastTriangle = loc.t;
      splitTriangle(loc.t, v);
    }
  }

  /// Positions ib, ic in `order` such that order[0], order[ib], order[ic] are
  /// distinct and not collinear; false when every point of `order` lies on
  /// one line.
  bool findFirstTriangle(const std::vector<std::uint32_t>& order, std::size_t& ib,
                         std::size_t& ic) const;

  /// Builds the first triangle from pending vertices in `order`; returns the
  /// three used, or throws when all pending points are collinear.
  void initialTriangle(const std::vector<std::uint32_t>& order, std::size_t& usedA,
                       std::size_t& usedB, std::size_t& usedC);

  /// The pending vertices in insertion order, the ones placed already (merged
  /// during an earlier finalize) left out. BRIO (biased randomized insertion
  /// order): vertex i goes to round k with probability 2^-(k+1), from a fixed
  /// hash of i; rounds go in from the smallest, each in Hilbert order over the
  /// bounding box. Deterministic for any thread count. Changes nothing.
  [[nodiscard]] std::vector<std::uint32_t> insertionOrder() const;
  /// Inserts the pending vertices `order` in that order (starting the
  /// triangulation with its first non-degenerate triple if there is none).
  void insertInOrder(const std::vector<std::uint32_t>& order);
};

}  // namespace tinsmith::cdt
