// The CDT's domain (book 6.6): which triangles are inside, from the
// boundary and hole rings among the constraints. Internal to core/cdt.
#pragma once

#include <cstdint>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/triangle_store.hpp"

namespace tinsmith::cdt {

/// What a feature's constraints are to the domain.
enum class Role : std::uint8_t { None, Boundary, Hole };

/// Feature id of the boundary edges of a TIN loaded by Cdt::fromTinData:
/// bounds the domain, never exported.
inline constexpr FeatureId kDomainFeature = 0xfffffffeu;

/// The rings that bound the domain: each feature's role, and whether any
/// boundary (or loaded TIN's edge, kDomainFeature) or hole was given.
struct Domain {
  std::vector<Role> featureRole;  // per feature
  bool hasBoundary = false, hasHole = false;

  /// Does half-edge h of `store` carry a domain ring: any boundary or hole
  /// (`boundary` false), or a boundary (`boundary` true)?
  [[nodiscard]] bool isDomainEdge(const TriangleStore& store, HalfedgeId h,
                                  bool boundary = false) const;
  /// Per triangle of `store`: inside the domain (1) or not (0). Without rings,
  /// every finite triangle is inside; else crossing-count parity from the
  /// outside, rings nesting by parity. With a boundary, hole edges count only
  /// inside some boundary ring: a hole outside every boundary (or the part of
  /// one that is) bounds nothing. Ghosts are never inside.
  [[nodiscard]] std::vector<std::uint8_t> classify(const TriangleStore& store) const;
};

}  // namespace tinsmith::cdt
