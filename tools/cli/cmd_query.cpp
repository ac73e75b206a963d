// `tinsmith query`: elevation, normal and slope of a TIN at points.
//   tinsmith query X.tin X Y [--json]
//   tinsmith query X.tin --points FILE [--json]   (x y per line; more columns ignored)
// A single point outside the TIN is an input error (exit 3) with or without
// --json; with --points, outside points print "outside" (JSON: null) and the
// run goes on (exit 0).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/surface/surface.hpp"
#include "ingest/export/mesh_export.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"

namespace tinsmith::cli {

namespace {

struct QueryOptions {
  std::string tin;
  std::optional<double> x, y;
  std::string points;
  bool json = false;
};

std::string num(double v) {
  std::string s;
  ingest::appendG17(s, v);
  return s;
}

std::string shortNum(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::vector<Point2> readQueryPoints(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw inputError("cannot read the query points", fileLocation(path), "check the path");
  std::vector<Point2> pts;
  std::string line;
  std::int64_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    std::istringstream fields(line);
    std::string first;
    if (!(fields >> first) || first[0] == '#') continue;
    Point2 p;
    std::istringstream again(line);
    if (!(again >> p.x >> p.y) || !std::isfinite(p.x) || !std::isfinite(p.y)) {
      if (pts.empty() && n == 1) continue;  // a header line
      throw inputError("expected \"x y\" (two numbers)", {path, {}, {}, n}, "one point per line: x y");
    }
    pts.push_back(p);
  }
  if (pts.empty())
    throw inputError("no points in the file", fileLocation(path), "one point per line: x y");
  return pts;
}

std::string jsonSample(const Point2& p, const std::optional<SurfaceSample>& s) {
  std::string out = "{\"x\": " + num(p.x) + ", \"y\": " + num(p.y);
  if (!s) return out + ", \"z\": null, \"normal\": null, \"slope\": null, \"slope_degrees\": null}";
  return out + ", \"z\": " + num(s->z) + ", \"normal\": [" + num(s->normal.x) + ", " +
         num(s->normal.y) + ", " + num(s->normal.z) + "], \"slope\": " + num(s->slope) +
         ", \"slope_degrees\": " + num(s->slopeDegrees) + "}";
}

std::string textSample(const Point2& p, const std::optional<SurfaceSample>& s) {
  std::string out = num(p.x) + " " + num(p.y) + " ";
  if (!s) return out + "outside";
  return out + "z " + shortNum(s->z, 3) + " normal " + shortNum(s->normal.x, 6) + " " +
         shortNum(s->normal.y, 6) + " " + shortNum(s->normal.z, 6) + " slope " +
         shortNum(s->slope, 6) + " (" + shortNum(s->slopeDegrees, 3) + "°)";
}

}  // namespace

void addQueryCommand(CLI::App& app) {
  auto opt = std::make_shared<QueryOptions>();
  auto* cmd = app.add_subcommand("query", "Elevation, normal and slope of a TIN at points");
  cmd->add_option("tin", opt->tin, "The .tin file")->required();
  cmd->add_option("x", opt->x, "Easting in the TIN's CRS");
  cmd->add_option("y", opt->y, "Northing in the TIN's CRS");
  cmd->add_option("--points", opt->points, "A file of query points, x y per line");
  addJsonFlag(*cmd, opt->json);
  cmd->footer(
      "A single point outside the TIN is an input error (exit 3), also with --json, which\n"
      "still prints its record (z, normal and slope null) to stdout. With --points, points\n"
      "outside print \"outside\" (JSON: null) and the run goes on (exit 0).\n\n" +
      cmd->get_footer());  // the exit codes, from tinsmith's own footer
  cmd->callback([opt] {
    const bool single = opt->x.has_value() || opt->y.has_value();
    if (single && !opt->points.empty()) throw usageError("give X Y or --points FILE, not both");
    if (single && !(opt->x && opt->y)) throw usageError("give both X and Y");
    if (!single && opt->points.empty()) throw usageError("give a point (X Y) or --points FILE");
    if (single && (!std::isfinite(*opt->x) || !std::isfinite(*opt->y)))
      throw usageError("X and Y must be finite numbers");
    const TinData tin = ingest::readTinFile(opt->tin);
    const Surface surface(tin);
    if (single) {
      const Point2 p{*opt->x, *opt->y};
      const auto s = surface.sample(p);
      // One rule for both modes: the one point asked for has no elevation, so
      // the query failed (exit 3) and a script testing only the exit status
      // cannot take it for an answer. The JSON record (z null) still goes to
      // stdout for a reader that parses it. A --points run is different: a
      // batch crossing the TIN's edge is ordinary use, so its outside points
      // are data.
      if (opt->json) std::cout << jsonSample(p, s) << "\n";
      if (!s)
        throw inputError("the point " + num(p.x) + ", " + num(p.y) + " is outside the TIN",
                         fileLocation(opt->tin), "query inside its extent (see `tinsmith info`)");
      if (!opt->json) std::cout << textSample(p, s) << "\n";
      return;
    }
    const auto pts = readQueryPoints(opt->points);
    std::string out = opt->json ? "[\n" : "";
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const auto s = surface.sample(pts[i]);
      if (opt->json)
        out += "  " + jsonSample(pts[i], s) + (i + 1 < pts.size() ? ",\n" : "\n");
      else
        out += textSample(pts[i], s) + "\n";
    }
    if (opt->json) out += "]\n";
    std::cout << out;
  });
}

}  // namespace tinsmith::cli
