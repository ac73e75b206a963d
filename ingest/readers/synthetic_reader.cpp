#include "ingest/readers/synthetic_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include "core/base/error.hpp"
#include "core/base/split_mix.hpp"
#include "core/surface/franke_function.hpp"
#include "ingest/readers/raster_reader.hpp"

namespace tinsmith::ingest {
namespace {

constexpr std::string_view kPrefix = "synthetic:";
constexpr double kMaxPoints = 1e8;  // a typo (n=1e12) fails instead of eating the memory

enum class Pattern { Grid, Random, Raster, Lines, Rings };
enum class Surface { Flat, Plane, Franke, Hill, Cone };
enum class Layout { Hatch, Cross, Star, Random };

struct PatternInfo {
  Pattern pattern;
  std::string_view name;
  std::set<std::string_view> keys;
};

// The keys every pattern takes, then each pattern's own.
const std::set<std::string_view> kCommonKeys = {"x0",    "y0",    "surface", "z0",
                                                "scale", "noise", "seed"};
const PatternInfo kPatterns[] = {
    {Pattern::Grid, "grid", {"nx", "ny", "spacing", "jitter", "duplicates"}},
    {Pattern::Random, "random", {"n", "width", "height", "duplicates"}},
    {Pattern::Raster, "raster", {"nx", "ny", "spacing", "nodata"}},
    {Pattern::Lines, "lines", {"n", "width", "height", "layout", "vertices", "z"}},
    {Pattern::Rings, "rings", {"n", "width", "height", "vertices", "interval"}},
};

/// A parsed spec: the pattern and its keys, each read (and range-checked) once.
class Spec {
 public:
  explicit Spec(std::string_view text) : text_(text) {
    if (!isSyntheticSpec(text))
      fail("is not a synthetic spec", "write synthetic:PATTERN?KEY=VALUE&…");
    const auto body = text.substr(kPrefix.size());
    const auto query = body.find('?');
    const auto name = body.substr(0, query);
    const PatternInfo* info = nullptr;
    for (const auto& p : kPatterns) {
      if (p.name == name) info = &p;
    }
    if (!info) fail("unknown pattern '" + std::string(name) + "'", "patterns: " + patternList());
    pattern_ = info->pattern;
    name_ = info->name;
    if (query == std::string_view::npos) return;
    auto rest = body.substr(query + 1);
    while (!rest.empty()) {
      const auto amp = rest.find('&');
      const auto pair = rest.substr(0, amp);
      rest = amp == std::string_view::npos ? std::string_view{} : rest.substr(amp + 1);
      if (pair.empty()) continue;
      const auto eq = pair.find('=');
      const std::string key(pair.substr(0, eq));
      if (eq == std::string_view::npos || eq + 1 == pair.size()) {
        fail("key '" + key + "' has no value", "write " + key + "=VALUE");
      }
      if (!kCommonKeys.count(key) && !info->keys.count(key)) {
        fail("unknown key '" + key + "' for pattern " + name_,
             "keys of " + name_ + ": " + keyList(*info));
      }
      if (!values_.emplace(key, std::string(pair.substr(eq + 1))).second) {
        fail("key '" + key + "' is given twice", "give each key once");
      }
    }
  }

  [[nodiscard]] Pattern pattern() const { return pattern_; }
  [[nodiscard]] bool has(const std::string& key) const { return values_.count(key) > 0; }
  [[nodiscard]] const std::string& name() const { return name_; }

  double number(const std::string& key, double fallback) const {
    const auto it = values_.find(key);
    if (it == values_.end()) return fallback;
    const auto& text = it->second;
    double value = 0.0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (result.ec != std::errc() || result.ptr != text.data() + text.size() ||
        !std::isfinite(value)) {
      fail(key + " = '" + text + "' is not a number",
           "write a decimal number, e.g. " + key + "=10");
    }
    return value;
  }

  /// A number checked against [lo, hi] (a whole number if `whole`).
  double checked(const std::string& key, double fallback, double lo, double hi,
                 bool whole = false) const {
    const double v = number(key, fallback);
    if (whole && v != std::floor(v)) fail(key + " = " + values_.at(key) + " is not a whole number");
    if (v < lo || v > hi) {
      fail(key + " = " + (values_.count(key) ? values_.at(key) : fmt(v)) + " is out of range",
           key + " must be " + fmt(lo) + " to " + fmt(hi));
    }
    return v;
  }

