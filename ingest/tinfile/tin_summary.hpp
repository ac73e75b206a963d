// A description of a TIN for `tinsmith info`: CRS, counts, extent, z range,
// features and constrained edges per kind. Text and JSON render the same.
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/tinfile/tin_counts.hpp"

namespace tinsmith::ingest {

struct TinSummary : TinCounts {
  std::string file;
  std::size_t fileBytes = 0;
  std::uint32_t formatVersion = 0;  ///< the file's (readTinFileHeader)
  std::string crs;
  bool empty = true;  ///< no vertices: extent and z range are meaningless
  double area = 0;    ///< sum of triangle areas in x, y (square metres)
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
/// The counts and extents of summariseTin(mesh), without the area (a pass
/// over every triangle).
TinCounts countTin(const Mesh& mesh);

}  // namespace tinsmith::ingest
