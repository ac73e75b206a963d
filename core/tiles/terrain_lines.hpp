// The lines a tile mesh must keep: break lines (roads, rivers, lake shores and
// plain break lines — the TIN's constrained edges of those features) and the
// rings of the TIN's domain boundary (its edges with one triangle: the outer
// boundary and the holes). Extracted once from the TIN, then simplified per
// zoom by Douglas–Peucker in 3-D and clipped to each tile.
//
// Chains run between nodes — vertices where the line graph does not simply
// continue (ends, junctions, a vertex shared by two features) — so
// simplification never disconnects a confluence or a road crossing: nodes are
// always kept. A river chain keeps its vertices' order, so a descending river
// stays descending after simplification (a subset of its vertices).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "core/base/point.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

struct TerrainLine {
  std::vector<Point3> points;  ///< ≥ 2 (rings: first point not repeated, ≥ 3)
  FeatureKind kind = FeatureKind::Other;
  bool ring = false;    ///< a domain-boundary ring (always closed)
  bool closed = false;  ///< the last point joins the first (rings, lake shores)
};

/// Whether the TIN's constrained edges of this kind are break lines in tiles.
bool isBreakLineKind(FeatureKind kind);

/// The break-line chains and domain-boundary rings of a TIN, deterministic.
std::vector<TerrainLine> extractTerrainLines(const TinData& tin);

/// The TIN's boundary half-edges (from, to), sorted: those a half-edge mesh
/// of it (Mesh::build) leaves without a twin — an edge of one triangle, of
/// two in the same direction, or of more than two — over the triangles with
/// three distinct corners in range. About 4 bytes a half-edge, not a mesh's
/// 60. Throws internalError for 2^31 vertices or 2^32 half-edges.
std::vector<std::pair<std::uint32_t, std::uint32_t>> boundaryHalfEdges(const TinData& tin);

/// How far a chord a → b that replaces part of a line is from the surface
/// the line lies on (largest vertical distance), so that simplification can
/// keep a chord that cuts a slope beside the line from straying off it.
using ChordError = std::function<double(const Point3& a, const Point3& b)>;

/// Douglas–Peucker in 3-D: keeps the ends (for a ring, the first vertex and
/// the vertex farthest from it) and every vertex farther than `tolerance` from
/// the simplified line; a ring keeps at least 3 vertices. With `chordError`,
/// a chord also splits (at its farthest vertex) while its error exceeds
/// `tolerance` (a chord that is one of the line's own segments must have none).
TerrainLine simplify(const TerrainLine& line, double tolerance, const ChordError& chordError = {});

/// A line cut to a closed rectangle. Where a segment crosses a side the
/// crossing is computed from the segment's ends in a canonical order
/// (lexicographic), with the side's coordinate exact and the other clamped to
/// the side, so the two tiles sharing the side get the same point bit for bit;
/// z is interpolated along the segment. A crossing within `snap` of a corner
/// becomes the corner. Pieces keep the line's kind.
struct ClippedPiece {
  std::vector<Point3> points;
  FeatureKind kind = FeatureKind::Other;
  bool ring = false;    ///< the piece came from a domain-boundary ring
  bool closed = false;  ///< a closed line wholly inside the rectangle
};
std::vector<ClippedPiece> clipToRect(const TerrainLine& line, const Rect& rect, double snap);

}  // namespace tinsmith::tiles