  std::size_t count(const std::string& key, double fallback, double lo) const {
    return static_cast<std::size_t>(checked(key, fallback, lo, kMaxPoints, true));
  }

  double positive(const std::string& key, double fallback) const {
    const double v = number(key, fallback);
    if (!(v > 0))
      fail(key + " = " + (values_.count(key) ? values_.at(key) : fmt(v)) + " is out of range",
           key + " must be greater than 0");
    return v;
  }

  /// One of `choices` (the first is the default).
  template <typename Enum>
  Enum choice(const std::string& key,
              std::initializer_list<std::pair<std::string_view, Enum>> choices) const {
    const auto it = values_.find(key);
    if (it == values_.end()) return choices.begin()->second;
    std::string list;
    for (const auto& [name, value] : choices) {
      if (name == it->second) return value;
      list += (list.empty() ? "" : " | ") + std::string(name);
    }
    fail(key + " = '" + it->second + "' is not known", key + " = " + list);
  }

  [[noreturn]] void fail(const std::string& problem, const std::string& hint = {}) const {
    throw inputError(problem, fileLocation(std::string(text_)), hint);
  }

  /// A number as the messages write it (fixed notation, shortest).
  static std::string fmt(double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);
    return {buf, r.ptr};
  }

 private:
  static std::string patternList() {
    std::string list;
    for (const auto& p : kPatterns) list += (list.empty() ? "" : ", ") + std::string(p.name);
    return list;
  }
  static std::string keyList(const PatternInfo& info) {
    std::set<std::string_view> all = kCommonKeys;
    all.insert(info.keys.begin(), info.keys.end());
    std::string list;
    for (const auto k : all) list += (list.empty() ? "" : ", ") + std::string(k);
    return list;
  }

  std::string_view text_;
  Pattern pattern_ = Pattern::Grid;
  std::string name_;
  std::map<std::string, std::string> values_;
};

/// The one generator of every random choice (portable: core/base/split_mix.hpp).
class Random : public SplitMix64 {
 public:
  using SplitMix64::SplitMix64;
  /// Uniform in [-a, a).
  double symmetric(double a) { return a * (2.0 * uniform() - 1.0); }
};

/// The extent the surface is spread over, and the surface.
struct Terrain {
  double x0 = 0, y0 = 0, width = 100, height = 100;
  Surface surface = Surface::Plane;
  double z0 = 0, scale = 100, noise = 0;

