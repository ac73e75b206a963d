// Constraint insertion into the CDT (Sloan; book 6.5): input segments go in
// by swapping the crossed diagonals away and re-running the LOP, never
// flipping a constrained edge; a segment that meets an existing constraint is
// split at the crossing, which crossing resolution places
// (crossing_resolution.cpp). This is the top layer of the working
// triangulation: Cdt's facade, the two-halves build and the domain use it.
// Internal to core/cdt.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "core/cdt/point_insertion.hpp"

namespace tinsmith::cdt {

/// How deep reroutes of crossed constraints may nest (rerouteThrough inserts
/// segments, whose crossings may reroute again): far beyond what input needs
/// (the tests and two minutes of fuzzing never nest a second one), far below a
/// stack overflow (a level takes about 1.2 KB of stack in an optimised build).
inline constexpr std::size_t kRerouteDepthLimit = 256;

/// An input constraint segment between input vertices.
struct Segment {
  VertexId a, b;
  FeatureId feature;
};

/// The steps of crossing resolution, in the order they are tried
/// (ConstrainedTriangulation::placeCrossing): the first that applies places
/// the crossing.
enum class CrossingStep : std::uint8_t {
  /// At an end of the segment being inserted that is no corner beside the
  /// crossed edge; the crossed constraint is rerouted through it.
  SegmentEnd,
  /// At the vertex (an end or an apex beside the crossed edge) within the
  /// tolerance of the crossing.
  NearVertex,
  /// A new vertex splitting the crossed edge (the usual case).
  SplitEdge,
  /// A new vertex strictly inside the one triangle beside the crossed edge
  /// that the rounded crossing fell in (the other is a sliver).
  BesideEdge,
  /// As BesideEdge after moving the crossing a few ulps across the edge.
  Nudged,
  /// A new vertex in a triangle beyond a sliver, reachable by flips.
  BeyondSliver,
  /// No vertex: an apex of a sliver is taken into the crossed constraint,
  /// and the segment is walked again.
  SliverApex,
  /// At the nearest of the crossed edge's ends and apexes (reported as forced
  /// when that bends a constraint beyond the tolerance).
  NearestVertex,
};
inline constexpr std::size_t kCrossingSteps = 8;

/// Where crossing resolution puts a crossing (placeCrossing's answer).
struct CrossingPlacement {
  CrossingStep step = CrossingStep::SplitEdge;
  // The existing vertex used (SegmentEnd, NearVertex, SliverApex, NearestVertex).
  VertexId vertex;
  // The triangle the new vertex goes into (BesideEdge, Nudged, BeyondSliver).
  TriangleId triangle;
  // The new vertex (SplitEdge, BesideEdge, Nudged, BeyondSliver).
  Point2 at;
  // SliverApex: how far the crossed constraint bends.
  double bendBy = 0;
};

/// One crossing under resolution: the segment cur→tgt being inserted meets
/// the constrained edge e = R→L (the half-edge on cur's side), with apex c
/// beside e on cur's side and d on the other (kInfinite for a ghost's). X is the
/// rounded intersection of the two lines; a vertex within `tol` of X is taken
/// to be at X; `nearest` is the nearest of R, L, c and d to X.
struct Crossing {
  VertexId cur, tgt;
  HalfedgeId e;
  VertexId R, L, c, d, nearest;
  Point2 X;
  double tol;
};

/// A constrained Delaunay triangulation under construction: input vertices
/// (Triangulation) and input segments, inserted at insertPendingPoints() and
/// insertPendingSegments().
class ConstrainedTriangulation : public Triangulation {
 public:
  std::vector<Segment> segments;
  std::size_t segmentsDone = 0;  // segments below this are inserted
  // Per feature: how far its constraints were bent by taking in apexes beside
  // them, beyond what report.intersections records (crossingVertex); the
  // validator allows that much more.
  std::vector<double> bend;
  // Reroutes under way (rerouteThrough), their bound and the deepest so far.
  std::size_t rerouteDepth = 0, rerouteDepthLimit = kRerouteDepthLimit, deepestReroute = 0;
  // How many crossings each step of crossing resolution placed (tests).
  std::array<std::size_t, kCrossingSteps> crossingSteps{};

  ConstrainedTriangulation() = default;
  explicit ConstrainedTriangulation(CdtOptions opts) : Triangulation(std::move(opts)) {}
  /// A triangulation of its own for a part of a bigger build (a half, the
  /// seam of the two-halves build): `xy`, `z`, `vfeat` become its pending
  /// input vertices 0.., `segments` (in those ids) its pending constraints.
  /// It runs on one thread, with no split of its own.
  ConstrainedTriangulation(double snapTolerance, std::size_t rerouteLimit,
                           std::vector<TinFeature> featureList, std::vector<Point2> points,
                           std::vector<double> heights, std::vector<FeatureId> vertexFeatures,
                           std::vector<Segment> segmentList);

