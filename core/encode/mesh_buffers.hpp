// From double-precision triangles in a content frame to the float buffers a
// .glb holds (core/encode/glb.hpp): positions relative to an origin, unit
// per-vertex normals, flat indices. Shared by the tile encoder
// (core/tiles/tile_content.cpp) and the whole-TIN export
// (ingest/export/glb_export.cpp), so both shade and place a surface alike.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "core/encode/glb.hpp"

namespace tinsmith::encode {

using Triangle = std::array<std::uint32_t, 3>;

/// An axis-aligned box: lowest and highest x, y, z.
struct Box3 {
  Point3 lo;
  Point3 hi;
  [[nodiscard]] Point3 centre() const {
    return {0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)};
  }
};

/// The points' bounding box; all zero for no points.
Box3 boundingBox(std::span<const Point3> points);

/// Per-vertex normals in the points' frame, not yet unit length: at each
/// vertex the sum of the cross products (b − a) × (c − a) of the triangles
/// around it, which weights each face by its area; zero at a vertex no
/// triangle uses. Triangles are counter-clockwise seen from outside, so the
/// normals point outward (up, for terrain). Indices must be below
/// points.size().
std::vector<Point3> areaWeightedNormals(std::span<const Point3> points,
                                        std::span<const Triangle> triangles);

/// The buffers: positions − origin rounded to float, normals scaled to unit
/// length (+z where a normal is zero), triangles flattened in order. The
/// normals' count must equal the points'.
MeshBuffers meshBuffersAround(std::span<const Point3> points, std::span<const Point3> normals,
                              std::span<const Triangle> triangles, const Point3& origin);

/// The farthest float rounding moves any point − origin (m): each coordinate
/// rounds to the nearest float, within 2⁻²⁴ of its magnitude, so a position
/// moves at most 2⁻²⁴ · |point − origin|. What a plain .glb's positions are
/// exact to, and what Draco's quantization adds to.
double floatRoundingBound(std::span<const Point3> points, const Point3& origin);

}  // namespace tinsmith::encode
