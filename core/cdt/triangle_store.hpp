// The CDT's triangle store (the data structure, as CGAL's
// Triangulation_data_structure_2 under its triangulations): triangles in flat
// arrays with their twins and constrained flags, the point of each vertex, and
// the operations that keep it a Delaunay triangulation — flips, splits at a new
// vertex, legalization (Lawson flips, book 4.2) and compaction into a Mesh.
// Internal to core/cdt.
//
// Triangle t owns half-edges 3t..3t+2 (ids.hpp); half-edge 3t+i runs from
// corner i to corner (i+1)%3 with the triangle on its left. The convex hull is
// closed by ghost triangles whose third corner is the vertex at infinity
// (kInfinite), so
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

#include "core/base/parallel.hpp"
#include "core/base/point.hpp"
#include "core/cdt/edge_feature_map.hpp"
#include "core/cdt/ids.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/spatial_sort.hpp"
#include "core/mesh/mesh.hpp"

namespace tinsmith::cdt {

/// Data-parallel loops over fewer items than this run on the calling thread.
inline constexpr std::size_t kSerialBelow = 4096;
using geometry::Box;
using geometry::HilbertGrid;
using geometry::radixSortHigh32;

class TriangleStore {
 public:
  // Vertex points, by vertex id (the CDT's input vertex ids).
  IdVector<VertexId, Point2> xy;
  IdVector<VertexId, HalfedgeId> vhe;  // an outgoing half-edge of each live vertex
  bool trackVhe = false;               // vhe is maintained only while constraints go in

  // Triangles. The corners (VertexId values, kInfinite included) and twins
  // (HalfedgeId values) per half-edge are plain arrays because compaction
  // moves them into a Mesh as they are (pack); read them through origin()
  // and twin(), write them through setTri() and link().
  std::vector<std::uint32_t> tv;
  std::vector<std::uint32_t> opp;
  IdVector<HalfedgeId, std::uint8_t> cons;  // constrained flag per half-edge
  EdgeFeatureMap edgeFeatures;
  std::vector<HalfedgeId> stack;  // half-edges legalize() has still to check

  // After pack() the triangle arrays live in a Mesh (compacted); the triangles
  // left out (ghosts, outside the domain) are kept here with their slots so
  // that unpack() restores the arrays exactly.
  struct RemovedTriangle {
    TriangleId slot;
    std::uint32_t tv[3];
    std::uint32_t opp[3];
    std::uint8_t cons[3];
  };
  std::vector<RemovedTriangle> removed;
  bool packed = false;
  std::uint32_t packedTriangles = 0;

  [[nodiscard]] bool triangulated() const { return !tv.empty(); }
  [[nodiscard]] std::uint32_t triCount() const { return static_cast<std::uint32_t>(tv.size() / 3); }
  /// The corner half-edge h starts from.
  [[nodiscard]] VertexId origin(HalfedgeId h) const { return VertexId(tv[h.value]); }
  /// Corner i (0..2) of triangle t.
  [[nodiscard]] VertexId corner(TriangleId t, std::uint32_t i) const {
    return VertexId(tv[halfedgeOf(t, i).value]);
  }
  /// The oppositely directed half-edge of the neighbouring triangle (every
  /// half-edge has one, ghosts closing the hull).
  [[nodiscard]] HalfedgeId twin(HalfedgeId h) const { return HalfedgeId(opp[h.value]); }
  /// The triangle across the edge of h.
  [[nodiscard]] TriangleId neighbour(HalfedgeId h) const { return triangleOf(twin(h)); }
  [[nodiscard]] bool isGhost(TriangleId t) const {
    return corner(t, 0) == kInfinite || corner(t, 1) == kInfinite || corner(t, 2) == kInfinite;
  }
  [[nodiscard]] const Point2& point(VertexId v) const { return xy[v]; }
  int orient(VertexId a, VertexId b, VertexId c) const {
    return geometry::orient2d(xy[a], xy[b], xy[c]);
  }
  int orientP(VertexId a, VertexId b, const Point2& p) const {
    return geometry::orient2d(xy[a], xy[b], p);
  }

