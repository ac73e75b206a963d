// `tinsmith fit`: fit a multilevel least-squares surface over binary
// triangulations (Algorithm 8.1) to an XYZ/CSV point file and write it as .tin.
#include <cctype>
#include <chrono>
#include <filesystem>
#include <set>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "ingest/readers/raster_reader.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "ingest/readers/text_points.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"

namespace tinsmith::cli {

namespace {

struct FitCliOptions {
  std::string points;
  std::string output;
  std::optional<std::string> tolerance;
  double lambda = 1.0;
  std::optional<double> lambdaAbs;
  std::string smoothing = "thin-plate";
  std::optional<std::string> criterion;
  std::optional<std::string> stats;
  std::string solver = "gs";
  int maxLevel = 20;
  int directLevels = 3;
  int threads = 0;
  std::string crs;
  bool quiet = false;
  std::optional<std::string> weightsColumn;
  std::optional<std::string> fixed;
  std::optional<std::string> domain;
};

double parseNumber(const std::string& text, const std::string& option);

/// --domain X0,Y0,SIZE: three numbers, SIZE > 0.
std::vector<double> parseDomain(const std::string& text) {
  std::vector<double> v;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t comma = text.find(',', begin);
    v.push_back(parseNumber(text.substr(begin, comma - begin), "--domain"));
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  if (v.size() != 3 || !(v[2] > 0)) {
    throw usageError("--domain: '" + text + "' is not X0,Y0,SIZE with SIZE > 0",
                     "e.g. --domain 430000,4512000,8000 for an 8 km square");
  }
  return v;
}

double parseNumber(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) {
    throw usageError(option + ": '" + text + "' is not a number", "e.g. " + option + " 0.5");
  }
  return v;
}

/// A whole number from 0 to `max` (a column index, a count) as the value of
/// `option`, or a usage error naming both. (Digits beyond int made std::stoi
/// throw std::out_of_range, reported as an internal error.)
std::uint64_t parseWholeNumber(const std::string& text, const std::string& option,
                               std::uint64_t max, const std::string& example) {
  const double v = parseNumber(text, option);
  if (!(v >= 0.0) || v != std::floor(v) || v > static_cast<double>(max)) {
    throw usageError(
        option + ": '" + text + "' is not a whole number from 0 to " + std::to_string(max),
        "e.g. " + example);
  }
  return static_cast<std::uint64_t>(v);
}

fit::Smoothing parseSmoothing(const std::string& s) {
  if (s == "thin-plate") return fit::Smoothing::ThinPlate;
  if (s == "membrane") return fit::Smoothing::Membrane;
  if (s == "umbrella") return fit::Smoothing::Umbrella;
  if (s == "umbrella-weighted") return fit::Smoothing::UmbrellaWeighted;
  if (s == "none") return fit::Smoothing::None;
  throw usageError("unknown --smoothing '" + s + "'", "use thin-plate, membrane, umbrella, umbrella-weighted or none");
}

fit::SolverKind parseSolver(const std::string& s) {
  if (s == "gs") return fit::SolverKind::GaussSeidel;
  if (s == "cg") return fit::SolverKind::ConjugateGradient;
  if (s == "direct") return fit::SolverKind::Direct;
  throw usageError("unknown --solver '" + s + "'", "use gs (Gauss-Seidel), cg or direct");
}

/// --tolerance "0.25%" (of the z range) or "2.5" (z units) and --criterion
/// "error,count:2,curvature:0.1" → the criteria. Without --criterion the
/// tolerance alone is the criterion.
fit::RefinementCriteria parseCriteria(const FitCliOptions& o) {
  fit::RefinementCriteria c;
  bool wantError = !o.criterion.has_value();
  if (o.criterion) {
    std::stringstream parts(*o.criterion);
    std::string part;
    while (std::getline(parts, part, ',')) {
      const auto colon = part.find(':');
      const std::string name = part.substr(0, colon);
      const std::string value = colon == std::string::npos ? "" : part.substr(colon + 1);
      if (name == "error") {
        wantError = true;
      } else if (name == "count") {
        if (value.empty())
          throw usageError("--criterion count:N needs a whole number N >= 0", "e.g. count:2");
        constexpr std::uint64_t kLargestExactCount =
            std::uint64_t{1} << 53;  // every whole number to here is a double
        c.countAbove = parseWholeNumber(value, "--criterion count", kLargestExactCount, "count:2");
      } else if (name == "curvature") {
        if (value.empty()) throw usageError("--criterion curvature:T needs a threshold T", "e.g. curvature:0.05");
        c.curvatureAbove = parseNumber(value, "--criterion curvature");
      } else {
        throw usageError("unknown criterion '" + part + "'", "use error, count:N, curvature:T or a comma-separated combination");
      }
    }
  }
  if (wantError) {
    if (!o.tolerance) throw usageError("the error criterion needs --tolerance", "e.g. --tolerance 0.25% or --tolerance 2.5");
    std::string t = *o.tolerance;
    const bool percent = !t.empty() && t.back() == '%';
    if (percent) t.pop_back();
    const double v = parseNumber(t, "--tolerance");
    if (!(v > 0)) throw usageError("--tolerance must be positive");
    if (percent) c.errorPercent = v;
    else c.errorAbsolute = v;
  } else if (o.tolerance) {
    throw usageError("--tolerance is given but --criterion has no 'error'", "add error to --criterion, e.g. error,count:2");
  }
  return c;
}

const char* solverName(fit::SolverKind s) {
  switch (s) {
    case fit::SolverKind::Direct: return "direct";
    case fit::SolverKind::GaussSeidel: return "gauss-seidel";
    case fit::SolverKind::ConjugateGradient: return "cg";
  }
  return "";
}

std::string statsJson(const fit::MultilevelFit& result, std::size_t points, double seconds) {
  const auto levels = result.levels();
  const auto& last = levels.back();
  nlohmann::ordered_json j;
  j["points"] = points;
  j["seconds"] = seconds;
  j["final"] = {{"level", last.level},
                {"vertices", last.vertices},
                {"triangles", last.triangles},
                {"max_error", last.maxError},
                {"rms_error", last.rmsError},
                {"stopped", result.stoppedAtMaxLevel() ? "max level" : "criterion met"},
                {"cells_failing", last.cellsFailing}};
  j["levels"] = nlohmann::ordered_json::array();
  for (const auto& s : levels) {
    j["levels"].push_back({{"level", s.level},
                           {"vertices", s.vertices},
                           {"triangles", s.triangles},
                           {"solver", solverName(s.solver)},
                           {"iterations", s.iterations},
                           {"relative_residual", s.relativeResidual},
                           {"lambda", s.lambda},
                           {"max_error", s.maxError},
                           {"rms_error", s.rmsError},
                           {"cells_failing", s.cellsFailing},
                           {"cells_refined", s.cellsRefined},
                           {"seconds", s.seconds}});
  }
  return j.dump(2) + "\n";  // NaN/inf become null: the file is always valid JSON
}

/// The data points of `path`: a raster's valid cell centres (by extension),
/// otherwise a text point file. A raster's CRS fills `crs` when none was given.
bool isRasterPath(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::set<std::string> kRasterExtensions = {".tif", ".tiff", ".exr", ".img", ".asc", ".vrt"};
  return kRasterExtensions.contains(ext);
}

std::vector<Point3> readFitInput(const std::string& path, std::string& crs) {
  if (ingest::isSyntheticSpec(path)) {
    return ingest::readSyntheticLayer(ingest::commandLineLayer(path, path, ingest::LayerKind::Points))
        .points;
  }
  if (!isRasterPath(path)) return ingest::readTextPoints(path);
  const ingest::HeightGrid grid = ingest::readHeightGrid(path);
  if (crs.empty()) crs = grid.crs;
  return ingest::gridToPoints(grid);
}

/// The per-point weights w_k (8.8) from column `column` (a 0-based index or a
/// header name) of the text point file `path`, in the order readTextPoints
/// returns the points. Throws inputError naming the file and line of a weight
/// that is not a positive finite number.
std::vector<double> readWeights(const std::string& path, const std::string& column) {
  if (isRasterPath(path) || ingest::isSyntheticSpec(path)) {
    throw usageError("--weights-column needs a text point file, not a raster or a synthetic spec",
                     "write the points as x y z w text");
  }
  const ingest::TextPointTable points = ingest::readTextPointTable(path);
  ingest::TextPointOptions wopt;
  wopt.delimiter = points.delimiter;
  wopt.header = points.hasHeader ? ingest::TextHeader::Present : ingest::TextHeader::Absent;
  wopt.xIndex = points.xIndex;
  wopt.yIndex = points.yIndex;
  const bool isIndex = !column.empty() && column.find_first_not_of("0123456789") == std::string::npos;
  if (isIndex) {
    wopt.zIndex = static_cast<int>(parseWholeNumber(
        column, "--weights-column", std::numeric_limits<int>::max(), "--weights-column 3"));
  } else {
    if (!points.hasHeader) {
      throw usageError("--weights-column '" + column + "' names a column but " + path + " has no header",
                       "give the 0-based column index instead, e.g. --weights-column 3");
    }
    wopt.zColumn = column;
  }
  const ingest::TextPointTable weights = ingest::readTextPointTable(path, wopt);
  if (weights.points.size() != points.points.size()) {
    throw internalError("the weight column of " + path + " has a different number of rows than the points");
  }
  std::vector<double> w(weights.points.size());
  for (std::size_t i = 0; i < w.size(); ++i) {
    w[i] = weights.points[i].z;
    if (!(w[i] > 0.0) || !std::isfinite(w[i])) {
      SourceLocation where;
      where.file = path;
      where.line = weights.lines[i];
      throw inputError("the weight " + std::to_string(w[i]) + " is not a positive number", where,
                       "weights (8.8) must be > 0; drop the point instead of giving it weight 0");
    }
  }
  return w;
}

}  // namespace

