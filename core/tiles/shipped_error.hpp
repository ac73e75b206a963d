// What a tile declares as its error, shared by the 3D Tiles and the
// quantized-mesh encoders (tile_content.hpp, terrain_content.hpp): measured
// on what a client decodes. Internal to core/tiles.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "core/tiles/chord_sag.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

inline double distance(const Point3& a, const Point3& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}
inline Point3 middle(const Point3& a, const Point3& b) {
  return {0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)};
}

/// The edges of triangles, each once (ends a < b packed as a · 2³² + b),
/// ascending; edgeOf finds one.
inline std::vector<std::uint64_t> uniqueEdges(std::span<const std::array<std::uint32_t, 3>> triangles) {
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      const std::uint64_t a = t[i], b = t[(i + 1) % 3];
      edges.push_back(a < b ? a << 32 | b : b << 32 | a);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}
inline std::size_t edgeOf(const std::vector<std::uint64_t>& edges, std::uint64_t a, std::uint64_t b) {
  const std::uint64_t key = a < b ? a << 32 | b : b << 32 | a;
  return static_cast<std::size_t>(std::lower_bound(edges.begin(), edges.end(), key) -
                                  edges.begin());
}

/// The chord sag of each edge of a tile's triangles (uniqueEdges, ascending):
/// the distance, at the edge's middle, between the chord's middle (in
/// `frame`, the exact positions of `project`'s points) and the ground there
/// (the point of the project CRS halfway between the ends, through the
/// georeference). What encoding moves does not change it.
struct EdgeSags {
  std::vector<std::uint64_t> edges;
  std::vector<double> sag;
};
template <class ToFrame>
EdgeSags edgeSags(const TileSurface& tile, std::span<const Point3> project,
                  std::span<const Point3> frame, const GeoReference& geo, const ToFrame& toFrame) {
  EdgeSags out{uniqueEdges(tile.triangles), {}};
  std::vector<Point3> middles(out.edges.size());
  for (std::size_t k = 0; k < out.edges.size(); ++k)
    middles[k] = middle(project[out.edges[k] >> 32], project[out.edges[k] & 0xffffffffU]);
  std::vector<encode::Geodetic> ground(middles.size());
  geo.toGeodetic(middles, ground);
  out.sag.resize(out.edges.size());
  for (std::size_t k = 0; k < out.edges.size(); ++k) {
    out.sag[k] = distance(middle(frame[out.edges[k] >> 32], frame[out.edges[k] & 0xffffffffU]),
                          toFrame(ground[k]));
  }
  return out;
}

/// The error a tile declares (tile_content.hpp, encodeTile): per surface
/// triangle, its measured vertical error, plus the farthest encoding moved
/// one of its corners (`shipped` against `frame`, the exact positions), plus
/// its chord's sag (`sags`, taken over the triangle as the quadratic it is to
/// second order: quadraticGapMax). The largest over the triangles, and over
/// those a refinement can reach (TileRecord). With `shipped` = `frame`, the
/// error before encoding.
struct ShippedError {
  double all = 0.0, reachable = 0.0;
};
inline ShippedError shippedError(const TileSurface& tile, const EdgeSags& sags,
                                 std::span<const Point3> frame, std::span<const Point3> shipped) {
  const bool perTriangle = tile.triangleErrors.size() == tile.triangles.size();
  const bool reach = tile.outOfReach.size() == tile.triangles.size();
  ShippedError worst;
  for (std::size_t t = 0; t < tile.triangles.size(); ++t) {
    const auto& tri = tile.triangles[t];
    double moved = 0.0;
    std::array<double, 3> middles{};
    for (int i = 0; i < 3; ++i) {
      moved = std::max(moved, distance(shipped[tri[i]], frame[tri[i]]));
      middles[i] = sags.sag[edgeOf(sags.edges, tri[i], tri[(i + 1) % 3])];
    }
    const double vertical = perTriangle ? tile.triangleErrors[t] : tile.error;
    const double e = vertical + moved + quadraticGapMax(middles[0], middles[1], middles[2]);
    worst.all = std::max(worst.all, e);
    if (!reach || !tile.outOfReach[t]) worst.reachable = std::max(worst.reachable, e);
  }
  return worst;
}

}  // namespace tinsmith::tiles
