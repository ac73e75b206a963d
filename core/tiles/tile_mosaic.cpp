#include "core/tiles/tile_mosaic.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/base/error.hpp"

namespace tinsmith::tiles {

namespace {

struct VertexKey {
  std::uint64_t x, y;
  friend bool operator==(const VertexKey&, const VertexKey&) = default;
};
struct VertexKeyHash {
  std::size_t operator()(const VertexKey& k) const {
    return std::hash<std::uint64_t>{}(k.x * 0x9e3779b97f4a7c15ULL ^ k.y);
  }
};

/// A coordinate's bits, −0 as +0.
std::uint64_t bitsOf(double v) {
  return std::bit_cast<std::uint64_t>(v + 0.0);
}

}  // namespace

TileMosaic mosaicOf(std::span<const TileSurface> tiles, const std::string& crs) {
  TileMosaic m;
  m.tin.crs = crs;
  m.tin.features = {{FeatureKind::BreakLine, "the tiles' break lines"},
                    {FeatureKind::River, "the tiles' rivers"}};
  std::unordered_map<VertexKey, std::uint32_t, VertexKeyHash> ids;
  for (const TileSurface& t : tiles) {
    if (t.empty()) continue;
    if (t.flags.size() != t.vertices.size() || t.heldEdges.size() != t.triangles.size() ||
        t.riverEdges.size() != t.triangles.size())
      throw internalError("mosaicOf: tile " + t.id.name() + " lacks its flags or held edges");
    m.maxError = std::max(m.maxError, t.error);
    std::vector<std::uint32_t> id(t.vertices.size());
    for (std::size_t v = 0; v < t.vertices.size(); ++v) {
      const Point3& p = t.vertices[v];
      const auto [it, added] = ids.try_emplace({bitsOf(p.x), bitsOf(p.y)},
                                               static_cast<std::uint32_t>(m.tin.vertices.size()));
      if (added) {
        if (m.tin.vertices.size() == UINT32_MAX)
          throw internalError("mosaicOf: more than 2^32 vertices");
        m.tin.vertices.push_back(p);
      } else if (m.tin.vertices[it->second].z != p.z) {
        throw internalError("mosaicOf: tile " + t.id.name() +
                            " and a neighbour disagree on the z of their side vertex at (" +
                            std::to_string(p.x) + ", " + std::to_string(p.y) +
                            "): not the tiles of one Tiler's zoom");
      }
      id[v] = it->second;
    }
    // A held edge that is no tile side lies inside this tile: one triangle
    // of it is a ring's (the domain's boundary), two a line's. By ends,
    // lesser first: its triangles, and whether it is a river's.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, bool>> held;
    for (std::size_t k = 0; k < t.triangles.size(); ++k) {
      const auto& tri = t.triangles[k];
      const TinData::Triangle merged{id[tri[0]], id[tri[1]], id[tri[2]]};
      m.tin.triangles.push_back(merged);
      for (int i = 0; i < 3; ++i) {
        if (!(t.heldEdges[k] & (1U << i))) continue;
        // Both ends on one side of the tile: the edge runs along it.
        if (t.flags[tri[i]] & t.flags[tri[(i + 1) % 3]] & 0xF) continue;
        const std::uint32_t a = merged[i], b = merged[(i + 1) % 3];
        auto& [uses, river] = held[{std::min(a, b), std::max(a, b)}];
        ++uses;
        river = river || (t.riverEdges[k] & (1U << i));
      }
    }
    for (const auto& [edge, use] : held)
      if (use.first >= 2)
        m.tin.constrainedEdges.push_back({edge.first, edge.second, use.second ? 1U : 0U});
  }
  return m;
}

PyramidFrame frameOf(const Tiler& tiler) {
  return {tiler.options(), tiler.geometry(),   tiler.finestZoom(),
          tiler.maxZoom(), tiler.mosaicZoom(), tiler.tin().crs};
}

TilerOptions mosaicTopOptions(const PyramidFrame& frame, int k, int m, std::vector<double> errors) {
  if (m < k || errors.size() != (std::size_t{1} << (2 * m)))
    throw internalError("mosaicTopOptions: " + std::to_string(errors.size()) + " errors for zoom " +
                        std::to_string(m) + ", the top above zoom " + std::to_string(k));
  TilerOptions options = frame.options;
  options.fixed = TilerOptions::FixedPyramid{frame.geometry, frame.finestZoom, k};
  options.maxZoom = frame.maxZoom;
  options.plan.reset();
  options.region.reset();
  options.plannedFinestZoom.reset();
  options.mosaicError = [errors = std::move(errors), m](const TileId& id) {
    const int dz = m - id.z;
    const std::size_t side = std::size_t{1} << m;
    double e = 0;
    for (std::uint32_t y = id.y << dz; y < (id.y + 1) << dz; ++y)
      for (std::uint32_t x = id.x << dz; x < (id.x + 1) << dz; ++x)
        e = std::max(e, errors[y * side + x]);
    return e;
  };
  return options;
}

}  // namespace tinsmith::tiles
