// The domain (see domain.hpp): 0-1 breadth-first crossing depths over the
// triangles, ring edges counting 1.
#include "core/cdt/domain.hpp"

#include <deque>

namespace tinsmith::cdt {
namespace {

/// Per triangle: the fewest half-edges with counts(h) crossed on a way in
/// from outside the hull (0-1 breadth-first search over the triangles).
template <class Counts>
std::vector<std::uint32_t> crossingDepth(const TriangleStore& store, const Counts& counts) {
  const std::uint32_t nt = store.triCount();
  std::vector<std::uint32_t> depth(nt, kNone);
  std::deque<std::uint32_t> dq;
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (store.isGhost(t)) {
      depth[t] = 0;
      dq.push_back(t);
    }
  }
  while (!dq.empty()) {
    const std::uint32_t t = dq.front();
    dq.pop_front();
    for (std::uint32_t i = 0; i < 3; ++i) {
      const std::uint32_t h = 3 * t + i;
      const std::uint32_t n = store.opp[h] / 3;
      const std::uint32_t w = counts(h) ? 1 : 0;
      if (depth[t] + w < depth[n]) {
        depth[n] = depth[t] + w;
        if (w == 0) {
          dq.push_front(n);
        } else {
          dq.push_back(n);
        }
      }
    }
  }
  return depth;
}

}  // namespace

bool Domain::isDomainEdge(const TriangleStore& store, std::uint32_t h, bool boundary) const {
  if (!store.cons[h]) return false;
  for (FeatureId f : store.edgeFeatures.find(edgeKey(store.tv[h], store.tv[nxt(h)]))) {
    if (f < featureRole.size() && featureRole[f] != Role::None) {
      if (!boundary || featureRole[f] == Role::Boundary) return true;
    }
    if (f == kDomainFeature) return true;  // domain edges of a loaded TIN bound it
  }
  return false;
}

std::vector<std::uint8_t> Domain::classify(const TriangleStore& store) const {
  const std::uint32_t nt = store.triCount();
  std::vector<std::uint8_t> inside(nt, 0);
  if (!hasBoundary && !hasHole) {
    for (std::uint32_t t = 0; t < nt; ++t) inside[t] = !store.isGhost(t);
    return inside;
  }
  std::vector<std::uint32_t> enclosing;  // boundary edges crossed
  if (hasBoundary && hasHole) {
    enclosing = crossingDepth(store, [&](std::uint32_t h) { return isDomainEdge(store, h, true); });
  }
  // (Across a hole edge that is no boundary edge the boundary depth is the
  // same on both sides.)
  const std::vector<std::uint32_t> depth = crossingDepth(store, [&](std::uint32_t h) {
    if (!isDomainEdge(store, h)) return false;
    return enclosing.empty() || enclosing[h / 3] > 0 || isDomainEdge(store, h, true);
  });
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (store.isGhost(t)) continue;
    inside[t] = hasBoundary ? (depth[t] % 2 == 1) : (depth[t] % 2 == 0);
  }
  return inside;
}

}  // namespace tinsmith::cdt