  TriangleId newTriangle() {
    const TriangleId t(triCount());
    for (int i = 0; i < 3; ++i) {
      tv.push_back(VertexId::kInvalid);
      opp.push_back(HalfedgeId::kInvalid);
      cons.push_back(0);
    }
    return t;
  }
  void setTri(TriangleId t, VertexId a, VertexId b, VertexId c) {
    tv[halfedgeOf(t, 0).value] = a.value;
    tv[halfedgeOf(t, 1).value] = b.value;
    tv[halfedgeOf(t, 2).value] = c.value;
    if (trackVhe) {
      if (a != kInfinite) vhe[a] = halfedgeOf(t, 0);
      if (b != kInfinite) vhe[b] = halfedgeOf(t, 1);
      if (c != kInfinite) vhe[c] = halfedgeOf(t, 2);
    }
  }
  /// Recomputes vhe from the triangles and keeps it current from now on
  /// (bulk point insertion does not need it and skips the upkeep).
  void startTrackingVhe();
  void link(HalfedgeId h, HalfedgeId g) {
    opp[h.value] = g.value;
    opp[g.value] = h.value;
  }
  /// Half-edge h (of a triangle just rewritten) takes over an edge that was
  /// there before: twinned with `outer`, constrained as `flag` says.
  void takeEdge(HalfedgeId h, HalfedgeId outer, std::uint8_t flag) {
    link(h, outer);
    cons[h] = flag;
  }

