// A description of a TIN for `tinsmith info`: CRS, counts, extent, z range,
// features and constrained edges per kind. Text and JSON render the same.
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

struct TinSummary {
  std::string file;
  std::size_t fileBytes = 0;
  std::string crs;
  /// constrainedEdges: distinct edges (an edge of several features counts once).
  std::size_t vertices = 0, triangles = 0, constrainedEdges = 0, features = 0;
  bool empty = true;  ///< no vertices: extent and z range are meaningless
  double minX = 0, minY = 0, maxX = 0, maxY = 0, minZ = 0, maxZ = 0;
  double area = 0;  ///< sum of triangle areas in x, y (square metres)
  struct PerKind {
    std::size_t features = 0;
    std::size_t edges = 0;  ///< constrained edges carrying a feature of this kind
  };
  std::map<std::string, PerKind> kinds;  ///< by featureKindName

  [[nodiscard]] std::string text() const;
  [[nodiscard]] std::string json() const;  ///< pretty-printed, ends with a newline
};

TinSummary summariseTin(const TinData& tin);
/// The same as summariseTin(mesh.toTinData()), without the copy.
TinSummary summariseTin(const Mesh& mesh);

}  // namespace tinsmith::ingest
