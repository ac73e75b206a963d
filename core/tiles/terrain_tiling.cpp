#include "core/tiles/terrain_tiling.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/base/error.hpp"
#include "core/geometry/predicates.hpp"
#include "core/tiles/geographic_grid.hpp"

namespace tinsmith::tiles {

namespace {

constexpr int kDeepestLevel = 28;

std::string place(const Point3& p) {
  std::ostringstream s;
  s.precision(10);
  s << "(" << p.x << ", " << p.y << ")";
  return s.str();
}

}  // namespace

void GeographicFrame::toGeodetic(std::span<const Point3> in,
                                 std::span<encode::Geodetic> out) const {
  for (std::size_t i = 0; i < in.size(); ++i)
    out[i] = {in[i].x / kMetresPerDegree, in[i].y / kMetresPerDegree, in[i].z};
}

GeographicTin toGeographicTin(const TinData& tin, const GeoReference& project) {
  std::vector<encode::Geodetic> g(tin.vertices.size());
  project.toGeodetic(tin.vertices, g);
  const auto lonSpan = [&](const TinData::Triangle& t) {
    const double a = g[t[0]].lon, b = g[t[1]].lon, c = g[t[2]].lon;
    return std::max({a, b, c}) - std::min({a, b, c});
  };
  GeographicTin out;
  // A triangle more than half the globe wide in longitude crosses the
  // antimeridian: the frame then starts at Greenwich.
  const bool across = std::any_of(tin.triangles.begin(), tin.triangles.end(),
                                  [&](const auto& t) { return lonSpan(t) > 180.0; });
  if (across) {
    out.west = 0.0;
    for (auto& p : g)
      if (p.lon < 0) p.lon += 360.0;
    for (const auto& t : tin.triangles) {
      if (lonSpan(t) > 180.0) {
        throw geometryError("the TIN's triangle at " + place(tin.vertices[t[0]]) + " in " +
                                tin.crs +
                                " spans more than 180° of longitude (a TIN around a pole)",
                            {}, "cut the TIN short of the pole to tile it as Cesium terrain");
      }
    }
  }
  out.tin.crs = "tinsmith:geographic";
  out.tin.vertices.resize(g.size());
  for (std::size_t i = 0; i < g.size(); ++i)
    out.tin.vertices[i] = {g[i].lon * kMetresPerDegree, g[i].lat * kMetresPerDegree, g[i].height};
  for (const auto& t : tin.triangles) {
    const Point3 &a = out.tin.vertices[t[0]], &b = out.tin.vertices[t[1]],
                 &c = out.tin.vertices[t[2]];
    if (geometry::orient2d(a.x, a.y, b.x, b.y, c.x, c.y) <= 0) {
      throw geometryError("the TIN's triangle at " + place(tin.vertices[t[0]]) + " in " + tin.crs +
                              " folds over in longitude and latitude (a sliver thinner than the "
                              "projection's rounding)",
                          {},
                          "a sliver on the TIN's hull (a DEM's edge): rebuild it with tinsmith tin "
                          "--trim-hull M (M about 3 × the point spacing); near points merged by "
                          "--snap 0.001 mend one inside");
    }
  }
  out.tin.triangles = tin.triangles;
  out.tin.constrainedEdges = tin.constrainedEdges;
  out.tin.features = tin.features;
  return out;
}

PyramidGeometry geographicPyramid(double west) {
  return PyramidGeometry({west * kMetresPerDegree, -90.0 * kMetresPerDegree},
                         360.0 * kMetresPerDegree);
}

std::optional<TileId> geographicTileOf(const TileId& t, double west) {
  if (t.z < 1 || t.y >= (std::uint64_t{1} << (t.z - 1))) return std::nullopt;
  const std::uint64_t columns = std::uint64_t{1} << t.z;
  // The frame's column 0 starts at `west`; the grid's at −180°.
  const auto shift = static_cast<std::uint64_t>(
      std::llround((west + 180.0) / 360.0 * static_cast<double>(columns)));
  return TileId{t.z - 1, static_cast<std::uint32_t>((t.x + shift) % columns), t.y};
}

int terrainLevelFor(double tolerance) {
  int level = 0;
  while (level <= kDeepestLevel && cesiumLevelMaximumGeometricError(level) > tolerance) ++level;
  if (level > kDeepestLevel) {
    throw usageError("a terrain tolerance of " + std::to_string(tolerance) +
                         " m is finer than the deepest level tinsmith tiles (" +
                         std::to_string(kDeepestLevel) + ": " +
                         std::to_string(cesiumLevelMaximumGeometricError(kDeepestLevel)) + " m)",
                     "give a tolerance of at least a millimetre");
  }
  return level;
}

TilerOptions terrainTilerOptions(TilerOptions base, double west, int finestLevel) {
  base.tolerance = cesiumLevelMaximumGeometricError(finestLevel);
  base.fixed = TilerOptions::FixedPyramid{geographicPyramid(west), finestLevel + 1, 1};
  if (!base.maxZoom) base.maxZoom = finestLevel + 1;
  return base;
}

}  // namespace tinsmith::tiles