  double z(double x, double y, Random& random) const {
    const double u = (x - x0) / width, v = (y - y0) / height;
    double s = 0.0;
    switch (surface) {
      case Surface::Flat:
        s = 0.0;
        break;
      case Surface::Plane:
        s = (u + v) / 2;
        break;
      case Surface::Franke:
        s = frankeFunction(u, v);
        break;
      case Surface::Hill:
        s = std::exp(-((u - 0.5) * (u - 0.5) + (v - 0.5) * (v - 0.5)) / 0.08);
        break;
      case Surface::Cone:
        s = std::max(0.0, 1.0 - 2.0 * std::hypot(u - 0.5, v - 0.5));
        break;
    }
    const double z = z0 + scale * s;
    return noise > 0 ? z + random.symmetric(noise) : z;
  }
};

/// Every value of a spec, read and range-checked once, before anything is made.
struct Params {
  Pattern pattern = Pattern::Grid;
  Terrain terrain;
  std::uint64_t seed = 1;
  std::size_t nx = 0, ny = 0, n = 0, duplicates = 0, vertices = 0;
  double spacing = 0, jitter = 0, nodata = 0, interval = 0;
  Layout layout = Layout::Hatch;
  bool linesHaveZ = true;
};

Params paramsOf(const Spec& spec) {
  Params p;
  p.pattern = spec.pattern();
  p.seed = static_cast<std::uint64_t>(spec.checked("seed", 1, 0, 9007199254740992.0, true));
  auto& t = p.terrain;
  t.x0 = spec.number("x0", 0.0);
  t.y0 = spec.number("y0", 0.0);
  t.surface = spec.choice<Surface>("surface", {{"plane", Surface::Plane},
                                               {"flat", Surface::Flat},
                                               {"franke", Surface::Franke},
                                               {"hill", Surface::Hill},
                                               {"cone", Surface::Cone}});
  t.z0 = spec.number("z0", 0.0);
  t.scale = spec.number("scale", 100.0);
  t.noise = spec.checked("noise", 0.0, 0.0, 1e9);
  if (p.pattern == Pattern::Grid || p.pattern == Pattern::Raster) {
    p.nx = spec.count("nx", 11, 1);
    p.ny = spec.count("ny", 11, 1);
    p.spacing = spec.positive("spacing", 10.0);
    if (static_cast<double>(p.nx) * static_cast<double>(p.ny) > kMaxPoints) {
      spec.fail("nx × ny = " + std::to_string(p.nx * p.ny) + " points is too many",
                "at most " + Spec::fmt(kMaxPoints));
    }
    // A grid's extent runs from the first point to the last, a raster's
    // from cell corner to cell corner. A one-row grid has no extent across:
    // the surface sees it as 1 m.
    const double cells = p.pattern == Pattern::Grid ? -1.0 : 0.0;
    auto extent = [&](std::size_t count) {
      const double e = (static_cast<double>(count) + cells) * p.spacing;
      return e > 0 ? e : 1.0;
    };
    t.width = extent(p.nx);
    t.height = extent(p.ny);
  } else {
    t.width = spec.positive("width", 100);
    t.height = spec.positive("height", 100);
  }
  switch (p.pattern) {
    case Pattern::Grid:
      if (p.nx * p.ny < 3)
        spec.fail("nx × ny is less than 3 points", "a TIN needs 3 points or more");
      p.jitter = spec.checked("jitter", 0.0, 0.0, 0.5) * p.spacing;
      p.duplicates = spec.count("duplicates", 0, 0);
      break;
    case Pattern::Random:
      p.n = spec.count("n", 100, 1);
      p.duplicates = spec.count("duplicates", 0, 0);
      break;
    case Pattern::Raster:
      p.nodata = spec.checked("nodata", 0.0, 0.0, 1.0);
      break;
    case Pattern::Lines:
      p.n = spec.count("n", 3, 1);
      p.layout = spec.choice<Layout>("layout", {{"hatch", Layout::Hatch},
                                                {"cross", Layout::Cross},
                                                {"star", Layout::Star},
                                                {"random", Layout::Random}});
      p.vertices = spec.count("vertices", 2, 2);
      p.linesHaveZ = spec.choice<bool>("z", {{"surface", true}, {"none", false}});
      break;
    case Pattern::Rings:
      p.n = spec.count("n", 5, 1);
      p.vertices = spec.count("vertices", 64, 3);
      p.interval = spec.positive("interval", 10);
      break;
  }
  // Keys every pattern takes, given where they do nothing, are refused like
  // unknown ones.
  auto unused = [&](std::initializer_list<const char*> keys, const std::string& why) {
    for (const char* key : keys)
      if (spec.has(key))
        spec.fail("key '" + std::string(key) + "' does nothing " + why, "leave it out");
  };
  if (p.pattern == Pattern::Rings)
    unused({"surface", "scale", "noise", "seed"},
           "for pattern rings (their heights step by interval from z0)");
  if (p.pattern == Pattern::Lines && !p.linesHaveZ)
    unused({"surface", "z0", "scale", "noise"}, "for lines with z=none (they have no heights)");
  // What the layer will hold, all told: never more than kMaxPoints.
  const double total =
      p.pattern == Pattern::Grid     ? static_cast<double>(p.nx) * p.ny + p.duplicates
      : p.pattern == Pattern::Random ? static_cast<double>(p.n) + p.duplicates
      : p.pattern == Pattern::Raster ? static_cast<double>(p.nx) * p.ny
                                     : static_cast<double>(p.n) * p.vertices *
                                           (p.layout == Layout::Cross ? 2 : 1);
  if (total > kMaxPoints)
    spec.fail("the layer would hold " + Spec::fmt(total) + " points or vertices, too many",
              "at most " + Spec::fmt(kMaxPoints) + " in all (n × vertices for lines and rings)");
  // Each value finite alone can still overflow together.
  if (!std::isfinite(t.x0 + t.width) || !std::isfinite(t.y0 + t.height))
    spec.fail("the extent (x0, y0 plus the width, height or nx, ny × spacing) is not finite",
              "give coordinates within the range of a double");
  if (!std::isfinite(std::abs(t.z0) + std::abs(t.scale) + t.noise))
    spec.fail("z0, scale and noise together are not finite", "give heights a double can hold");
  return p;
}

void addDuplicates(const Params& p, Random& random, IngestedLayer& out) {
  const auto n = out.points.size();
  for (std::size_t i = 0; i < p.duplicates; ++i) {
    const auto k = static_cast<std::size_t>(random.next() % n);
    out.points.push_back(out.points[k]);
    out.pointIds.push_back(out.pointIds[k]);
  }
}

HeightGrid rasterGrid(const Params& p) {
  const auto& terrain = p.terrain;
  Random random(p.seed);
  HeightGrid grid;
  grid.width = static_cast<int>(p.nx);
  grid.height = static_cast<int>(p.ny);
  grid.geotransform = {terrain.x0, p.spacing, 0.0, terrain.y0 + terrain.height, 0.0, -p.spacing};
  grid.z.resize(p.nx * p.ny);
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const auto c = grid.cellCentre(col, row);
      const bool hole = p.nodata > 0 && random.uniform() < p.nodata;
      const double z = terrain.z(c.x, c.y, random);
      grid.z[static_cast<std::size_t>(row) * p.nx + static_cast<std::size_t>(col)] =
          hole ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(z);
    }
  }
  return grid;
}