  /// Is p in conflict with triangle t (inside its circumcircle, or for a ghost
  /// strictly outside its hull edge, or on the open hull edge)?
  inline bool inConflict(TriangleId t, const Point2& p) const {
    const VertexId a = corner(t, 0), b = corner(t, 1), c = corner(t, 2);
    if (std::max(a, std::max(b, c)) < kInfinite) [[likely]] {
      return geometry::incircle(xy[a], xy[b], xy[c], p) > 0;
    }
    VertexId u, v;
    if (a == kInfinite) {
      u = b, v = c;
    } else if (b == kInfinite) {
      u = c, v = a;
    } else if (c == kInfinite) {
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
  /// Afterwards triangle of h = (c,a,d) and twin's triangle = (d,b,c).
  void flip(HalfedgeId h) {
    const HalfedgeId g = twin(h);
    const TriangleId t0 = triangleOf(h), t1 = triangleOf(g);
    const VertexId a = origin(h), b = origin(nxt(h)), c = origin(prv(h)), d = origin(prv(g));
    const HalfedgeId x1 = twin(nxt(h)), x2 = twin(prv(h)), x3 = twin(nxt(g)), x4 = twin(prv(g));
    const std::uint8_t c1 = cons[nxt(h)], c2 = cons[prv(h)], c3 = cons[nxt(g)], c4 = cons[prv(g)];
    setTri(t0, c, a, d);
    setTri(t1, d, b, c);
    const HalfedgeId ca = halfedgeOf(t0, 0), ad = halfedgeOf(t0, 1), dc = halfedgeOf(t0, 2);
    const HalfedgeId db = halfedgeOf(t1, 0), bc = halfedgeOf(t1, 1), cd = halfedgeOf(t1, 2);
    takeEdge(ca, x2, c2);
    takeEdge(ad, x3, c3);
    link(dc, cd);
    cons[dc] = 0;
    cons[cd] = 0;
    takeEdge(db, x4, c4);
    takeEdge(bc, x1, c1);
  }

  /// Restores the (constrained) Delaunay property around vertex p after the
  /// half-edges on `stack` (each opposite p in its triangle) were created.
  void legalize(VertexId p) {
    const Point2 pp = xy[p];
    while (!stack.empty()) {
      const HalfedgeId h = stack.back();
      stack.pop_back();
      if (cons[h]) continue;
      const HalfedgeId g = twin(h);
      if (!inConflict(triangleOf(g), pp)) continue;
      flip(h);
      // p is corner 0 of h's triangle = (p,a,d) and corner 2 of (d,b,p).
      stack.push_back(halfedgeOf(triangleOf(h), 1));
      stack.push_back(halfedgeOf(triangleOf(g), 0));
    }
  }

  // -------------------------------------------------------------- splits
  /// Splits triangle t = (a,b,c) at new vertex p into (a,b,p), (b,c,p), (c,a,p).
  void splitTriangle(TriangleId t, VertexId p) {
    const VertexId a = corner(t, 0), b = corner(t, 1), c = corner(t, 2);
    const HalfedgeId ab = halfedgeOf(t, 0), bc = halfedgeOf(t, 1), ca = halfedgeOf(t, 2);
    const HalfedgeId o0 = twin(ab), o1 = twin(bc), o2 = twin(ca);
    const std::uint8_t c0 = cons[ab], c1 = cons[bc], c2 = cons[ca];
    const TriangleId n1 = newTriangle(), n2 = newTriangle();
    setTri(t, a, b, p);
    setTri(n1, b, c, p);
    setTri(n2, c, a, p);
    takeEdge(halfedgeOf(t, 0), o0, c0);
    takeEdge(halfedgeOf(n1, 0), o1, c1);
    takeEdge(halfedgeOf(n2, 0), o2, c2);
    // the reused slot's inner edges are new
    cons[halfedgeOf(t, 1)] = cons[halfedgeOf(t, 2)] = 0;
    link(halfedgeOf(t, 1), halfedgeOf(n1, 2));
    link(halfedgeOf(t, 2), halfedgeOf(n2, 1));
    link(halfedgeOf(n1, 1), halfedgeOf(n2, 2));
    stack.clear();
    stack.push_back(halfedgeOf(t, 0));
    stack.push_back(halfedgeOf(n1, 0));
    stack.push_back(halfedgeOf(n2, 0));
    legalize(p);
  }

  /// Splits the edge of half-edge h (a→b in (a,b,c), twin in (b,a,d)) at new
  /// vertex p; a constrained edge stays constrained in both halves.
  void splitEdge(HalfedgeId h, VertexId p) {
    const HalfedgeId g = twin(h);
    const TriangleId t0 = triangleOf(h), t1 = triangleOf(g);
    const VertexId a = origin(h), b = origin(nxt(h)), c = origin(prv(h)), d = origin(prv(g));
    const HalfedgeId xbc = twin(nxt(h)), xca = twin(prv(h)), xad = twin(nxt(g)), xdb = twin(prv(g));
    const std::uint8_t cbc = cons[nxt(h)], cca = cons[prv(h)], cad = cons[nxt(g)],
                       cdb = cons[prv(g)];
    const std::uint8_t split = cons[h];
    const TriangleId n0 = newTriangle(), n1 = newTriangle();
    setTri(t0, c, a, p);
    setTri(n0, b, c, p);
    setTri(t1, d, b, p);
    setTri(n1, a, d, p);
    takeEdge(halfedgeOf(t0, 0), xca, cca);
    takeEdge(halfedgeOf(n0, 0), xbc, cbc);
    takeEdge(halfedgeOf(t1, 0), xdb, cdb);
    takeEdge(halfedgeOf(n1, 0), xad, cad);
    const HalfedgeId ap = halfedgeOf(t0, 1), pc = halfedgeOf(t0, 2);
    const HalfedgeId cp = halfedgeOf(n0, 1), pb = halfedgeOf(n0, 2);
    const HalfedgeId bp = halfedgeOf(t1, 1), pd = halfedgeOf(t1, 2);
    const HalfedgeId dp = halfedgeOf(n1, 1), pa = halfedgeOf(n1, 2);
    link(ap, pa);
    link(pc, cp);
    link(pb, bp);
    link(pd, dp);
    cons[pc] = cons[cp] = cons[pd] = cons[dp] = 0;
    cons[ap] = cons[pa] = cons[pb] = cons[bp] = split;
    if (split) {
      edgeFeatures.split(edgeKey(a, b), edgeKey(a, p), edgeKey(p, b));
    }
    stack.clear();
    stack.push_back(halfedgeOf(t0, 0));
    stack.push_back(halfedgeOf(n0, 0));
    stack.push_back(halfedgeOf(t1, 0));
    stack.push_back(halfedgeOf(n1, 0));
    legalize(p);
  }

  /// Half-edge p→q, or invalid if p and q are not adjacent.
  HalfedgeId findHalfedge(VertexId p, VertexId q) const {
    const HalfedgeId start = vhe[p];
    HalfedgeId h = start;
    do {
      if (origin(nxt(h)) == q) return h;
      h = twin(prv(h));
    } while (h != start);
    return HalfedgeId::invalid();
  }

  /// Lawson's LOP (book 4.2) from the given edges (vertex pairs): flips every
  /// unconstrained edge that is not locally Delaunay, queueing the four edges
  /// around each flip. Consumes `todo`. Throws internalError if it runs away.
  void lop(std::vector<std::pair<VertexId, VertexId>>& todo);
  /// Runs the LOP on every edge of the triangles around v — needed after a
  /// forced split at a rounded intersection point, where v may lie off the
  /// split edge and edges at v itself can be non-Delaunay.
  void lopAround(VertexId v);
  /// Flips, until none is left, every unconstrained edge between two finite
  /// triangles whose quad is cocircular and whose other diagonal avoids the
  /// quad's least point by (x, y) (CdtOptions::canonicalTies): on a
  /// Delaunay triangulation it gives the one Delaunay triangulation of the
  /// points lifted by ε^rank, whatever the order they went in.
  void settleTies();

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
  /// vertex, its mesh vertex (invalid if no kept triangle uses it). The store
  /// keeps its points but no triangles until unpack(); features and crs of
  /// the storage are left to the caller.
  MeshStorage pack(std::vector<std::uint8_t> inside, std::span<const double> z,
                   std::size_t featureCount, unsigned threads,
                   IdVector<VertexId, VertexId>& vertexOf);
  /// The inverse of pack(): takes back its corners and twins, with
  /// workingVertex[mesh vertex] = the vertex it came from. The triangle arrays
  /// become exactly what they were before pack().
  void unpack(std::vector<std::uint32_t>&& corners, std::vector<std::uint32_t>&& twins,
              const std::vector<VertexId>& workingVertex);
};

}  // namespace tinsmith::cdt
