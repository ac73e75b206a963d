// Flat triangles of a contour TIN and where to add vertices to remove them.
//
// A triangle is flat when its three vertices lie on contours (each is an end
// of a contour-constrained edge) and have the same z: all three sit on one
// contour level, so the triangle is level. Contour-only TINs are full of them
// wherever a contour bends back on itself — valley heads, ridge noses,
// summits — and they turn valleys and ridges into terraces.
//
// The repair (after the approach of inserting points on the medial axis
// between contour arms): flat triangles are grouped into flat regions
// (neighbours across edges that are not contour edges, same level z0). For
// every flat triangle one new vertex is proposed: the midpoint of its longest
// edge when that edge is not a contour edge (across a valley or ridge that
// midpoint lies near the medial axis between the two contour arms), else its
// centroid. Its z follows the terrain's steepest path out of the region: with
// d0 the distance to the region's own z0 contour edges and d1 the distance to
// the nearest vertex where the region opens onto another level z1,
//     z = z0 + (z1 − z0) · d0 / (d0 + d1),
// so z rises (ridge) or falls (valley) from the contour towards the next one.
// A region closed by its contour on every side (a summit or a pit) gets a
// dome: z = z0 ± h · d0 / d0max with h half the contour interval seen just
// outside. Every proposed vertex lies inside or on its flat triangle, so once
// inserted every flat triangle is split and every new triangle has a vertex
// off the level: repeating the analysis finds what remains (normally none).
#pragma once

#include <cstddef>
#include <vector>

#include "core/base/point.hpp"
#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

struct FlatTriangleAnalysis {
  std::vector<std::uint32_t> flatTriangles;  ///< indices into TinData::triangles
  std::size_t regions = 0;                   ///< connected flat regions
  std::size_t closedRegions = 0;             ///< summits and pits (no exit to another level)
  /// Vertices to insert (x, y, z), deterministic order. Empty when there is
  /// nothing to repair, or a region's z cannot be estimated (no neighbour level).
  std::vector<Point3> proposals;
};

// Each function takes the TIN as TinData or as a Mesh (the CDT's output, so
// the builder needs no TinData copy while it repairs); a Mesh and its
// toTinData() give identical results (same vertex and triangle numbering).

/// Which vertices lie on a contour: ends of edges constrained by a Contour feature.
std::vector<char> contourVertices(const TinData& tin);
std::vector<char> contourVertices(const Mesh& mesh);

/// Counts and locates flat triangles and proposes the vertices that repair them.
/// `minSpacing` (metres): proposals closer than this to an existing vertex of
/// their triangle are skipped (they would merge into it).
FlatTriangleAnalysis analyseFlatTriangles(const TinData& tin, double minSpacing = 0.0);
FlatTriangleAnalysis analyseFlatTriangles(const Mesh& mesh, double minSpacing = 0.0);

/// Just the count (for reports): flat triangles in `tin`.
std::size_t countFlatTriangles(const TinData& tin);
std::size_t countFlatTriangles(const Mesh& mesh);

}  // namespace tinsmith::ingest
