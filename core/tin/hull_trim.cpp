#include "core/tin/hull_trim.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

#include "core/mesh/mesh.hpp"

namespace tinsmith {

std::size_t trimHull(TinData& tin, double maxEdge) {
  // The mesh's twins and constraint flags; half-edge 3t + i runs from corner
  // i to corner i + 1 of triangle t, as in TinData. An edge is on the
  // boundary when it has no twin or its twin's triangle was removed.
  const Mesh mesh = Mesh::fromTinData(tin);
  const std::size_t nt = tin.triangles.size();
  std::vector<char> removed(nt, 0);
  auto onBoundary = [&](std::uint32_t h) {
    const HalfedgeId g = mesh.twin(HalfedgeId(h));
    return !g.valid() || removed[Mesh::triangle(g).value];
  };
  auto ends = [&](std::uint32_t h) {
    const auto& t = tin.triangles[h / 3];
    return std::array{t[h % 3], t[(h % 3 + 1) % 3]};
  };
  auto length = [&](std::uint32_t h) {
    const auto [a, b] = ends(h);
    return std::hypot(tin.vertices[b].x - tin.vertices[a].x, tin.vertices[b].y - tin.vertices[a].y);
  };
  std::vector<std::uint32_t> boundaryEdges(tin.vertices.size(), 0);  // per vertex
  std::vector<std::uint32_t> triangles(tin.vertices.size(), 0);      // per vertex
  std::deque<std::uint32_t> queue;
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (std::uint32_t i = 0; i < 3; ++i) {
      ++triangles[tin.triangles[t][i]];
      if (onBoundary(3 * t + i)) {
        ++boundaryEdges[tin.triangles[t][i]];
        queue.push_back(t);
      }
    }
  }
  std::size_t count = 0;
  while (!queue.empty()) {
    const std::uint32_t t = queue.front();
    queue.pop_front();
    if (removed[t]) continue;
    int boundaryCount = 0;
    std::uint32_t outer = 0;
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (onBoundary(3 * t + i)) {
        ++boundaryCount;
        outer = 3 * t + i;
      }
    }
    if (boundaryCount != 1 || mesh.isConstrained(HalfedgeId(outer)) || !(length(outer) > maxEdge))
      continue;
    const std::uint32_t apex = tin.triangles[t][(outer % 3 + 2) % 3];
    if (boundaryEdges[apex] > 0 || triangles[apex] < 2) continue;
    removed[t] = 1;  // before its inner edges are asked: they are on the boundary now
    ++count;
    const auto [a, b] = ends(outer);
    --boundaryEdges[a];
    --boundaryEdges[b];
    for (std::uint32_t v : tin.triangles[t]) --triangles[v];
    // Its two inner edges are now on the boundary.
    for (std::uint32_t h : {3 * t + (outer % 3 + 1) % 3, 3 * t + (outer % 3 + 2) % 3}) {
      const std::uint32_t g = mesh.twin(HalfedgeId(h)).value;
      const auto [u, w] = ends(g);
      ++boundaryEdges[u];
      ++boundaryEdges[w];
      queue.push_back(g / 3);
    }
  }
  if (count == 0) return 0;
  // The trimmed boundary: a new feature's constrained edges.
  const auto feature = static_cast<std::uint32_t>(tin.features.size());
  tin.features.push_back({FeatureKind::Boundary,
                          "hull trimmed of edges longer than " + std::to_string(maxEdge) + " m"});
  std::vector<TinData::ConstrainedEdge> added;
  std::vector<TinData::Triangle> kept;
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (removed[t]) continue;
    kept.push_back(tin.triangles[t]);
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (!onBoundary(3 * t + i)) continue;
      const auto [a, b] = ends(3 * t + i);
      added.push_back({std::min(a, b), std::max(a, b), feature});
    }
  }
  // Every boundary edge, so the feature's rings are closed.
  std::sort(added.begin(), added.end(),
            [](const TinData::ConstrainedEdge& x, const TinData::ConstrainedEdge& y) {
              return x.a < y.a || (x.a == y.a && x.b < y.b);
            });
  tin.constrainedEdges.insert(tin.constrainedEdges.end(), added.begin(), added.end());
  tin.triangles = std::move(kept);
  return count;
}

}  // namespace tinsmith
