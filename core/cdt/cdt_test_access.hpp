// Test-only access to the CDT's internals: the counters and limits that let a
// test check how much work the CDT did, or reach a bound that natural input
// does not. Production code has no use for it.
#pragma once

#include <cstddef>

#include "core/cdt/cdt.hpp"
#include "core/cdt/constraints.hpp"
#include "core/mesh/validate.hpp"

namespace tinsmith {

struct CdtTestAccess {
  /// Bounds how deep reroutes of crossed constraints may nest in cdt's next
  /// finalize() calls (beyond it they throw internalError); the default is
  /// far beyond what input needs.
  static void setRerouteDepthLimit(Cdt& cdt, std::size_t limit);
  /// The deepest nesting of reroutes so far (0: none).
  static std::size_t deepestReroute(const Cdt& cdt);
  /// cdt.validate(options), also giving the steps its constraint-chain
  /// searches took: the adjacency entries they examined (each with an O(1)
  /// look-up of whether its vertex was reached already).
  static ValidationReport validate(const Cdt& cdt, std::size_t& chainSteps,
                                   const ValidationOptions& options = {});
  /// How many crossings of constraints the given step of crossing resolution
  /// placed so far (cdt::CrossingStep, in core/cdt/constraints.hpp).
  static std::size_t crossingsPlacedBy(const Cdt& cdt, cdt::CrossingStep step);
};

}  // namespace tinsmith
