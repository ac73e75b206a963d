// The CDT's triangle store (the data structure, as CGAL's
// Triangulation_data_structure_2 under its triangulations): triangles in flat
// arrays with their twins and constrained flags, the point of each vertex, and
// the operations that keep it a Delaunay triangulation — flips, splits at a new
// vertex, legalization (Lawson flips, book 4.2) and compaction into a Mesh.
// Internal to core/cdt.
//
// Triangle t owns half-edges 3t..3t+2; half-edge 3t+i runs from corner i to
// corner (i+1)%3 with the triangle on its left. The convex hull is closed by
// ghost triangles whose third corner is the vertex at infinity (kInf), so
// every half-edge has a twin. Flips and splits reuse triangle slots; nothing
// is deleted until compaction. The small operations on the insertion paths
// (inConflict, flip, legalize, the splits) are defined here, in the class, so
// that point location and insertion inline them.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/base/point.hpp"
#include "core/cdt/edge_feature_map.hpp"
#include "core/geometry/predicates.hpp"
#include "core/mesh/mesh.hpp"

namespace tinsmith::cdt {

/// No vertex, half-edge or triangle.
inline constexpr std::uint32_t kNone = 0xffffffffu;
/// The vertex at infinity, third corner of every ghost triangle.
inline constexpr std::uint32_t kInf = 0xfffffffeu;

/// The next and previous half-edge of the same triangle.
inline std::uint32_t nxt(std::uint32_t h) {
  return h % 3 == 2 ? h - 2 : h + 1;
}
inline std::uint32_t prv(std::uint32_t h) {
  return h % 3 == 0 ? h + 2 : h - 1;
}

class TriangleStore {
 public:
  // Vertex points, by vertex id (the CDT's input vertex ids).
  std::vector<Point2> xy;
  std::vector<std::uint32_t> vhe;  // an outgoing half-edge of each live vertex
  bool trackVhe = false;           // vhe is maintained only while constraints go in

  // Triangles.
  std::vector<std::uint32_t> tv;   // corners
  std::vector<std::uint32_t> opp;  // twin half-edge
  std::vector<std::uint8_t> cons;  // constrained flag per half-edge
  EdgeFeatureMap edgeFeatures;
  std::vector<std::uint32_t> stack;  // half-edges legalize() has still to check

  // After pack() the triangle arrays live in a Mesh (compacted); the triangles
  // left out (ghosts, outside the domain) are kept here with their slots so
  // that unpack() restores the arrays exactly.
  struct RemovedTriangle {
    std::uint32_t slot;
    std::uint32_t tv[3];
    std::uint32_t opp[3];
    std::uint8_t cons[3];
  };
  std::vector<RemovedTriangle> removed;
  bool packed = false;
  std::uint32_t packedTriangles = 0;

  [[nodiscard]] bool triangulated() const { return !tv.empty(); }
  [[nodiscard]] std::uint32_t triCount() const { return static_cast<std::uint32_t>(tv.size() / 3); }
  [[nodiscard]] bool isGhost(std::uint32_t t) const {
    return tv[3 * t] == kInf || tv[3 * t + 1] == kInf || tv[3 * t + 2] == kInf;
  }
  int orient(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    return geometry::orient2d(xy[a], xy[b], xy[c]);
  }
  int orientP(std::uint32_t a, std::uint32_t b, const Point2& p) const {
    return geometry::orient2d(xy[a], xy[b], p);
  }

  std::uint32_t newTriangle() {
    const auto t = triCount();
    for (int i = 0; i < 3; ++i) {
      tv.push_back(kNone);
      opp.push_back(kNone);
      cons.push_back(0);
    }
    return t;
  }
  void setTri(std::uint32_t t, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    tv[3 * t] = a;
    tv[3 * t + 1] = b;
    tv[3 * t + 2] = c;
    if (trackVhe) {
      if (a != kInf) vhe[a] = 3 * t;
      if (b != kInf) vhe[b] = 3 * t + 1;
      if (c != kInf) vhe[c] = 3 * t + 2;
    }
  }
  /// Recomputes vhe from the triangles and keeps it current from now on
  /// (bulk point insertion does not need it and skips the upkeep).
  void startTrackingVhe();
  void link(std::uint32_t h, std::uint32_t g) {
    opp[h] = g;
    opp[g] = h;
  }

