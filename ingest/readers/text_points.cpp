#include "ingest/readers/text_points.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <string_view>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"

namespace tinsmith::ingest {
namespace {

SourceLocation atLine(const std::string& file, std::optional<std::int64_t> line = std::nullopt) {
  SourceLocation where;
  where.file = file;
  where.line = line;
  return where;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::string_view unquote(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) {
    s = s.substr(1, s.size() - 2);
  }
  return trim(s);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Splits `line` into fields; returns the count. Fields are views into `line`.
void splitFields(std::string_view line, TextDelimiter delimiter,
                 std::vector<std::string_view>& out) {
  out.clear();
  if (delimiter == TextDelimiter::Whitespace) {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      if (i >= line.size()) break;
      const std::size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
      out.push_back(line.substr(start, i - start));
    }
    return;
  }
  const char sep = delimiter == TextDelimiter::Comma       ? ','
                   : delimiter == TextDelimiter::Semicolon ? ';'
                                                           : '\t';
  std::size_t start = 0;
  while (true) {
    const std::size_t pos = line.find(sep, start);
    if (pos == std::string_view::npos) {
      out.push_back(trim(line.substr(start)));
      break;
    }
    out.push_back(trim(line.substr(start, pos - start)));
    start = pos + 1;
  }
  // A trailing separator leaves an empty last field; drop it.
  if (!out.empty() && out.back().empty()) out.pop_back();
}

TextDelimiter detectDelimiter(std::string_view line) {
  if (line.find('\t') != std::string_view::npos &&
      line.find_first_not_of(" \t\r") != std::string_view::npos) {
    // Tabs with other separators around: a tab-separated file.
    if (line.find(',') == std::string_view::npos && line.find(';') == std::string_view::npos) {
      return TextDelimiter::Tab;
    }
  }
  if (line.find(';') != std::string_view::npos) return TextDelimiter::Semicolon;
  if (line.find(',') != std::string_view::npos) return TextDelimiter::Comma;
  if (line.find('\t') != std::string_view::npos) return TextDelimiter::Tab;
  return TextDelimiter::Whitespace;
}

enum class NumberStatus { Ok, NotANumber, NonFinite };

NumberStatus parseNumber(std::string_view field, double& value) {
  field = unquote(field);
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return NumberStatus::NotANumber;
  const auto* first = field.data();
  const auto* last = field.data() + field.size();
  const auto result = std::from_chars(first, last, value);
  if (result.ec != std::errc() || result.ptr != last) {
    // from_chars reports out-of-range for huge values: treat as non-finite.
    if (result.ec == std::errc::result_out_of_range) return NumberStatus::NonFinite;
    return NumberStatus::NotANumber;
  }
  return std::isfinite(value) ? NumberStatus::Ok : NumberStatus::NonFinite;
}

int findColumn(const std::vector<std::string>& names,
               std::initializer_list<std::string_view> candidates) {
  for (const auto candidate : candidates) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == candidate) return static_cast<int>(i);
    }
  }
  return -1;
}

int namedColumn(const std::vector<std::string>& names, const std::string& wanted, const char* role,
                const std::string& sourceName, std::int64_t headerLine) {
  const auto key = lower(wanted);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == key) return static_cast<int>(i);
  }
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw inputError(
      std::string(role) + " column '" + wanted + "' is not in the header (" + list + ")",
      atLine(sourceName, headerLine), "name a column that exists");
}

const char* delimiterName(TextDelimiter d) {
  switch (d) {
    case TextDelimiter::Comma:
      return "comma";
    case TextDelimiter::Semicolon:
      return "semicolon";
    case TextDelimiter::Tab:
      return "tab";
    case TextDelimiter::Whitespace:
      return "whitespace";
    case TextDelimiter::Auto:
      return "auto";
  }
  return "?";
}

}  // namespace