void makePoints(const Spec& spec, const Params& p, IngestedLayer& out) {
  const auto& terrain = p.terrain;
  Random random(p.seed);
  if (p.pattern == Pattern::Grid) {
    out.points.reserve(p.nx * p.ny + p.duplicates);
    for (std::size_t j = 0; j < p.ny; ++j) {
      for (std::size_t i = 0; i < p.nx; ++i) {
        double x = terrain.x0 + static_cast<double>(i) * p.spacing;
        double y = terrain.y0 + static_cast<double>(j) * p.spacing;
        if (p.jitter > 0) {
          x += random.symmetric(p.jitter);
          y += random.symmetric(p.jitter);
        }
        out.points.push_back({x, y, terrain.z(x, y, random)});
        out.pointIds.push_back(static_cast<std::int64_t>(j * p.nx + i));
      }
    }
    addDuplicates(p, random, out);
  } else if (p.pattern == Pattern::Random) {
    out.points.reserve(p.n + p.duplicates);
    for (std::size_t i = 0; i < p.n; ++i) {
      const double x = terrain.x0 + random.uniform() * terrain.width;
      const double y = terrain.y0 + random.uniform() * terrain.height;
      out.points.push_back({x, y, terrain.z(x, y, random)});
      out.pointIds.push_back(static_cast<std::int64_t>(i));
    }
    addDuplicates(p, random, out);
  } else {
    out.points = gridToPoints(rasterGrid(p), &out.pointIds);
    if (out.points.empty()) spec.fail("every cell is nodata", "lower nodata (a fraction, 0 to 1)");
  }
}

void makeLines(const Params& p, IngestedLayer& out) {
  const auto& terrain = p.terrain;
  Random random(p.seed);
  const std::size_t n = p.n;
  const double x1 = terrain.x0 + terrain.width, y1 = terrain.y0 + terrain.height;
  const double cx = terrain.x0 + terrain.width / 2, cy = terrain.y0 + terrain.height / 2;
  const double radius = std::min(terrain.width, terrain.height) / 2;
  constexpr double kNoZ = std::numeric_limits<double>::quiet_NaN();
  std::int64_t fid = 0;
  auto add = [&](std::vector<Point3> vertices, bool closed, bool hasZ) {
    IngestedFeature f;
    f.fid = ++fid;
    f.closed = closed;
    f.hasZ = hasZ;
    f.vertices = std::move(vertices);
    out.features.push_back(std::move(f));
  };

  if (p.pattern == Pattern::Rings) {
    for (std::size_t k = 1; k <= n; ++k) {
      const double r = radius * static_cast<double>(k) / static_cast<double>(n + 1);
      const double z = terrain.z0 + static_cast<double>(n + 1 - k) * p.interval;
      std::vector<Point3> ring;
      for (std::size_t i = 0; i < p.vertices; ++i) {
        const double a =
            2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(p.vertices);
        ring.push_back({cx + r * std::cos(a), cy + r * std::sin(a), z});
      }
      add(std::move(ring), true, true);
    }
    return;
  }

  const bool hasZ = p.linesHaveZ;
  auto vertex = [&](double x, double y) {
    return Point3{x, y, hasZ ? terrain.z(x, y, random) : kNoZ};
  };
  // A polyline from a to b, p.vertices evenly spaced.
  auto straight = [&](Point2 a, Point2 b) {
    std::vector<Point3> line;
    for (std::size_t i = 0; i < p.vertices; ++i) {
      const double t = static_cast<double>(i) / static_cast<double>(p.vertices - 1);
      line.push_back(vertex(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)));
    }
    add(std::move(line), false, hasZ);
  };
  const auto across = [&](std::size_t k, double from, double length) {
    return from + length * static_cast<double>(k) / static_cast<double>(n + 1);
  };
  switch (p.layout) {
    case Layout::Hatch:
    case Layout::Cross:
      for (std::size_t k = 1; k <= n; ++k) {
        const double y = across(k, terrain.y0, terrain.height);
        straight({terrain.x0, y}, {x1, y});
      }
      if (p.layout == Layout::Cross) {
        for (std::size_t k = 1; k <= n; ++k) {
          const double x = across(k, terrain.x0, terrain.width);
          straight({x, terrain.y0}, {x, y1});
        }
      }
      break;
    case Layout::Star:
      for (std::size_t k = 0; k < n; ++k) {
        const double a = std::numbers::pi * static_cast<double>(k) / static_cast<double>(n);
        const double dx = radius * std::cos(a), dy = radius * std::sin(a);
        straight({cx - dx, cy - dy}, {cx + dx, cy + dy});
      }
      break;
    case Layout::Random:
      for (std::size_t k = 0; k < n; ++k) {
        std::vector<Point3> line;
        for (std::size_t i = 0; i < p.vertices; ++i) {
          const double x = terrain.x0 + random.uniform() * terrain.width;
          const double y = terrain.y0 + random.uniform() * terrain.height;
          line.push_back(vertex(x, y));
        }
        add(std::move(line), false, hasZ);
      }
      break;
  }
}