  // ---------------------------------------------------- pending input
  /// Inserts the pending points: a first bulk of at least
  /// options.splitMinPoints as two halves (insertAsTwoHalves) when they
  /// split well, else in insertionOrder().
  void insertPendingPoints();
  /// Inserts the segments not inserted yet (insertSegments).
  void insertPendingSegments();

  /// Inserts segments[k] for every k in `which` (ascending), in runs of up to
  /// 64 consecutive segments of one polyline (each starting where the last
  /// ended), the runs in the Hilbert order of their first midpoints: each
  /// segment starts next to the last one, and consecutive runs work on the
  /// same part of the mesh (and of memory). Nothing but rounding depends on
  /// this order: crossing ties are decided by feature (outranks()), not by
  /// which segment came first.
  void insertSegments(const std::vector<std::uint32_t>& which);

  // ---------------------------------- two-halves build (two_halves.cpp)
  /// Per triangle: 1 unless it is certainly Delaunay in the union of the two
  /// halves, the left one's points having x <= leftMax and the right one's
  /// x >= rightMin; `leftHalf` says which half this is. Ghosts are unsafe.
  /// Only triangles connected to a ghost through unsafe ones are tested: the
  /// triangles in conflict with any one point of the other half (outside this
  /// half's hull) form a connected set holding a ghost, so the unsafe set is
  /// connected too, and a triangle never reached is safe.
  [[nodiscard]] IdVector<TriangleId, std::uint8_t> unsafeTriangles(bool leftHalf, double leftMax,
                                                                   double rightMin) const;

  /// The x value that splits the pending points `order` into a left part
  /// (x < split) and a right part (x >= split) of comparable size, with every
  /// left–right pair farther apart than the snap tolerance (so no merge can
  /// span the seam). NaN when there is none.
  [[nodiscard]] double splitValue(const std::vector<VertexId>& order) const;

  /// Triangulates the pending points `order` (first bulk, nothing triangulated
  /// yet) as two halves and merges them, emptying `order`; false, with
  /// nothing changed, when the points do not split well (then the caller
  /// inserts them in one go).
  bool insertAsTwoHalves(std::vector<VertexId>& order);

  /// Replaces this triangulation's triangles (the left half, global ids) by
  /// the union of the safe triangles of both halves and the triangles of
  /// DT(S) that fill the hole between them. `right` has the right half in local ids
  /// (rightGlobal maps them); unsafeLeft/unsafeRight flag each half's
  /// triangles (unsafeTriangles()). Frees right's triangle arrays as it
  /// copies them. In three steps (two_halves.cpp): collectSeam (S and the
  /// hole's border), fillHole (DT(S) inside the hole), stitch (copy and link).
  void mergeHalves(ConstrainedTriangulation& right, const IdVector<VertexId, VertexId>& rightGlobal,
                   const IdVector<TriangleId, std::uint8_t>& unsafeLeft,
                   const IdVector<TriangleId, std::uint8_t>& unsafeRight);

  // --------------------------------------------- constraint insertion
  /// Marks the edge p–q constrained, carrying f; throws internalError when
  /// p–q is no edge.
  void addEdgeFeature(VertexId p, VertexId q, FeatureId f);

  /// Is c on the ray from a through b (c collinear with a, b assumed)?
  bool onRay(VertexId a, VertexId b, VertexId c) const;

  /// Is u a vertex exactly on the input segment a0→b0 (exact orient2d) and
  /// strictly between cur and tgt? After a split at a rounded crossing point,
  /// cur→tgt is no longer on the input line, so a vertex exactly on it must be
  /// found against a0→b0 or the constraint would bypass it by an ulp.
  bool onInputSegment(VertexId a0, VertexId b0, VertexId cur, VertexId tgt, VertexId u,
                      const std::vector<VertexId>& passed) const;

  /// Inserts the constraint segment a→b (live vertices) for feature f.
  void insertSegment(VertexId a, VertexId b, FeatureId f);

  /// Swaps away every edge crossing a→b (Sloan; book 6.5), marks a–b
  /// constrained for f, then restores the Delaunay property from the new edges.
  void removeCrossings(VertexId a, VertexId b,
                       const std::vector<std::pair<VertexId, VertexId>>& crossed, FeatureId f);

  // ---------------------------------------------- crossing resolution
  /// z of the segment u→w (linear in its vertices' z) at the point of it
  /// nearest to p.
  double zAlong(VertexId u, VertexId w, const Point2& p) const;

  /// Does feature f win a crossing or an edge against g? Higher
  /// constraintPriority() first, then the earlier registered feature.
  bool outranks(FeatureId f, FeatureId g) const;

