#include "ingest/readers/text_polylines.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/base/error.hpp"

namespace tinsmith::ingest {

namespace {

bool parseNumber(std::string_view field, double& out) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  const auto r = std::from_chars(field.data(), field.data() + field.size(), out);
  return r.ec == std::errc() && r.ptr == field.data() + field.size();
}

}  // namespace

std::vector<TextPolyline> parseTextPolylines(std::string_view text, const std::string& sourceName) {
  std::vector<TextPolyline> out;
  TextPolyline current;
  auto finish = [&](std::int64_t line) {
    if (current.vertices.empty()) return;
    if (current.vertices.size() == 1)
      throw inputError("a polyline has a single vertex", {sourceName, {}, {}, current.firstLine},
                       "a break line needs at least two vertices; separate polylines by one blank line");
    if (current.vertices.size() > 3 && current.vertices.front() == current.vertices.back()) {
      current.vertices.pop_back();
      current.closed = true;
    }
    out.push_back(std::move(current));
    current = {};
    (void)line;
  };
  std::int64_t lineNo = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos) {
      finish(lineNo);
      if (end == text.size()) break;
      continue;
    }
    if (line[first] == '#') {
      if (end == text.size()) break;
      continue;
    }
    std::vector<std::string_view> fields;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == ',')) ++i;
      if (i >= line.size()) break;
      std::size_t j = i;
      while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != ',') ++j;
      fields.push_back(line.substr(i, j - i));
      i = j;
    }
    const SourceLocation where{sourceName, {}, {}, lineNo};
    if (fields.size() != 3)
      throw inputError("expected three numbers \"x y z\", found " + std::to_string(fields.size()) +
                           " field(s)",
                       where, "write one vertex per line as x y z; a blank line between polylines");
    Point3 p;
    double* dst[3] = {&p.x, &p.y, &p.z};
    for (int k = 0; k < 3; ++k) {
      if (!parseNumber(fields[k], *dst[k]))
        throw inputError("'" + std::string(fields[k]) + "' is not a number", where,
                         "write one vertex per line as x y z");
      if (!std::isfinite(*dst[k]))
        throw inputError("coordinate '" + std::string(fields[k]) + "' is not finite", where,
                         "remove NaN and infinite values");
    }
    if (current.vertices.empty()) current.firstLine = lineNo;
    current.vertices.push_back(p);
    if (end == text.size()) break;
  }
  finish(lineNo);
  if (out.empty())
    throw inputError("no polyline in the file", fileLocation(sourceName),
                     "write one vertex per line as x y z, a blank line between polylines");
  return out;
}

std::vector<TextPolyline> readTextPolylines(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw inputError("the break-line file does not exist", fileLocation(path), "check the path");
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path, ec))
    throw inputError("cannot read the break-line file", fileLocation(path), "check permissions");
  std::ostringstream text;
  text << in.rdbuf();
  return parseTextPolylines(text.str(), path.string());
}

}  // namespace tinsmith::ingest