GeometryClass patternClass(Pattern p) {
  switch (p) {
    case Pattern::Grid:
    case Pattern::Random:
    case Pattern::Raster:
      return GeometryClass::Points;
    case Pattern::Lines:
      return GeometryClass::Lines;
    case Pattern::Rings:
      return GeometryClass::Areas;
  }
  return GeometryClass::Points;
}

void checkKind(const Spec& spec, LayerKind kind) {
  const auto made = patternClass(spec.pattern());
  const auto wanted = geometryClass(kind);
  const bool pointsOk = made == GeometryClass::Points &&
                        (wanted == GeometryClass::Points || wanted == GeometryClass::Raster);
  const bool linesOk = made != GeometryClass::Points && wanted == GeometryClass::Lines;
  const bool areasOk = made == GeometryClass::Areas && wanted == GeometryClass::Areas;
  if (pointsOk || linesOk || areasOk) return;
  spec.fail("pattern " + spec.name() + " makes " +
                (made == GeometryClass::Points  ? "points"
                 : made == GeometryClass::Lines ? "open lines"
                                                : "closed rings") +
                ", but kind = \"" + std::string(toString(kind)) + "\" takes " +
                (wanted == GeometryClass::Lines   ? "lines"
                 : wanted == GeometryClass::Areas ? "areas"
                                                  : "points"),
            "points, dem: grid, random, raster; contours, road, river: lines, rings; lake, "
            "boundary, hole: rings");
}

}  // namespace

bool isSyntheticSpec(std::string_view path) {
  return path.starts_with(kPrefix);
}

void checkSyntheticSpec(std::string_view text, LayerKind kind) {
  const Spec spec(text);
  checkKind(spec, kind);
  (void)paramsOf(spec);
}

IngestedLayer readSyntheticLayer(const LayerConfig& config) {
  const auto text = config.path.string();
  const Spec spec(text);
  checkKind(spec, config.kind);
  IngestedLayer out;
  out.config = config;
  out.kind = featureKind(config.kind);
  out.sourceCrs = config.crs;
  out.crs = config.crs;
  const auto params = paramsOf(spec);
  if (patternClass(spec.pattern()) == GeometryClass::Points) {
    makePoints(spec, params, out);
  } else {
    makeLines(params, out);
  }
  if (config.zValue) {
    for (auto& p : out.points) p.z = *config.zValue;
    for (auto& f : out.features) {
      for (auto& v : f.vertices) v.z = *config.zValue;
      f.hasZ = true;
    }
  }
  out.hasZ = std::all_of(out.features.begin(), out.features.end(),
                         [](const IngestedFeature& f) { return f.hasZ; });
  return out;
}

HeightGrid syntheticHeightGrid(std::string_view text) {
  const Spec spec(text);
  if (spec.pattern() != Pattern::Raster) {
    spec.fail("pattern " + spec.name() + " is not a raster", "write synthetic:raster?…");
  }
  return rasterGrid(paramsOf(spec));
}

}  // namespace tinsmith::ingest
