// The domain (see domain.hpp): 0-1 breadth-first crossing depths over the
// triangles, ring edges counting 1.
#include "core/cdt/domain.hpp"

#include <deque>

namespace tinsmith::cdt {
namespace {

/// Per triangle: the fewest half-edges with counts(h) crossed on a way in
/// from outside the hull (0-1 breadth-first search over the triangles).
/// Depths not reached yet.
constexpr std::uint32_t kUnreached = ~std::uint32_t{0};

template <class Counts>
IdVector<TriangleId, std::uint32_t> crossingDepth(const TriangleStore& store,
                                                  const Counts& counts) {
  const std::uint32_t nt = store.triCount();
  IdVector<TriangleId, std::uint32_t> depth(nt, kUnreached);
  std::deque<TriangleId> dq;
  for (std::uint32_t k = 0; k < nt; ++k) {
    const TriangleId t(k);
    if (store.isGhost(t)) {
      depth[t] = 0;
      dq.push_back(t);
    }
  }
  while (!dq.empty()) {
    const TriangleId t = dq.front();
    dq.pop_front();
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId h = halfedgeOf(t, i);
      const TriangleId n = store.neighbour(h);
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

bool Domain::isDomainEdge(const TriangleStore& store, HalfedgeId h, bool boundary) const {
  if (!store.cons[h]) return false;
  for (FeatureId f : store.edgeFeatures.find(edgeKey(store.origin(h), store.origin(nxt(h))))) {
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
    for (std::uint32_t t = 0; t < nt; ++t) inside[t] = !store.isGhost(TriangleId(t));
    return inside;
  }
  IdVector<TriangleId, std::uint32_t> enclosing;  // boundary edges crossed
  if (hasBoundary && hasHole) {
    enclosing = crossingDepth(store, [&](HalfedgeId h) { return isDomainEdge(store, h, true); });
  }
  // (Across a hole edge that is no boundary edge the boundary depth is the
  // same on both sides.)
  const IdVector<TriangleId, std::uint32_t> depth = crossingDepth(store, [&](HalfedgeId h) {
    if (!isDomainEdge(store, h)) return false;
    return enclosing.empty() || enclosing[triangleOf(h)] > 0 || isDomainEdge(store, h, true);
  });
  for (std::uint32_t k = 0; k < nt; ++k) {
    const TriangleId t(k);
    if (store.isGhost(t)) continue;
    inside[k] = hasBoundary ? (depth[t] % 2 == 1) : (depth[t] % 2 == 0);
  }
  return inside;
}

}  // namespace tinsmith::cdt
