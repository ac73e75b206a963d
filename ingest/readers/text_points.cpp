#include "ingest/readers/text_points.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string_view>

#include "core/base/error.hpp"

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

TextPointTable parseTextPoints(std::string_view text, const std::string& sourceName,
                               const TextPointOptions& options) {
  TextPointTable table;
  table.delimiter = options.delimiter;
  bool first = true;
  std::int64_t lineNo = 0;
  std::vector<std::string_view> fields;
  int xi = 0, yi = 1, zi = options.fixedZ ? -1 : 2;
  int needed = 0;

  // Strip a UTF-8 byte-order mark.
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);

  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = trim(text.substr(pos, end - pos));
    pos = end + 1;
    ++lineNo;
    if (line.empty() || line.front() == '#') continue;

    if (first) {
      first = false;
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
                         atLine(sourceName, lineNo),
                         "add a header line or choose columns by index");
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
      table.xIndex = xi;
      table.yIndex = yi;
      table.zIndex = zi;
      needed = std::max({xi, yi, zi}) + 1;
      if (isHeader) continue;
    }

    splitFields(line, table.delimiter, fields);
    if (static_cast<int>(fields.size()) < needed) {
      throw inputError("expected at least " + std::to_string(needed) + " " +
                           delimiterName(table.delimiter) + "-separated fields, found " +
                           std::to_string(fields.size()),
                       atLine(sourceName, lineNo), "fix or remove the line");
    }
    Point3 p;
    const std::array<std::pair<int, double*>, 3> wanted{{{xi, &p.x}, {yi, &p.y}, {zi, &p.z}}};
    const std::array<const char*, 3> role{"x", "y", "z"};
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
    table.points.push_back(p);
    table.lines.push_back(lineNo);
  }
  if (table.points.empty()) {
    throw inputError("the file holds no points", atLine(sourceName),
                     "check the file and its delimiter");
  }
  return table;
}

TextPointTable readTextPointTable(const std::filesystem::path& path,
                                  const TextPointOptions& options) {
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
  if (text.find('\0') != std::string::npos) {
    throw inputError("is not a text file (it contains NUL bytes)", atLine(path.string()),
                     "give a CSV/XYZ text file, or a GIS file in an OGR format");
  }
  return parseTextPoints(text, path.string(), options);
}

std::vector<Point3> readTextPoints(const std::filesystem::path& path,
                                   const TextPointOptions& options) {
  return readTextPointTable(path, options).points;
}

}  // namespace tinsmith::ingest