void addFitCommand(CLI::App& app) {
  auto o = std::make_shared<FitCliOptions>();
  auto* cmd = app.add_subcommand("fit", "Fit a multilevel least-squares surface over binary triangulations");
  cmd->add_option("points", o->points,
                  "XYZ/CSV point file (x, y, z; projected metres), or a projected raster "
                  "(GeoTIFF or any GDAL raster, EXR heightmap) whose valid cells are the points, "
                  "or generated points ('synthetic:random?n=5000&surface=franke&scale=1', "
                  "see config/README.md)")
      ->required();
  cmd->add_option("--tolerance", o->tolerance, "Error criterion: z units (2.5), or a percentage of the z range (0.25%)");
  cmd->add_option("--lambda", o->lambda, "Smoothing weight as a multiple of the default lambda_d (default 1)");
  cmd->add_option("--lambda-abs", o->lambdaAbs, "Absolute smoothing weight (overrides --lambda)");
  cmd->add_option("--smoothing", o->smoothing, "thin-plate (default) | membrane | umbrella | umbrella-weighted | none");
  cmd->add_option("--criterion", o->criterion, "error, count:N, curvature:T, or a comma-separated combination (all must hold)");
  addOutputOption(*cmd, o->output, "The .tin file to write")->required();
  cmd->add_option("--stats", o->stats, "Per-level statistics as JSON");
  cmd->add_option("--solver", o->solver, "gs (Gauss-Seidel, default) | cg | direct, on the levels after --direct-levels");
  cmd->add_option("--max-level", o->maxLevel, "The finest grid level whose cells may be refined (1..29, default 20)");
  cmd->add_option("--direct-levels", o->directLevels, "Levels solved by the direct solver first (default 3)");
  addThreadsOption(*cmd, o->threads, "Worker threads", "the same fit for any count");
  addCrsOption(*cmd, o->crs, "CRS to record in the .tin");
  cmd->add_option("--domain", o->domain,
                  "The square to fit over, as X0,Y0,SIZE: lower-left corner and side in the "
                  "points' units (default: the bounding square of the points); every point must "
                  "lie in it");
  addQuietFlag(*cmd, o->quiet, "No progress and no summary on stderr");
  cmd->add_option("--weights-column", o->weightsColumn,
                  "Column of the point file (0-based index or header name) holding a weight w > 0 for each point "
                  "(weighted least squares, 8.8)");
  cmd->add_option("--fixed", o->fixed,
                  "XYZ/CSV file of points the surface must pass through exactly (constrained least squares, 8.9); "
                  "each is moved to the nearest vertex of the finest grid");
  cmd->callback([o] {
    fit::MultilevelOptions opt;
    opt.smoothing = parseSmoothing(o->smoothing);
    opt.solver = parseSolver(o->solver);
    opt.criteria = parseCriteria(*o);
    if (!(o->lambda >= 0)) throw usageError("--lambda must be >= 0");
    opt.lambdaFactor = o->lambda;
    if (o->lambdaAbs) {
      if (!(*o->lambdaAbs >= 0)) throw usageError("--lambda-abs must be >= 0");
      opt.lambdaAbsolute = *o->lambdaAbs;
    }
    opt.maxLevel = o->maxLevel;
    opt.directLevels = o->directLevels;
    opt.threads = o->threads;
    if (o->domain) {
      const std::vector<double> d = parseDomain(*o->domain);
      opt.domainOrigin = Point2{d[0], d[1]};
      opt.domainSize = d[2];
    }
    if (!o->quiet) opt.progress = [](const std::string& line) { std::cerr << line << "\n"; };

    std::string crs = o->crs;
    const std::vector<Point3> points = readFitInput(o->points, crs);
    if (o->weightsColumn) opt.weights = readWeights(o->points, *o->weightsColumn);
    if (o->fixed) opt.fixed = ingest::readTextPoints(*o->fixed);
    const auto start = std::chrono::steady_clock::now();
    const fit::MultilevelFit result = fit::fitMultilevel(points, opt);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ingest::writeTinFile(o->output, result.toTinData(crs));
    if (o->stats) {
      ingest::AtomicFile out(*o->stats);
      out.write(statsJson(result, points.size(), seconds));
      out.commit();
    }
    const auto& last = result.levels().back();
    if (!o->quiet) {
      std::cerr << "wrote " << o->output << ": " << last.vertices << " vertices, " << last.triangles
                << " triangles, level " << last.level << ", max error " << last.maxError << ", rms " << last.rmsError
                << "\n";
    }
    if (result.stoppedAtMaxLevel()) {  // a warning, so even with --quiet
      std::cerr << "warning: " << last.cellsFailing << " cells of level " << last.level
                << " still fail the refinement criterion; the fit stopped at --max-level " << opt.maxLevel
                << " (raise it for a finer fit)\n";
    }
  });
}

}  // namespace tinsmith::cli
