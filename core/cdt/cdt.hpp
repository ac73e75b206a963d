// Constrained Delaunay triangulation of terrain input (book ch. 3, 4, 6):
// points with z, constraint polylines (break lines, contours, roads, rivers),
// an optional outer boundary and holes. Produces a Mesh / TinData.
//
// Algorithm: points are spatially sorted (Hilbert curve order) and inserted
// incrementally; each is located by a visibility walk from the previous vertex
// (stochastic edge order from a fixed seed, with an exhaustive fallback, so it
// cannot cycle) and the Delaunay property restored by Lawson flips (4.2). The
// convex hull is closed by "ghost" triangles at a vertex at infinity, so the
// hull needs no special cases. Constraint segments are inserted by swapping the
// crossed diagonals away (Sloan; book 6.5) and re-running the LOP on the new
// edges, never flipping a constrained edge. Predicates are exact
// (core/geometry/predicates.hpp); constructed points (constraint
// intersections) are rounded to doubles.
//
// A first bulk of at least CdtOptions::splitMinPoints points is built as two
// halves, left and right of the median x (on two threads when threads >= 2):
// each half gets its points and the constraints with both ends on its side;
// the triangles whose circumcircles certainly stay on their own side are
// kept, the hole between them is filled by the constrained Delaunay
// triangulation of the rest's corners, and the constraints that cross the
// split go in last. The split never depends on the thread count.
//
// Degeneracies, decided deterministically (same input and options → same mesh):
//   * cocircular quadruples: an edge is flipped only if the opposite vertex is
//     strictly inside the circumcircle — the neutral case keeps the current edge
//     (or, with CdtOptions::canonicalTies, the diagonal avoiding the least point);
//   * points closer than snapTolerance (exactly equal when 0) merge into the
//     vertex already there; z is taken from the higher constraintPriority()
//     feature (ties: the earlier input), the merge is recorded in the report;
//   * a constraint through existing vertices is split at them; collinear
//     overlapping constraints share edges (the edge records every feature);
//   * crossing constraints are split at their intersection; the new vertex's z
//     is interpolated along the higher-priority feature (ties: the feature
//     registered first); the event is recorded. Segments go in in the Hilbert
//     order of their midpoints, whatever their input order;
//   * zero-length segments (after merging) are dropped and recorded.
//
// Usage:
//   Cdt cdt({.snapTolerance = 0.001});
//   auto road = cdt.addFeature(FeatureKind::Road, "roads.gpkg, feature 3");
//   cdt.insertPoints(points, spotFeature);
//   cdt.insertConstraint(roadLine, road);
//   cdt.finalize();                  // throws tinsmith::Error on bad input
//   TinData tin = cdt.toTinData();   // or cdt.mesh()
// More input may be added after finalize(); the next finalize() inserts it into
// the existing triangulation. Until then mesh(), toTinData() and validate()
// throw usageError and meshVertex() returns invalid ids.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "core/mesh/mesh.hpp"
#include "core/mesh/validate.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith {

/// Index into the feature list (TinData::features); kNoFeature for input that
/// belongs to no feature (priority 0).
using FeatureId = std::uint32_t;
inline constexpr FeatureId kNoFeature = std::numeric_limits<std::uint32_t>::max();

struct CdtOptions {
  /// Points closer than this (metres, in x, y) merge into one vertex. 0 merges
  /// only exact duplicates. Also used to snap a constraint intersection onto a
  /// vertex that is nearer than this.
  double snapTolerance = 0.0;
  /// Copied into TinData::crs.
  std::string crs;
  /// Threads for the parallel stages (spatial sort, the two halves of a
  /// split build, copying, output mesh points); 0 =
  /// std::thread::hardware_concurrency(). The result is identical for every
  /// value.
  unsigned threads = 1;
  /// The first bulk of at least this many points is triangulated as two
  /// halves, left and right of a vertical line (concurrently when threads >=
  /// 2), which are then merged along the seam; 0 = always in one go. With
  /// cocircular input the mesh may depend on this value (any choice is
  /// Delaunay); it never depends on `threads`.
  std::size_t splitMinPoints = 50000;
  /// Cocircular ties are broken by a symbolic perturbation instead of
  /// keeping the edge already there: each point's lift onto the paraboloid
  /// is raised by ε^rank, ranked by (x, y), so of a cocircular quad's two
  /// diagonals the one avoiding its least point wins. The mesh is then a
  /// function of the points and constraints alone — not of their order, the
  /// split or anything else — so triangulations of overlapping parts of one
  /// point set agree where they are Delaunay (ingest/build/block_tin.hpp).
  /// Costs one pass of incircle tests over the edges after the insertion.
  bool canonicalTies = false;
};