  /// Is p in conflict with triangle t (inside its circumcircle, or for a ghost
  /// strictly outside its hull edge, or on the open hull edge)?
  inline bool inConflict(std::uint32_t t, const Point2& p) const {
    const std::uint32_t a = tv[3 * t], b = tv[3 * t + 1], c = tv[3 * t + 2];
    if (std::max(a, std::max(b, c)) < kInf) [[likely]] {
      return geometry::incircle(xy[a], xy[b], xy[c], p) > 0;
    }
    std::uint32_t u, v;
    if (a == kInf) {
      u = b, v = c;
    } else if (b == kInf) {
      u = c, v = a;
    } else if (c == kInf) {
      u = a, v = b;
    } else {
      return geometry::incircle(xy[a], xy[b], xy[c], p) > 0;
    }
    const int o = orientP(u, v, p);
    if (o != 0) return o > 0;
    const Point2 &pu = xy[u], &pv = xy[v];
    return std::min(pu.x, pv.x) <= p.x && p.x <= std::max(pu.x, pv.x) &&
           std::min(pu.y, pv.y) <= p.y && p.y <= std::max(pu.y, pv.y) && !(p == pu) && !(p == pv);
  }

  // --------------------------------------------------------------- flips
  /// Flips the edge of half-edge h (a→b in (a,b,c); twin in (b,a,d)) to c–d.
  /// Afterwards triangle h/3 = (c,a,d) and twin's triangle = (d,b,c).
  void flip(std::uint32_t h) {
    const std::uint32_t g = opp[h];
    const std::uint32_t t0 = h / 3, t1 = g / 3;
    const std::uint32_t a = tv[h], b = tv[nxt(h)], c = tv[prv(h)], d = tv[prv(g)];
    const std::uint32_t x1 = opp[nxt(h)], x2 = opp[prv(h)], x3 = opp[nxt(g)], x4 = opp[prv(g)];
    const std::uint8_t c1 = cons[nxt(h)], c2 = cons[prv(h)], c3 = cons[nxt(g)], c4 = cons[prv(g)];
    setTri(t0, c, a, d);
    setTri(t1, d, b, c);
    const std::uint32_t b0 = 3 * t0, b1 = 3 * t1;
    link(b0, x2);
    cons[b0] = c2;
    link(b0 + 1, x3);
    cons[b0 + 1] = c3;
    link(b0 + 2, b1 + 2);
    cons[b0 + 2] = 0;
    cons[b1 + 2] = 0;
    link(b1, x4);
    cons[b1] = c4;
    link(b1 + 1, x1);
    cons[b1 + 1] = c1;
  }

  /// Restores the (constrained) Delaunay property around vertex p after the
  /// half-edges on `stack` (each opposite p in its triangle) were created.
  void legalize(std::uint32_t p) {
    const Point2 pp = xy[p];
    while (!stack.empty()) {
      const std::uint32_t h = stack.back();
      stack.pop_back();
      if (cons[h]) continue;
      const std::uint32_t g = opp[h];
      if (!inConflict(g / 3, pp)) continue;
      flip(h);
      // p is corner 0 of triangle h/3 = (p,a,d) and corner 2 of (d,b,p).
      stack.push_back(3 * (h / 3) + 1);
      stack.push_back(3 * (g / 3));
    }
  }

  // -------------------------------------------------------------- splits
  /// Splits triangle t = (a,b,c) at new vertex p into (a,b,p), (b,c,p), (c,a,p).
  void splitTriangle(std::uint32_t t, std::uint32_t p) {
    const std::uint32_t a = tv[3 * t], b = tv[3 * t + 1], c = tv[3 * t + 2];
    const std::uint32_t o0 = opp[3 * t], o1 = opp[3 * t + 1], o2 = opp[3 * t + 2];
    const std::uint8_t c0 = cons[3 * t], c1 = cons[3 * t + 1], c2 = cons[3 * t + 2];
    const std::uint32_t n1 = newTriangle(), n2 = newTriangle();
    setTri(t, a, b, p);
    setTri(n1, b, c, p);
    setTri(n2, c, a, p);
    link(3 * t, o0);
    cons[3 * t] = c0;
    link(3 * n1, o1);
    cons[3 * n1] = c1;
    link(3 * n2, o2);
    cons[3 * n2] = c2;
    cons[3 * t + 1] = cons[3 * t + 2] = 0;  // the reused slot's inner edges are new
    link(3 * t + 1, 3 * n1 + 2);
    link(3 * t + 2, 3 * n2 + 1);
    link(3 * n1 + 1, 3 * n2 + 2);
    stack.clear();
    stack.push_back(3 * t);
    stack.push_back(3 * n1);
    stack.push_back(3 * n2);
    legalize(p);
  }