namespace {

/// The columns chosen from the first data line (and the header, if any).
struct Columns {
  int x = 0, y = 1, z = 2;  ///< z is -1 with a fixed z
  int needed = 0;           ///< fields a data line must have
};

/// Reads the first content line: the delimiter, whether it is a header, the
/// columns. Returns whether the line is a header (else it holds data).
bool setUpColumns(std::string_view line, std::int64_t lineNo, const std::string& sourceName,
                  const TextPointOptions& options, TextPointTable& table, Columns& c) {
  std::vector<std::string_view> fields;
  int xi = 0, yi = 1, zi = options.fixedZ ? -1 : 2;
  if (table.delimiter == TextDelimiter::Auto) table.delimiter = detectDelimiter(line);
  splitFields(line, table.delimiter, fields);
  bool isHeader = false;
  if (options.header == TextHeader::Present) {
    isHeader = true;
  } else if (options.header == TextHeader::Auto) {
    double dummy = 0.0;
    isHeader = std::any_of(fields.begin(), fields.end(), [&](std::string_view f) {
      return parseNumber(f, dummy) == NumberStatus::NotANumber;
    });
  }
  if (isHeader) {
    table.hasHeader = true;
    for (const auto f : fields) table.columnNames.push_back(lower(unquote(f)));
    const auto& n = table.columnNames;
    const int gx = findColumn(n, {"lon", "lng", "long", "longitude"});
    const int gy = findColumn(n, {"lat", "latitude"});
    const int px = findColumn(n, {"x", "easting", "east", "e"});
    const int py = findColumn(n, {"y", "northing", "north", "n"});
    const int pz = findColumn(n, {"z", "elevation", "elev", "height", "h", "alt", "altitude",
                                  "ele", "ellipsoidal_height", "ortho_height"});
    if (px >= 0 && py >= 0) {
      xi = px;
      yi = py;
    } else if (gx >= 0 && gy >= 0) {
      xi = gx;
      yi = gy;
      table.geographicNames = true;
    }
    if (!options.fixedZ && pz >= 0) zi = pz;
    if (!options.xColumn.empty()) xi = namedColumn(n, options.xColumn, "x", sourceName, lineNo);
    if (!options.yColumn.empty()) yi = namedColumn(n, options.yColumn, "y", sourceName, lineNo);
    if (!options.zColumn.empty()) zi = namedColumn(n, options.zColumn, "z", sourceName, lineNo);
  } else if (!options.xColumn.empty() || !options.yColumn.empty() || !options.zColumn.empty()) {
    throw inputError("columns are chosen by name but the file has no header line",
                     atLine(sourceName, lineNo), "add a header line or choose columns by index");
  }
  if (options.xIndex) xi = *options.xIndex;
  if (options.yIndex) yi = *options.yIndex;
  if (options.zIndex && !options.fixedZ) zi = *options.zIndex;
  if (xi < 0 || yi < 0 || (zi < 0 && !options.fixedZ)) {
    throw inputError("a column index is negative", atLine(sourceName, lineNo));
  }
  if (xi == yi || xi == zi || yi == zi) {
    throw inputError("x, y and z must be different columns (got " + std::to_string(xi) + ", " +
                         std::to_string(yi) + ", " + std::to_string(zi) + ")",
                     atLine(sourceName, lineNo), "name the columns in the layer's options");
  }
  table.xIndex = c.x = xi;
  table.yIndex = c.y = yi;
  table.zIndex = c.z = zi;
  c.needed = std::max({xi, yi, zi}) + 1;
  return isHeader;
}

/// The common line parsed in one scan: plain, unquoted numbers in the wanted
/// columns of a whitespace-, comma- or semicolon-separated line (trimmed).
/// Returns false when it meets anything else — a quote, a '+', a short line,
/// a field that is not all number, a value that is not finite, a tab-separated
/// file — and the caller takes the general path, which accepts exactly what
/// this accepts, with the same values, and words the errors.
bool parsePlainLine(std::string_view line, TextDelimiter delimiter, const Columns& c, Point3& p) {
  if (delimiter == TextDelimiter::Tab || delimiter == TextDelimiter::Auto) return false;
  const bool blankSeparated = delimiter == TextDelimiter::Whitespace;
  const char sep = delimiter == TextDelimiter::Comma ? ',' : ';';
  auto blank = [](char ch) { return ch == ' ' || ch == '\t' || ch == '\r'; };
  const char* s = line.data();
  const char* const end = s + line.size();
  const int want = c.z < 0 ? 2 : 3;
  int found = 0;
  for (int field = 0; found < want; ++field) {
    while (s < end && blank(*s)) ++s;  // between fields, or a field's leading blanks
    if (s == end && blankSeparated) return false;
    double* target = field == c.x ? &p.x : field == c.y ? &p.y : field == c.z ? &p.z : nullptr;
    if (target) {
      if (s == end || *s == '"' || *s == '\'' || *s == '+') return false;
      const auto r = std::from_chars(s, end, *target);
      if (r.ec != std::errc() || !std::isfinite(*target)) return false;
      s = r.ptr;
      ++found;
      if (blankSeparated) {
        if (s < end && !blank(*s)) return false;
      } else {
        while (s < end && blank(*s)) ++s;
        if (s < end && *s != sep) return false;
      }
    } else if (blankSeparated) {
      while (s < end && !blank(*s)) ++s;
    } else {
      while (s < end && *s != sep) ++s;
    }
    if (!blankSeparated) {
      if (s == end && found < want) return false;
      ++s;  // past the separator
    }
  }
  return true;
}

/// The data lines of `text`, whose first line is line `firstLine` of the
/// file: appends their points and line numbers. Returns the number of lines
/// (counting blank and comment lines). Throws on the first bad line.
std::int64_t parseDataLines(std::string_view text, std::int64_t firstLine,
                            const std::string& sourceName, const TextPointOptions& options,
                            TextDelimiter delimiter, const Columns& c,
                            std::vector<Point3>& points, std::vector<std::int64_t>& lines) {
  std::vector<std::string_view> fields;
  const std::array<const char*, 3> role{"x", "y", "z"};
  std::int64_t lineNo = firstLine - 1;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = trim(text.substr(pos, end - pos));
    pos = end + 1;
    ++lineNo;
    if (line.empty() || line.front() == '#') continue;
    Point3 p;
    if (parsePlainLine(line, delimiter, c, p)) {
      if (options.fixedZ) p.z = *options.fixedZ;
      points.push_back(p);
      lines.push_back(lineNo);
      continue;
    }
    splitFields(line, delimiter, fields);
    if (static_cast<int>(fields.size()) < c.needed) {
      throw inputError("expected at least " + std::to_string(c.needed) + " " +
                           delimiterName(delimiter) + "-separated fields, found " +
                           std::to_string(fields.size()),
                       atLine(sourceName, lineNo), "fix or remove the line");
    }
    const std::array<std::pair<int, double*>, 3> wanted{{{c.x, &p.x}, {c.y, &p.y}, {c.z, &p.z}}};
    for (std::size_t k = 0; k < 3; ++k) {
      if (wanted[k].first < 0) continue;
      const auto field = fields[static_cast<std::size_t>(wanted[k].first)];
      const auto status = parseNumber(field, *wanted[k].second);
      if (status == NumberStatus::NotANumber) {
        throw inputError(
            std::string(role[k]) + " value '" + std::string(field) + "' is not a number",
            atLine(sourceName, lineNo), "use plain decimal numbers with '.' as the decimal point");
      }
      if (status == NumberStatus::NonFinite) {
        throw inputError(std::string(role[k]) + " value '" + std::string(field) +
                             "' is not finite (NaN or infinity)",
                         atLine(sourceName, lineNo), "remove the point or give it a real value");
      }
    }
    if (options.fixedZ) p.z = *options.fixedZ;
    points.push_back(p);
    lines.push_back(lineNo);
  }
  return lineNo - firstLine + 1;
}