/// What the CDT changed in its input, so callers can report it.
struct CdtReport {
  struct Merge {
    Point2 at;                     ///< position of the vertex kept
    VertexId kept;                 ///< input vertex id that stays
    VertexId merged;               ///< input vertex id merged into it
    double keptZ = 0, droppedZ = 0;
    FeatureId keptFeature = kNoFeature, droppedFeature = kNoFeature;
  };
  struct Intersection {
    Point3 at;                     ///< the new (or snapped-to) vertex, z as chosen
    VertexId vertex;               ///< its input-side vertex id
    FeatureId existing = kNoFeature;  ///< feature of the constraint already there
    FeatureId inserted = kNoFeature;  ///< feature of the constraint being inserted
    double zExisting = 0, zInserted = 0;  ///< z of each constraint at that point
    /// The rounded crossing could not go in as a vertex on both constraints
    /// (slivers between near-duplicate vertices) and was moved to the nearest
    /// vertex of the two triangles beside the crossed edge, bending a
    /// constraint by more than the snap tolerance: they bend through `at`.
    bool forced = false;
    /// How far the constraints bend to pass through the vertex used: its
    /// larger distance from the two constraint segments (0 for a new vertex,
    /// up to the snap tolerance when snapped, more when forced). Bends add up
    /// along a constraint.
    double moved = 0;
  };
  struct Dropped {
    enum class What { ZeroLengthSegment, PointOutsideDomain };
    What what = What::ZeroLengthSegment;
    FeatureId feature = kNoFeature;
    Point2 at;
  };
  std::vector<Merge> merges;
  std::vector<Intersection> intersections;
  std::vector<Dropped> dropped;
};

struct CdtTestAccess;

class Cdt {
 public:
  explicit Cdt(CdtOptions options = {});
  ~Cdt();
  Cdt(Cdt&&) noexcept;
  Cdt& operator=(Cdt&&) noexcept;
  Cdt(const Cdt&) = delete;
  Cdt& operator=(const Cdt&) = delete;

  /// Registers an input feature; the id indexes TinData::features.
  FeatureId addFeature(FeatureKind kind, std::string source);
  [[nodiscard]] const std::vector<TinFeature>& features() const;

  /// Adds a point (x, y, z in the project CRS, metres). Returns its input
  /// vertex id (consecutive from 0 over every inserted point, polyline vertices
  /// included). Throws inputError for a non-finite coordinate or an x, y
  /// outside 0 ∪ [1e-50, 1e60] in magnitude (where exact predicates on doubles
  /// would underflow or overflow), naming the feature. The point is
  /// triangulated at the next finalize().
  VertexId insertPoint(const Point3& p, FeatureId feature = kNoFeature);
  /// Adds many points; returns the id of the first (the rest follow in order).
  /// All or nothing: throws as insertPoint for the first bad point, having
  /// added none.
  VertexId insertPoints(std::span<const Point3> points, FeatureId feature = kNoFeature);

  /// Adds a constraint polyline (its vertices become input vertices); `closed`
  /// adds the segment from the last vertex back to the first. A polyline with
  /// fewer than 2 vertices adds its points only. All or nothing, as
  /// insertPoints (so are addBoundary and addHole).
  void insertConstraint(std::span<const Point3> polyline, FeatureId feature, bool closed = false);
  /// Adds a constraint segment between two input vertices.
  void insertConstraintSegment(VertexId a, VertexId b, FeatureId feature);

  /// The outer boundary of the domain: a closed ring (first vertex need not be
  /// repeated). Triangles outside every boundary ring are removed at finalize().
  /// Several rings may be given (several islands). Its edges are constraints.
  void addBoundary(std::span<const Point3> ring, FeatureId feature);
  /// A hole (void): triangles inside are removed. Rings nest by parity; with
  /// a boundary, a hole (or the part of one) outside every boundary ring
  /// removes nothing.
  void addHole(std::span<const Point3> ring, FeatureId feature);

  /// Triangulates everything pending and inserts pending constraints. Throws
  /// geometryError when the input has fewer than 3 non-collinear distinct
  /// points; internalError on a broken invariant.
  void finalize();

  /// The finished mesh (after finalize(), with no input added since; else
  /// throws usageError): only triangles inside the domain;
  /// vertex ids are compacted (see meshVertex()). Built on the first call after
  /// each finalize() (domain classification + compaction, about a fifth of the
  /// triangulation time) of mesh(), toTinData(), meshVertex(), report() or
  /// validate(); these may be called from several threads at once (the first
  /// builds, the others wait), not while input is added or finalize() runs.
  [[nodiscard]] const Mesh& mesh() const;
  /// mesh() as TinData (vertices, CCW triangles, constrained edges per feature,
  /// features, crs).
  [[nodiscard]] TinData toTinData() const;
  /// Mesh vertex of an input vertex (after merges); invalid if it was dropped
  /// (outside the domain) or finalize() has not run since the last input.
  [[nodiscard]] VertexId meshVertex(VertexId input) const;
  [[nodiscard]] std::size_t inputVertexCount() const;

  [[nodiscard]] const CdtReport& report() const;

  /// validate(mesh()) plus: every input point is a mesh vertex or reported as
  /// merged/dropped, and every inserted constraint segment is present as a chain
  /// of mesh edges carrying its feature, through vertices within rounding/snap
  /// distance of the input segment (for features bent by a crossing reported
  /// as forced: connected only; checked when no boundary or hole clips the
  /// constraints).
  [[nodiscard]] ValidationReport validate(const ValidationOptions& options = {}) const;

  /// Re-triangulates a TinData: its vertices and constrained edges become input
  /// (same feature ids) and triangles outside its boundary edges stay outside.
  /// Use to add more input to a loaded TIN.
  static Cdt fromTinData(const TinData& tin, CdtOptions options = {});

 private:
  friend struct CdtTestAccess;  // core/cdt/cdt_test_access.hpp
  void buildMesh() const;
  [[nodiscard]] ValidationReport validateCounting(const ValidationOptions& options,
                                                  std::size_t& chainSteps) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tinsmith
