#include "core/tiles/terrain_content.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/base/error.hpp"
#include "core/encode/quantized_mesh.hpp"
#include "core/tiles/geographic_grid.hpp"
#include "core/tiles/shipped_error.hpp"
#include "core/tiles/terrain_fill.hpp"
#include "core/tiles/terrain_tiling.hpp"

namespace tinsmith::tiles {

std::vector<std::uint8_t> waterMask(const Rect& rect, const std::vector<TerrainLine>& lakes) {
  constexpr int kSize = 256;
  std::vector<const TerrainLine*> near;
  for (const auto& lake : lakes)
    if (lake.closed && lake.points.size() >= 3 && boundsOf(lake.points).overlaps(rect))
      near.push_back(&lake);
  std::vector<std::uint8_t> mask(kSize * kSize, 0);
  if (!near.empty()) {
    std::vector<double> crossings;
    for (int row = 0; row < kSize; ++row) {
      // Even–odd along the row: where the shores cross the row's centre line.
      const double y = rect.y1 - (row + 0.5) / kSize * rect.height();
      crossings.clear();
      for (const TerrainLine* lake : near) {
        const auto& p = lake->points;
        for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
          if ((p[i].y > y) != (p[j].y > y))
            crossings.push_back(p[i].x + (y - p[i].y) / (p[j].y - p[i].y) * (p[j].x - p[i].x));
        }
      }
      std::sort(crossings.begin(), crossings.end());
      for (int col = 0; col < kSize; ++col) {
        const double x = rect.x0 + (col + 0.5) / kSize * rect.width();
        const auto left =
            std::lower_bound(crossings.begin(), crossings.end(), x) - crossings.begin();
        if (left % 2 == 1) mask[static_cast<std::size_t>(row * kSize + col)] = 255;
      }
    }
  }
  if (std::all_of(mask.begin(), mask.end(), [&](std::uint8_t m) { return m == mask[0]; }))
    return {mask[0]};
  return mask;
}

TileContent encodeTerrainTile(const TileSurface& surface, const TileId& id,
                              const PyramidGeometry& geometry, const TerrainTileOptions& options) {
  if (!geographicTileOf(id, options.west))
    throw internalError("encodeTerrainTile: " + id.name() + " is no tile of the geographic grid");
  const Rect rect = geometry.bounds(id);
  const TerrainFill fill = fillOutsideSurface(surface, rect, fillSegmentsForLevel(id.z - 1));

  // One numbering: the surface's vertices, then the fill's.
  TileSurface measured;
  measured.id = id;
  measured.vertices = surface.vertices;
  measured.vertices.insert(measured.vertices.end(), fill.vertices.begin(), fill.vertices.end());
  measured.triangles = surface.triangles;
  measured.triangles.insert(measured.triangles.end(), fill.triangles.begin(), fill.triangles.end());
  measured.error = surface.error;
  measured.triangleErrors = surface.triangleErrors;
  measured.triangleErrors.resize(surface.triangles.size(), surface.error);
  measured.triangleErrors.resize(measured.triangles.size(), 0.0);
  measured.outOfReach = surface.outOfReach;
  measured.outOfReach.resize(measured.triangles.size(), 0);

  encode::GeodeticMesh mesh;
  mesh.west = rect.x0 / kMetresPerDegree;
  mesh.east = rect.x1 / kMetresPerDegree;
  mesh.south = rect.y0 / kMetresPerDegree;
  mesh.north = rect.y1 / kMetresPerDegree;
  const GeographicFrame frame;
  mesh.vertices.resize(measured.vertices.size());
  frame.toGeodetic(measured.vertices, mesh.vertices);
  mesh.triangles = measured.triangles;
  mesh.shadingTriangles = mesh.triangles.size();  // a wall's foot is lit as the ground
  mesh.triangles.insert(mesh.triangles.end(), fill.walls.begin(), fill.walls.end());
  encode::QuantizedTerrain q = encode::quantizeTerrain(mesh);

  std::vector<Point3> ecef(mesh.vertices.size());
  for (std::size_t i = 0; i < ecef.size(); ++i) ecef[i] = encode::geodeticToEcef(mesh.vertices[i]);
  const auto toEcef = [](const encode::Geodetic& g) { return encode::geodeticToEcef(g); };
  const ShippedError error = shippedError(
      measured, edgeSags(measured, measured.vertices, ecef, frame, toEcef), ecef, q.decoded);

  TileRecord record;
  record.id = id;
  record.error = error.all;
  record.reachableError = error.reachable;
  constexpr double kRadian = std::numbers::pi / 180.0;
  const GeoRect g = geographicTileBounds(*geographicTileOf(id, options.west));
  record.region = {g.west * kRadian,  g.south * kRadian, g.east * kRadian,
                   g.north * kRadian, q.tile.minHeight,  q.tile.maxHeight};
  record.vertices = q.tile.u.size();
  record.triangles = q.tile.triangles.size();
  record.breakLineVertices = surface.breakLineVertices;
  record.positionErrorBound = q.maxMove;
  q.tile.waterMask = options.lakes ? waterMask(rect, *options.lakes) : std::vector<std::uint8_t>{0};
  // The metadata names the tile as a client does: its grid tile.
  TileRecord shipped = record;
  shipped.id = *geographicTileOf(id, options.west);
  q.tile.metadata = recordToJson(shipped);
  TileContent content{encode::encodeQuantizedMesh(q.tile), record};
  content.record.bytes = content.glb.size();
  return content;
}

std::optional<TileRecord> recordFromTerrainTile(std::string_view bytes) {
  try {
    const auto json = encode::quantizedMeshMetadata(bytes);
    if (!json) return std::nullopt;
    return recordFromExtras(*json);
  } catch (const Error&) {
    return std::nullopt;
  }
}

}  // namespace tinsmith::tiles