/// Texts shorter than this are parsed on the calling thread.
constexpr std::size_t kParallelBytes = std::size_t{1} << 20;
/// The pieces a long text is cut into (at line ends) for parallel parsing.
constexpr unsigned kPieces = 32;

/// Where the line holding offset `at` - 1 ends, plus one: the start of the
/// first line that begins at or after `at` (0 for 0; text.size() if none).
std::size_t nextLineStart(std::string_view text, std::size_t at) {
  if (at == 0) return 0;
  const std::size_t nl = text.find('\n', at - 1);
  return nl == std::string_view::npos ? text.size() : nl + 1;
}

}  // namespace

namespace {

/// Parsing a text that comes in chunks cut at line ends: the columns, once
/// found, and the lines parsed so far.
struct TextChunkParser {
  TextPointTable& table;  // the columns found; points and lines appended here
  const std::string& sourceName;
  const TextPointOptions& options;
  Columns columns;
  std::int64_t lineNo = 0;  // lines parsed so far
  bool columnsFound = false;

  void parse(std::string_view text) {
    // Up to the first content line: the columns; the data lines after it.
    std::size_t pos = 0;
    if (!columnsFound && lineNo == 0 && text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF")
      pos = 3;  // a UTF-8 byte-order mark
    while (!columnsFound && pos < text.size()) {
      std::size_t end = text.find('\n', pos);
      if (end == std::string_view::npos) end = text.size();
      const std::string_view line = trim(text.substr(pos, end - pos));
      ++lineNo;
      if (!line.empty() && line.front() != '#') {
        columnsFound = true;
        if (setUpColumns(line, lineNo, sourceName, options, table, columns))
          pos = end + 1;  // a header: the data starts on the next line
        else
          --lineNo;  // data: this line is the data's first
        break;
      }
      pos = end + 1;
    }
    if (columnsFound && pos < text.size()) parseData(text.substr(pos));
  }

  // The data in pieces cut at line ends, parsed in parallel with line numbers
  // counted from each piece's start, then joined in order. A piece that fails
  // is parsed again from its true first line, so the error (the first in the
  // file: pieces before it parsed cleanly) names the right line.
  void parseData(std::string_view data) {
    struct Piece {
      std::size_t begin = 0, end = 0;
      std::vector<Point3> points;
      std::vector<std::int64_t> lines;
      std::int64_t lineCount = 0;
      bool failed = false;
    };
    const unsigned pieces = data.size() < kParallelBytes ? 1 : kPieces;
    std::vector<Piece> parts(pieces);
    parallelParts(
        data.size(), pieces, resolveThreads(options.threads),
        [&](std::size_t b, std::size_t e, unsigned k) {
          Piece& piece = parts[k];
          piece.begin = nextLineStart(data, b);
          piece.end = std::max(piece.begin, nextLineStart(data, e));
          const std::string_view slice = data.substr(piece.begin, piece.end - piece.begin);
          piece.points.reserve(slice.size() / 24);
          piece.lines.reserve(slice.size() / 24);
          try {
            piece.lineCount = parseDataLines(slice, 1, sourceName, options, table.delimiter,
                                             columns, piece.points, piece.lines);
          } catch (const Error&) {
            piece.failed = true;
          }
        });
    std::size_t total = 0;
    for (const Piece& piece : parts) total += piece.points.size();
    table.points.reserve(table.points.size() + total);
    table.lines.reserve(table.lines.size() + total);
    for (Piece& piece : parts) {
      const std::int64_t firstLine = lineNo + 1;
      if (piece.failed) {
        std::vector<Point3> points;
        std::vector<std::int64_t> lines;
        parseDataLines(data.substr(piece.begin, piece.end - piece.begin), firstLine, sourceName,
                       options, table.delimiter, columns, points, lines);
        throw internalError("a text point piece failed once and parsed cleanly the second time");
      }
      table.points.insert(table.points.end(), piece.points.begin(), piece.points.end());
      for (const std::int64_t l : piece.lines) table.lines.push_back(l + lineNo);
      lineNo += piece.lineCount;
      std::vector<Point3>().swap(piece.points);
      std::vector<std::int64_t>().swap(piece.lines);
    }
  }
};

void throwNoPoints(const std::string& sourceName) {
  throw inputError("the file holds no points", atLine(sourceName),
                   "check the file and its delimiter");
}

/// The file opened for reading, or the error readTextPointTable gives.
std::ifstream openTextFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw inputError("file not found", atLine(path.string()),
                     "check the path (relative paths are taken from the config file's folder)");
  }
  if (std::filesystem::is_directory(path, ec)) {
    throw inputError("is a directory, not a point file", atLine(path.string()));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw inputError("cannot open the file for reading", atLine(path.string()),
                     "check its permissions");
  return in;
}

void refuseBinary(std::string_view text, const std::filesystem::path& path) {
  if (text.find('\0') != std::string_view::npos) {
    throw inputError("is not a text file (it contains NUL bytes)", atLine(path.string()),
                     "give a CSV/XYZ text file, or a GIS file in an OGR format");
  }
}

}  // namespace

