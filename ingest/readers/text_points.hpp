// readers.text: CSV / XYZ text point files (spot heights, survey points).
//
// Format accepted: one point per line, fields separated by comma, semicolon,
// tab or runs of blanks (detected from the first data line unless given);
// '.' is the decimal separator; blank lines and lines starting with '#' are
// skipped; an optional header line names the columns. Coordinates are
// returned exactly as written (no CRS handling here — the caller reprojects).
//
// Column choice, in order: the names/indices in the options; else, with a
// header, the first column named x|easting|east|e|lon|lng|long|longitude
// (x), y|northing|north|n|lat|latitude (y), z|elevation|elev|height|h|alt|
// altitude|ele|ellipsoidal_height (z), case-insensitive, quotes stripped;
// else columns 0, 1, 2.
//
// Throws tinsmith::Error (kind Input) naming the file and the 1-based line:
// missing or unreadable file, a line with too few fields, a field that is not
// a number, NaN or infinity, a named column that does not exist, a file with
// no points.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith::ingest {

enum class TextDelimiter { Auto, Comma, Semicolon, Tab, Whitespace };
enum class TextHeader { Auto, Present, Absent };

struct TextPointOptions {
  TextDelimiter delimiter = TextDelimiter::Auto;
  /// Auto: the first data line is a header when any of its fields is not a number.
  TextHeader header = TextHeader::Auto;
  /// Column names (need a header) — empty: detect from the header (see above).
  std::string xColumn, yColumn, zColumn;
  /// 0-based column indices; override names when set.
  std::optional<int> xIndex, yIndex, zIndex;
  /// When set, the file has only x and y and every point gets this z.
  std::optional<double> fixedZ;
  /// Threads parsing a long file (0: every core); the result is the same for any count.
  unsigned threads = 1;
};

/// A text point file with where each point came from.
struct TextPointTable {
  std::vector<Point3> points;
  std::vector<std::int64_t> lines;                ///< 1-based source line of each point
  TextDelimiter delimiter = TextDelimiter::Auto;  ///< the one used
  bool hasHeader = false;
  std::vector<std::string> columnNames;    ///< from the header, if any
  int xIndex = 0, yIndex = 1, zIndex = 2;  ///< columns used (zIndex -1 with fixedZ)
  bool geographicNames = false;            ///< the header said lon/lat: x, y are degrees
};

/// Reads every point of `path`. See the file comment for format and errors.
TextPointTable readTextPointTable(const std::filesystem::path& path,
                                  const TextPointOptions& options = {});

/// Same, points only.
std::vector<Point3> readTextPoints(const std::filesystem::path& path,
                                   const TextPointOptions& options = {});

/// Reads `path` about `chunkBytes` at a time, cut at line ends, handing each
/// chunk's points to `sink` in the file's order: the file is never whole in
/// memory. The points and errors are readTextPointTable's.
void readTextPointsInChunks(const std::filesystem::path& path, const TextPointOptions& options,
                            std::size_t chunkBytes,
                            const std::function<void(std::span<const Point3>)>& sink);
/// Parses text already in memory; `sourceName` names it in errors.
TextPointTable parseTextPoints(std::string_view text, const std::string& sourceName,
                               const TextPointOptions& options = {});

}  // namespace tinsmith::ingest
