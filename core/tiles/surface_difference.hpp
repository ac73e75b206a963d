// The exact vertical distance between two piecewise-linear surfaces: a tile's
// mesh and the TIN. Their difference is linear on every cell of their overlay
// (each piece of a mesh triangle cut by the TIN triangles under it), so its
// largest absolute value is taken at a vertex of the overlay: a TIN vertex
// inside a mesh triangle, a mesh vertex inside a TIN triangle, or a crossing of
// a TIN edge with a mesh edge. So per mesh triangle: the TIN's section along
// each of its edges (the crossings, and its corners where the TIN has them)
// against the mesh's line, and the TIN vertices inside it against the mesh's
// plane — work in proportion to the overlay's vertices, not its cells. The
// result is a bound up to the rounding of those crossings (about 1e-12 of the
// tile's size), not a sample. Only the overlap of the two domains counts.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "core/base/point.hpp"
#include "core/geometry/cell_grid.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

/// A uniform grid over a TIN's triangles for overlap queries. Keeps a
/// reference to `tin`; immutable, so any number of threads may query it.
class TinIndex {
 public:
  explicit TinIndex(const TinData& tin);
  [[nodiscard]] const TinData& tin() const { return tin_; }
  /// The triangles whose bounding boxes meet `box`, each once, ascending —
  /// all those that meet it, and of the rest only those within a hundredth
  /// of an index cell of a cell the box overlaps (a long slanted sliver is
  /// listed only in the cells it comes near).
  void overlapping(const Rect& box, std::vector<std::uint32_t>& out) const;
  /// The vertices inside `box` (closed).
  void verticesIn(const Rect& box, std::vector<std::uint32_t>& out) const;

  /// A point of the TIN's section along a segment: the parameter t ∈ [0, 1]
  /// from a to b and the TIN's z there. z is NaN at a marker that starts a gap
  /// (the part of the segment after the previous point and before the next
  /// lies outside the TIN).
  struct SectionPoint {
    double t;
    double z;
  };
  /// The TIN's section along a → b: where the segment enters and leaves each
  /// TIN triangle, ascending in t (points within 1e-12 merged, the lower
  /// triangle id's z kept), with gap markers. The section is linear between
  /// consecutive points, so it is the TIN along the segment exactly. A
  /// function of (a, b) alone: the same call gives the same doubles.
  void section(Point2 a, Point2 b, std::vector<SectionPoint>& out) const;
  /// The TIN's z at p (the lowest-id triangle containing it), or nullopt.
  [[nodiscard]] std::optional<double> z(Point2 p) const;

 private:
  [[nodiscard]] Rect triangleBox(std::uint32_t t) const;
  const TinData& tin_;
  std::optional<CellGrid> grid_;        // triangles by their boxes
  std::optional<CellGrid> vertexGrid_;  // vertices
};

struct SurfaceDifference {
  double maxAbs = 0.0;  ///< max |mesh − TIN| over the overlap (m)
  Point2 at;            ///< where it is reached
  double meshZ = 0.0, tinZ = 0.0;
  std::size_t pieces = 0;  ///< overlay vertices visited
  /// The largest difference at a TIN vertex of the overlay (0 when none), where
  /// and the TIN's z there.
  double vertexAbs = 0.0;
  Point2 vertex;
  double vertexZ = 0.0;
};

/// The largest difference along a mesh edge p → q (z linear from p.z to q.z)
/// against the TIN's section under it: the same doubles whichever end comes
/// first (the section is taken from the lesser end in x, then y).
struct EdgeDifference {
  double maxAbs = 0.0;
  Point2 at;
  double meshZ = 0.0, tinZ = 0.0;
  std::size_t points = 0;  ///< section points visited
};

/// Edge differences remembered by their end vertices (ids into the
/// `vertices` the triangles index), for a caller that measures triangles
/// sharing edges again and again (a mesh refined in place). forget(v) when
/// vertex v moves or changes z.
class EdgeDifferenceCache {
 public:
  void forget(std::uint32_t v) {
    if (v < generation_.size()) ++generation_[v];
  }

 private:
  friend std::vector<SurfaceDifference> triangleDifferences(
      std::span<const Point3>, std::span<const std::array<std::uint32_t, 3>>, const TinIndex&,
      EdgeDifferenceCache*);
  struct Entry {
    EdgeDifference difference;
    std::uint32_t generationA, generationB;
  };
  std::unordered_map<std::uint64_t, Entry> edges_;
  std::vector<std::uint32_t> generation_;
};

/// The difference of a triangle mesh (CCW triangles over `vertices`) and the
/// indexed TIN within each mesh triangle, in the triangles' order (maxAbs 0
/// and `at` unset for a triangle outside the TIN). With a cache, an edge
/// measured before (same ends, neither forgotten since) is not measured again;
/// the results are the same doubles.
std::vector<SurfaceDifference> triangleDifferences(
    std::span<const Point3> vertices, std::span<const std::array<std::uint32_t, 3>> triangles,
    const TinIndex& tin, EdgeDifferenceCache* cache = nullptr);

/// The largest of triangleDifferences (pieces summed).
SurfaceDifference maxVerticalDifference(std::span<const Point3> vertices,
                                        std::span<const std::array<std::uint32_t, 3>> triangles,
                                        const TinIndex& tin);

}  // namespace tinsmith::tiles