TextPointTable parseTextPoints(std::string_view text, const std::string& sourceName,
                               const TextPointOptions& options) {
  TextPointTable table;
  table.delimiter = options.delimiter;
  TextChunkParser parser{table, sourceName, options, {}, 0, false};
  parser.parse(text);
  if (table.points.empty()) throwNoPoints(sourceName);
  return table;
}

void readTextPointsInChunks(const std::filesystem::path& path, const TextPointOptions& options,
                            std::size_t chunkBytes,
                            const std::function<void(std::span<const Point3>)>& sink) {
  std::ifstream in = openTextFile(path);
  const std::string name = path.string();
  TextPointTable table;
  table.delimiter = options.delimiter;
  TextChunkParser parser{table, name, options, {}, 0, false};
  std::string buffer;
  std::string carry;  // the last chunk's unfinished line
  bool any = false;
  chunkBytes = std::max<std::size_t>(chunkBytes, 1);
  while (true) {
    buffer.assign(carry);
    const std::size_t have = buffer.size();
    buffer.resize(have + chunkBytes);
    in.read(buffer.data() + have, static_cast<std::streamsize>(chunkBytes));
    buffer.resize(have + static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw inputError("cannot read the file", atLine(name), "check its permissions");
    const bool last = !in;
    std::size_t cut = buffer.size();
    if (!last) {
      const std::size_t nl = buffer.rfind('\n');
      cut = nl == std::string::npos ? 0 : nl + 1;
    }
    carry.assign(buffer, cut);
    buffer.resize(cut);
    refuseBinary(buffer, path);
    parser.parse(buffer);
    if (!table.points.empty()) {
      any = true;
      sink(table.points);
      table.points.clear();
      table.lines.clear();
    }
    if (last) break;
  }
  if (!any) throwNoPoints(name);
}

TextPointTable readTextPointTable(const std::filesystem::path& path,
                                  const TextPointOptions& options) {
  std::ifstream in = openTextFile(path);
  std::string text;
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size > 0) {
    text.resize(static_cast<std::size_t>(size));
    in.read(text.data(), size);
  }
  if (!in && size > 0)
    throw inputError("cannot read the file", atLine(path.string()), "check its permissions");
  refuseBinary(text, path);
  return parseTextPoints(text, path.string(), options);
}

std::vector<Point3> readTextPoints(const std::filesystem::path& path,
                                   const TextPointOptions& options) {
  return readTextPointTable(path, options).points;
}

}  // namespace tinsmith::ingest
