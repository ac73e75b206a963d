// Greedy refinement of a fitted tile mesh against the TIN, one point at a
// time, worst first (as greedy-insertion terrain simplifiers do; Garland &
// Heckbert 1995): the triangle whose exact error (surface_difference.hpp) is
// the largest takes the TIN's point where that error is reached, and only the
// triangles the insertion changes are measured again. The mesh stays a
// constrained Delaunay triangulation: a new vertex goes in by Lawson flips
// that never cross a held edge (a tile side, a break line, a domain ring).
//
// Where the worst point is
//   - at (or beside) a free vertex: the vertex is what is off; it takes the
//     TIN's z and is held;
//   - on a break line or ring edge (within rounding): the line is split there,
//     its new vertex on the TIN (a river's z kept between the edge's ends, so
//     no river rises downstream);
//   - on a free edge: the edge is split there;
//   - inside a triangle: a new vertex on the TIN (the worst TIN vertex of the
//     triangle when that one misses the tolerance too, else the worst point).
// A point never goes onto a tile side, nor closer to one than `sideMargin`
// (sides are shared with the neighbouring tile bit for bit); an error on a
// side is the side's own, left as it is.
//
// Every new vertex lies on the TIN, so the mesh converges to the TIN at
// worst; the free vertices keep their fitted z. Deterministic: the same tile
// gives the same result (ties broken by triangle index).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/tiles/chord_sag.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

struct RefineOptions {
  double tolerance = 1.0;            ///< metres: refine while a triangle is above
  std::size_t maxTriangles = 32768;  ///< stop before the tile holds more
  double sideMargin = 0.0;           ///< metres a new vertex keeps from the tile's sides
  /// When positive (m), a triangle's chord sag below a sphere of this radius
  /// (chord_sag.hpp) counts in its error: where the sag is the larger part,
  /// the point taken is where it is deepest (a long flat triangle is split
  /// until it lies within the tolerance of the curved ground).
  double earthRadius = 0.0;
};

/// Refines `tile` (a constrained Delaunay triangulation: CCW triangles,
/// heldEdges, riverEdges, flags as TileSurface documents) in place. Each
/// triangle's exact difference (triangleDifferences) is measured once and
/// again only when the triangle changes; an edge's, once for its life.
/// Sets tile.error, tile.errorAt and tile.triangleErrors (vertical, without
/// the sag) from the final triangles, and tile.outOfReach for the triangles
/// left over the tolerance because nothing the tile may do reaches their
/// worst point (on a side, or within the side margin outside them), and
/// returns how many vertices it inserted or held.
std::size_t refineTile(TileSurface& tile, const TinIndex& tin, const RefineOptions& options);

}  // namespace tinsmith::tiles
