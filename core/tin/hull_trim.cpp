#include "core/tin/hull_trim.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <set>
#include <vector>

namespace tinsmith {

std::size_t trimHull(TinData& tin, double maxEdge) {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const std::size_t nt = tin.triangles.size();
  // Directed edges sorted, so each finds its reverse: half-edge h = 3t + i
  // runs from corner i to corner i + 1 of triangle t.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
  edges.reserve(3 * nt);
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (std::uint32_t i = 0; i < 3; ++i) {
      const std::uint64_t a = tin.triangles[t][i], b = tin.triangles[t][(i + 1) % 3];
      edges.push_back({(a << 32) | b, 3 * t + i});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::uint32_t> twin(3 * nt, kNone);
  for (const auto& [key, h] : edges) {
    const std::uint64_t reverse = (key << 32) | (key >> 32);
    const auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(reverse, 0U));
    if (it != edges.end() && it->first == reverse) twin[h] = it->second;
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> constrained;
  for (const auto& e : tin.constrainedEdges)
    constrained.insert({std::min(e.a, e.b), std::max(e.a, e.b)});
  auto ends = [&](std::uint32_t h) {
    const auto& t = tin.triangles[h / 3];
    return std::array{t[h % 3], t[(h % 3 + 1) % 3]};
  };
  auto isConstrained = [&](std::uint32_t h) {
    const auto [a, b] = ends(h);
    return constrained.count({std::min(a, b), std::max(a, b)}) > 0;
  };
  auto length = [&](std::uint32_t h) {
    const auto [a, b] = ends(h);
    return std::hypot(tin.vertices[b].x - tin.vertices[a].x, tin.vertices[b].y - tin.vertices[a].y);
  };
  std::vector<char> removed(nt, 0);
  std::vector<std::uint32_t> boundaryEdges(tin.vertices.size(), 0);  // per vertex
  std::vector<std::uint32_t> triangles(tin.vertices.size(), 0);      // per vertex
  std::deque<std::uint32_t> queue;
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (std::uint32_t i = 0; i < 3; ++i) {
      ++triangles[tin.triangles[t][i]];
      if (twin[3 * t + i] == kNone) {
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
    int onBoundary = 0;
    std::uint32_t outer = kNone;
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (twin[3 * t + i] == kNone) {
        ++onBoundary;
        outer = 3 * t + i;
      }
    }
    if (onBoundary != 1 || isConstrained(outer) || !(length(outer) > maxEdge)) continue;
    const std::uint32_t apex = tin.triangles[t][(outer % 3 + 2) % 3];
    if (boundaryEdges[apex] > 0 || triangles[apex] < 2) continue;
    removed[t] = 1;
    ++count;
    const auto [a, b] = ends(outer);
    --boundaryEdges[a];
    --boundaryEdges[b];
    for (std::uint32_t v : tin.triangles[t]) --triangles[v];
    // Its two inner edges are now on the boundary.
    for (std::uint32_t h : {3 * t + (outer % 3 + 1) % 3, 3 * t + (outer % 3 + 2) % 3}) {
      const std::uint32_t g = twin[h];
      twin[g] = kNone;
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
      if (twin[3 * t + i] != kNone) continue;
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