  /// The highest-ranking (outranks()) feature of the constrained edge u–w.
  FeatureId edgeWinner(VertexId u, VertexId w) const;

  /// Radius within which a constructed (rounded) point is taken to be an
  /// existing vertex: 2^-40 of its coordinate magnitude (about 6e-6 m at UTM
  /// northings), far above the rounding error of a crossing yet far below
  /// survey precision.
  static double constructionTolerance(const Point2& p);

  /// Distance from vertex v to the segment between vertices a and b.
  double distanceToSegment(VertexId v, VertexId a, VertexId b) const;

  /// Is each feature of the edge R–L on both or on neither of the edges R–u
  /// and u–L?
  bool chainsStayOpen(VertexId R, VertexId L, VertexId u) const;

  /// Records that the features of edge R–L (but `except`) bend by `by`.
  void addBend(VertexId R, VertexId L, FeatureId except, double by);

  /// The constraint cur→tgt crosses constrained edge e (R→L, in the
  /// triangle on cur's side). Makes a vertex at the crossing and returns it,
  /// or returns invalid when it rerouted e's constraint instead (the caller
  /// walks cur→tgt again). Where the vertex goes is placeCrossing's choice;
  /// the event is recorded in the report.
  VertexId crossingVertex(VertexId cur, VertexId tgt, HalfedgeId e, FeatureId f);
  /// The crossing of cur→tgt with the constrained edge e (see Crossing).
  [[nodiscard]] Crossing crossingAt(VertexId cur, VertexId tgt, HalfedgeId e) const;
  /// Where crossing x goes: the first step, in CrossingStep's order, that
  /// applies. Changes nothing.
  [[nodiscard]] CrossingPlacement placeCrossing(const Crossing& x) const;
  // The steps of placeCrossing, one per CrossingStep (documented there),
  // each changing nothing; each assumes that the steps before it did not
  // apply. nullopt: the step does not apply.
  [[nodiscard]] std::optional<CrossingPlacement> atSegmentEnd(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> atNearVertex(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> splittingEdge(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> besideEdge(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> nudgedBesideEdge(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> beyondSliver(const Crossing& x) const;
  [[nodiscard]] std::optional<CrossingPlacement> atSliverApex(const Crossing& x) const;
  [[nodiscard]] CrossingPlacement atNearestVertex(const Crossing& x) const;
  /// Squared distance from vertex v to p.
  [[nodiscard]] double squaredDistance(VertexId v, const Point2& p) const {
    const double dx = xy[v].x - p.x, dy = xy[v].y - p.y;
    return dx * dx + dy * dy;
  }
  /// Is p strictly inside the triangle (a, b, u) beyond its edge a→b (u not
  /// kInfinite)?
  [[nodiscard]] bool strictlyInside(VertexId a, VertexId b, VertexId u, const Point2& p) const {
    return u != kInfinite && geometry::orient2d(xy[b], xy[u], p) > 0 &&
           geometry::orient2d(xy[u], xy[a], p) > 0;
  }
  /// The triangle that holds point p strictly inside (or, with a target
  /// vertex at p, a triangle at the target), if the open segment from vertex a
  /// to p crosses no constrained edge and passes through no vertex; else
  /// invalid.
  [[gnu::noinline]] TriangleId clearPathEnd(VertexId a, const Point2& p,
                                            VertexId target = VertexId::invalid()) const;

  /// The constrained edge R–L is replaced by R→w→L, w a vertex the segments
  /// from R and L to which cross no constrained edge and pass through no
  /// vertex (an apex beside R–L, or see clearPathEnd): they are edges already
  /// or are recovered by flips alone. Throws internalError when R–L is no
  /// edge, or when reroutes nest deeper than rerouteDepthLimit (each reroute
  /// inserts segments that may cross constraints and reroute again; the
  /// guards of insertSegment are per call).
  [[gnu::noinline]] void rerouteThrough(VertexId R, VertexId L, VertexId w);

  /// X moved by up to 8 ulps across the edge a→b towards u, to a point
  /// strictly inside the triangle (a, b, u); nullopt if none is found.
  [[gnu::noinline]] std::optional<Point2> nudgedInto(VertexId a, VertexId b, VertexId u,
                                                     const Point2& X) const;

  /// Of the apexes c and d beside e (kInfinite to skip one), the one nearest
  /// to e's segment within maxDistance, and its distance; invalid if none. An apex
  /// qualifies if each of e's features is on both or on neither of its edges
  /// to e's ends: the feature's chain then grows by an edge, or loses e where
  /// it already runs through the apex. A feature on one of them only would
  /// make its chain run back on itself.
  [[gnu::noinline]] std::pair<VertexId, double> sliverApexOnEdge(HalfedgeId e, VertexId c,
                                                                 VertexId d,
                                                                 double maxDistance) const;
};

}  // namespace tinsmith::cdt
