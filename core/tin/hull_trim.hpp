// Trimming the slivers a convex hull adds around a non-convex point set.
// A Delaunay triangulation covers its points' convex hull; where the data's
// footprint is not convex — a DEM projected into another CRS, whose edges
// along meridians and parallels curve — the hull is closed by long, thin
// triangles that join points kilometres apart. They are not terrain: across
// them the surface is a near-vertical wall, and a tiler would spend its budget
// following it.
#pragma once

#include <cstddef>

#include "core/tin/tin_data.hpp"

namespace tinsmith {

/// Removes, from the outside in, every boundary triangle whose boundary edge
/// is unconstrained and longer than `maxEdge` (metres, in x, y), as long as
/// the domain stays one disk a component and every vertex keeps a triangle: a
/// triangle goes only when exactly one of its edges is on the boundary and
/// its third vertex is not. The new boundary edges become constrained edges of
/// a new Boundary feature, so a re-triangulation (Cdt::fromTinData) keeps the
/// trimmed domain. Vertices are not renumbered; the triangles keep their
/// order. Deterministic. Returns the number of triangles removed.
std::size_t trimHull(TinData& tin, double maxEdge);

}  // namespace tinsmith