  /// Splits the edge of half-edge h (a→b in (a,b,c), twin in (b,a,d)) at new
  /// vertex p; a constrained edge stays constrained in both halves.
  void splitEdge(std::uint32_t h, std::uint32_t p) {
    const std::uint32_t g = opp[h];
    const std::uint32_t t0 = h / 3, t1 = g / 3;
    const std::uint32_t a = tv[h], b = tv[nxt(h)], c = tv[prv(h)], d = tv[prv(g)];
    const std::uint32_t xbc = opp[nxt(h)], xca = opp[prv(h)], xad = opp[nxt(g)], xdb = opp[prv(g)];
    const std::uint8_t cbc = cons[nxt(h)], cca = cons[prv(h)], cad = cons[nxt(g)],
                       cdb = cons[prv(g)];
    const std::uint8_t split = cons[h];
    const std::uint32_t n0 = newTriangle(), n1 = newTriangle();
    setTri(t0, c, a, p);
    setTri(n0, b, c, p);
    setTri(t1, d, b, p);
    setTri(n1, a, d, p);
    link(3 * t0, xca);
    cons[3 * t0] = cca;
    link(3 * n0, xbc);
    cons[3 * n0] = cbc;
    link(3 * t1, xdb);
    cons[3 * t1] = cdb;
    link(3 * n1, xad);
    cons[3 * n1] = cad;
    link(3 * t0 + 1, 3 * n1 + 2);  // a→p / p→a
    link(3 * t0 + 2, 3 * n0 + 1);  // p→c / c→p
    link(3 * n0 + 2, 3 * t1 + 1);  // p→b / b→p
    link(3 * t1 + 2, 3 * n1 + 1);  // p→d / d→p
    cons[3 * t0 + 2] = cons[3 * n0 + 1] = cons[3 * t1 + 2] = cons[3 * n1 + 1] = 0;
    cons[3 * t0 + 1] = cons[3 * n1 + 2] = cons[3 * n0 + 2] = cons[3 * t1 + 1] = split;
    if (split) {
      edgeFeatures.split(edgeKey(a, b), edgeKey(a, p), edgeKey(p, b));
    }
    stack.clear();
    stack.push_back(3 * t0);
    stack.push_back(3 * n0);
    stack.push_back(3 * t1);
    stack.push_back(3 * n1);
    legalize(p);
  }

  /// Half-edge p→q, or kNone if p and q are not adjacent.
  std::uint32_t findHalfedge(std::uint32_t p, std::uint32_t q) const {
    const std::uint32_t start = vhe[p];
    std::uint32_t h = start;
    do {
      if (tv[nxt(h)] == q) return h;
      h = opp[prv(h)];
    } while (h != start);
    return kNone;
  }

  /// Lawson's LOP (book 4.2) from the given edges (vertex pairs): flips every
  /// unconstrained edge that is not locally Delaunay, queueing the four edges
  /// around each flip. Consumes `todo`. Throws internalError if it runs away.
  void lop(std::vector<std::pair<std::uint32_t, std::uint32_t>>& todo);
  /// Runs the LOP on every edge of the triangles around v — needed after a
  /// forced split at a rounded intersection point, where v may lie off the
  /// split edge and edges at v itself can be non-Delaunay.
  void lopAround(std::uint32_t v);

  /// Triangles to reserve for a first bulk: 2 per point, plus room for
  /// constraint crossings (2 triangles each; up to 16 per segment, at most
  /// one per point) so that the arrays rarely grow: a doubling would briefly
  /// hold both copies, while capacity never used costs address space only
  /// (its pages are never touched).
  static std::size_t trianglesFor(std::size_t points, std::size_t segments) {
    return 2 * points + 4 + std::min(32 * segments, points);
  }
  void reserveTriangles(std::size_t triangles);

  // --------------------------------------------------------- compaction
  /// Moves the triangles flagged in `inside` (their order kept; at least one,
  /// none a ghost) into the returned storage, vertices renumbered in
  /// increasing id order; sets the rest aside for unpack(). Edge features
  /// below featureCount are carried over, ascending. vertexOf gets, per
  /// vertex, its mesh vertex (kNone if no kept triangle uses it). The store
  /// keeps its points but no triangles until unpack(); features and crs of
  /// the storage are left to the caller.
  MeshStorage pack(std::vector<std::uint8_t> inside, std::span<const double> z,
                   std::size_t featureCount, unsigned threads,
                   std::vector<std::uint32_t>& vertexOf);
  /// The inverse of pack(): takes back its corners and twins, with
  /// workingVertex[mesh vertex] = the vertex it came from. The triangle arrays
  /// become exactly what they were before pack().
  void unpack(std::vector<std::uint32_t>&& corners, std::vector<std::uint32_t>&& twins,
              const std::vector<std::uint32_t>& workingVertex);
};

}  // namespace tinsmith::cdt
