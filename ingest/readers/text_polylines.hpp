// readers.polylines: break lines as plain text, for `tinsmith tin --breaklines`.
//
// Format: one vertex per line, "x y z" (separated by blanks, tabs or commas);
// a blank line ends a polyline; lines starting with '#' are comments (they do
// not end a polyline). A polyline whose last vertex repeats its first exactly
// is a closed ring (stored without the repeat). Coordinates as written, in
// the TIN's CRS, metres.
//
//   # ridge line
//   431000.0 4512000.0 1601.5
//   431020.0 4512011.5 1603.0
//
//   431100.0 4512100.0 1590.0
//   ...
//
// Throws inputError naming the file and the 1-based line: a missing file, a
// vertex line without exactly three numbers, NaN or infinity, a polyline of a
// single vertex, a file without any polyline.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith::ingest {

struct TextPolyline {
  std::vector<Point3> vertices;
  bool closed = false;
  std::int64_t firstLine = 0;  ///< 1-based line of its first vertex
};

std::vector<TextPolyline> readTextPolylines(const std::filesystem::path& path);
std::vector<TextPolyline> parseTextPolylines(std::string_view text, const std::string& sourceName);

}  // namespace tinsmith::ingest
