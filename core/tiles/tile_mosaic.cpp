#include "core/tiles/tile_mosaic.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <map>
#include <tuple>
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

}  // namespace

TileMosaic mosaicOf(std::span<const TileSurface> tiles, const std::string& crs) {
  TileMosaic m;
  m.tin.crs = crs;
  m.tin.features = {{FeatureKind::BreakLine, "the tiles' break lines"},
                    {FeatureKind::River, "the tiles' rivers"}};
  std::unordered_map<VertexKey, std::uint32_t, VertexKeyHash> ids;
  // Held edges that are no tile side, by their ends (lesser first): a river?
  std::map<std::pair<std::uint32_t, std::uint32_t>, bool> held;
  // How many triangles each undirected edge has: one is the mosaic's boundary.
  std::unordered_map<std::uint64_t, int> uses;
  const auto edgeKey = [](std::uint32_t a, std::uint32_t b) {
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
  };
  for (const TileSurface& t : tiles) {
    if (t.empty()) continue;
    m.maxError = std::max(m.maxError, t.error);
    std::vector<std::uint32_t> id(t.vertices.size());
    for (std::size_t v = 0; v < t.vertices.size(); ++v) {
      const Point3& p = t.vertices[v];
      const auto [it, added] =
          ids.try_emplace({std::bit_cast<std::uint64_t>(p.x), std::bit_cast<std::uint64_t>(p.y)},
                          static_cast<std::uint32_t>(m.tin.vertices.size()));
      if (added) {
        if (m.tin.vertices.size() == UINT32_MAX)
          throw internalError("mosaicOf: more than 2^32 vertices");
        m.tin.vertices.push_back(p);
      } else if (m.tin.vertices[it->second].z != p.z) {
        ++m.mismatchedVertices;
      }
      id[v] = it->second;
    }
    for (std::size_t k = 0; k < t.triangles.size(); ++k) {
      const auto& tri = t.triangles[k];
      const TinData::Triangle merged{id[tri[0]], id[tri[1]], id[tri[2]]};
      m.tin.triangles.push_back(merged);
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t a = merged[i], b = merged[(i + 1) % 3];
        ++uses[edgeKey(a, b)];
        if (!(t.heldEdges[k] & (1U << i))) continue;
        // Both ends on one side of the tile: the edge runs along it.
        if (t.flags[tri[i]] & t.flags[tri[(i + 1) % 3]] & 0xF) continue;
        const bool river = t.riverEdges[k] & (1U << i);
        auto [e, added] = held.try_emplace({std::min(a, b), std::max(a, b)}, river);
        if (!added) e->second = e->second || river;
      }
    }
  }
  for (const auto& [edge, river] : held) {
    if (uses[edgeKey(edge.first, edge.second)] < 2) continue;  // a ring's: the boundary
    m.tin.constrainedEdges.push_back({edge.first, edge.second, river ? 1U : 0U});
  }
  return m;
}

}  // namespace tinsmith::tiles
