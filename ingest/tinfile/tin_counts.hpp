// What a TIN holds and covers: counts, extent and z range. Shared by the
// summary of a .tin file (TinSummary) and the TIN builder's report.
#pragma once

#include <cstddef>

namespace tinsmith::ingest {

struct TinCounts {
  /// constrainedEdges: distinct edges (an edge of several features counts once).
  std::size_t vertices = 0, triangles = 0, constrainedEdges = 0, features = 0;
  double minX = 0, minY = 0, maxX = 0, maxY = 0, minZ = 0, maxZ = 0;
};

}  // namespace tinsmith::ingest
