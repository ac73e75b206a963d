// The block-by-block TIN (block_tin.hpp): prepare (spool, bucket,
// deduplicate), triangulate each block with its surroundings, assemble.
#include "ingest/build/block_tin.hpp"

#include <stdlib.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/geometry/predicates.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {

namespace {

bool lessXY(const Point2& a, const Point2& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

/// The order CdtOptions::canonicalTies ranks points by, and the blocks own
/// triangles by (their least corner's).
bool lessXY(const Point3& a, const Point3& b) {
  return lessXY(a.xy(), b.xy());
}

/// The scratch folder next to the output, removed with everything in it.
class ScratchDir {
 public:
  explicit ScratchDir(const std::filesystem::path& output) {
    const auto dir = output.has_parent_path() ? output.parent_path() : std::filesystem::path(".");
    std::string pattern = (dir / ("." + output.filename().string() + ".blocks.XXXXXX")).string();
    if (!mkdtemp(pattern.data()))
      throw ioError("cannot make a scratch folder for the blocks", fileLocation(dir.string()),
                    "the output's folder must be writable, with room for the points twice over");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Binary files of Point3 records (the host's bytes: they never leave it).
void appendPoints(const std::filesystem::path& path, std::span<const Point3> points) {
  if (points.empty()) return;
  std::FILE* f = std::fopen(path.c_str(), "ab");
  const bool written =
      f && std::fwrite(points.data(), sizeof(Point3), points.size(), f) == points.size();
  const bool closed = f && std::fclose(f) == 0;
  if (!written || !closed)
    throw ioError("cannot write a scratch file", fileLocation(path.string()), "is the disk full?");
}

/// Reads the file into `points`, whose memory is reused from call to call
/// (a block reads many).
void readPoints(const std::filesystem::path& path, std::vector<Point3>& points) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  points.resize(ec ? 0 : size / sizeof(Point3));  // a block without points has no file
  if (points.empty()) return;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  const bool ok = f && std::fread(points.data(), sizeof(Point3), points.size(), f) == points.size();
  if (f) std::fclose(f);
  if (!ok) throw ioError("cannot read a scratch file", fileLocation(path.string()));
}

std::vector<Point3> readPoints(const std::filesystem::path& path) {
  std::vector<Point3> points;
  readPoints(path, points);
  return points;
}

/// Reads a spool file in chunks.
template <class F>
void forEachChunk(const std::filesystem::path& path, F&& f) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw ioError("cannot read a scratch file", fileLocation(path.string()));
  std::vector<Point3> chunk(1 << 16);
  while (true) {
    const std::size_t n = std::fread(chunk.data(), sizeof(Point3), chunk.size(), file);
    if (n == 0) break;
    f(std::span<const Point3>(chunk.data(), n));
  }
  const bool failed = std::ferror(file);
  std::fclose(file);
  if (failed) throw ioError("cannot read a scratch file", fileLocation(path.string()));
}

/// The blocks: squares of side `side` from (x0, y0), nx × ny of them, rows
/// from the south. A point's block is a function of its coordinates alone.
struct BlockGrid {
  double x0 = 0, y0 = 0, side = 1;
  std::uint32_t nx = 1, ny = 1;
  [[nodiscard]] std::uint32_t column(double x) const { return clampIndex((x - x0) / side, nx); }
  [[nodiscard]] std::uint32_t row(double y) const { return clampIndex((y - y0) / side, ny); }
  [[nodiscard]] std::size_t blockOf(const Point3& p) const {
    return std::size_t{row(p.y)} * nx + column(p.x);
  }
  [[nodiscard]] std::size_t count() const { return std::size_t{nx} * ny; }
  static std::uint32_t clampIndex(double u, std::uint32_t n) {
    if (!(u > 0)) return 0;
    return static_cast<std::uint32_t>(std::min<double>(std::floor(u), n - 1));
  }
};

/// Where the CDT's exact predicates work (as Cdt::insertPoint checks it).
bool outOfRange(double v) {
  const double a = std::fabs(v);
  return a > 1e60 || (a != 0.0 && a < 1e-50);
}

struct Circle {
  Point2 center;
  double radius = HUGE_VAL;
};

Circle circumcircle(Point2 a, Point2 b, Point2 c) {
  std::array<Point2, 3> p{a, b, c};
  std::sort(p.begin(), p.end(), [](const Point2& u, const Point2& v) { return lessXY(u, v); });
  const double bx = p[1].x - p[0].x, by = p[1].y - p[0].y;
  const double cx = p[2].x - p[0].x, cy = p[2].y - p[0].y;
  const double d = 2 * (bx * cy - by * cx);
  if (d == 0) return {};
  const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  const double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
  return {{p[0].x + ux, p[0].y + uy}, std::hypot(ux, uy)};
}

/// Whether the points are all on one line (or fewer than three).
bool collinear(std::span<const Point3> points) {
  if (points.size() < 3) return true;
  const Point2 a = points[0].xy();
  std::size_t k = 1;
  while (k < points.size() && points[k].xy() == a) ++k;
  if (k == points.size()) return true;
  const Point2 b = points[k].xy();
  for (const Point3& p : points)
    if (geometry::orient2d(a, b, p.xy()) != 0) return false;
  return true;
}

class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

constexpr const char* kBlocksFormat = "tinsmith-blocks/1";
constexpr std::array<char, 8> kTriMagic = {'T', 'I', 'N', 'B', 'L', 'K', '1', '\0'};

std::filesystem::path bucketPath(const std::filesystem::path& dir, std::size_t block) {
  return dir / "points" / ("block-" + std::to_string(block) + ".bin");
}
std::filesystem::path trianglesPath(const std::filesystem::path& dir, std::size_t task) {
  return dir / "triangles" / (std::to_string(task) + ".tri");
}

/// What stage 1 decided, as blocks.json keeps it.
struct BlockLayout {
  BlockGrid grid;
  double radius = 0;
  std::vector<std::uint64_t> first;  // per block: its first vertex; one more at the end
  std::vector<std::size_t> tasks;    // the blocks with points, in order
  std::string crs;
  std::vector<std::string> sources;
  BlockTinReport report;  // stage 1's part

  [[nodiscard]] std::size_t own(std::size_t b) const { return first[b + 1] - first[b]; }
};

void writeLayout(const std::filesystem::path& dir, const BlockLayout& layout) {
  const BlockTinReport& r = layout.report;
  nlohmann::ordered_json j;
  j["format"] = kBlocksFormat;
  j["crs"] = layout.crs;
  j["sources"] = layout.sources;
  j["grid"] = {{"x0", layout.grid.x0},
               {"y0", layout.grid.y0},
               {"side", layout.grid.side},
               {"nx", layout.grid.nx},
               {"ny", layout.grid.ny}};
  j["maxCircumradius"] = layout.radius;
  j["tasks"] = layout.tasks;
  j["first"] = layout.first;
  j["inputPoints"] = r.inputPoints;
  j["duplicates"] = r.duplicates;
  j["extent"] = {r.extent.x0, r.extent.y0, r.extent.x1, r.extent.y1};
  j["z"] = {r.zMin, r.zMax};
  nlohmann::ordered_json times = nlohmann::ordered_json::object();
  for (const auto& t : r.times) times[t.stage] = t.seconds;
  j["seconds"] = times;
  AtomicFile file(dir / "blocks.json");
  file.write(j.dump(1) + "\n");
  file.commit();
}

BlockLayout readLayout(const std::filesystem::path& dir) {
  const auto path = dir / "blocks.json";
  std::ifstream in(path);
  if (!in)
    throw inputError("no blocks.json: not a folder of points prepared in blocks",
                     fileLocation(dir.string()), "prepare it with tinsmith slurm-tin");
  const auto j = nlohmann::ordered_json::parse(in, nullptr, false);
  if (!j.is_object() || j.value("format", "") != kBlocksFormat)
    throw inputError(
        "not a blocks.json this tinsmith reads (format " + std::string(kBlocksFormat) + ")",
        fileLocation(path.string()), "prepare the points again with this tinsmith");
  BlockLayout layout;
  try {
    layout.crs = j.at("crs").get<std::string>();
    layout.sources = j.at("sources").get<std::vector<std::string>>();
    const auto& g = j.at("grid");
    layout.grid = {g.at("x0").get<double>(), g.at("y0").get<double>(), g.at("side").get<double>(),
                   g.at("nx").get<std::uint32_t>(), g.at("ny").get<std::uint32_t>()};
    layout.radius = j.at("maxCircumradius").get<double>();
    layout.tasks = j.at("tasks").get<std::vector<std::size_t>>();
    layout.first = j.at("first").get<std::vector<std::uint64_t>>();
    BlockTinReport& r = layout.report;
    r.inputPoints = j.at("inputPoints").get<std::size_t>();
    r.duplicates = j.at("duplicates").get<std::size_t>();
    const auto e = j.at("extent").get<std::array<double, 4>>();
    r.extent = {e[0], e[1], e[2], e[3]};
    const auto z = j.at("z").get<std::array<double, 2>>();
    r.zMin = z[0];
    r.zMax = z[1];
    for (const auto& [stage, seconds] : j.at("seconds").items())
      r.times.push_back({stage, seconds.get<double>()});
  } catch (const nlohmann::json::exception& e) {
    throw inputError(std::string("blocks.json is damaged: ") + e.what(),
                     fileLocation(path.string()), "prepare the points again");
  }
  if (layout.first.size() != layout.grid.count() + 1)
    throw inputError("blocks.json is damaged: its offsets do not match its grid",
                     fileLocation(path.string()), "prepare the points again");
  layout.report.gridBlocks = layout.grid.count();
  layout.report.blocks = layout.tasks.size();
  layout.report.blockSide = layout.grid.side;
  layout.report.maxCircumradius = layout.radius;
  layout.report.vertices = layout.first.back();
  return layout;
}

/// A block's own points and those of other blocks within reach, each with
/// its TIN vertex: the same for the triangulation and the assembly.
struct LoadedBlock {
  std::vector<Point3> points;  // its own first
  std::vector<std::uint32_t> global;
  std::size_t own = 0;
  tiles::Rect around;  // what was read: the square grown by 2R and a hair
};

/// Fills `load` with block b's points and those within reach; its vectors'
/// memory, and `theirs`, are reused from block to block.
void loadBlock(const BlockLayout& layout, const std::filesystem::path& dir, std::size_t b,
               LoadedBlock& load, std::vector<Point3>& theirs) {
  const BlockGrid& grid = layout.grid;
  load.own = layout.own(b);
  readPoints(bucketPath(dir, b), load.points);
  if (load.points.size() != load.own)
    throw inputError("block " + std::to_string(b) + " holds " + std::to_string(load.points.size()) +
                         " points where blocks.json says " + std::to_string(load.own),
                     fileLocation(bucketPath(dir, b).string()), "prepare the points again");
  load.global.resize(load.own);
  std::iota(load.global.begin(), load.global.end(), static_cast<std::uint32_t>(layout.first[b]));
  const std::uint32_t column = static_cast<std::uint32_t>(b % grid.nx);
  const std::uint32_t row = static_cast<std::uint32_t>(b / grid.nx);
  const double reach = 2 * layout.radius * (1 + 1e-9) + grid.side * 1e-9;
  load.around = {grid.x0 + column * grid.side - reach, grid.y0 + row * grid.side - reach,
                 grid.x0 + (column + 1) * grid.side + reach,
                 grid.y0 + (row + 1) * grid.side + reach};
  const tiles::Rect& around = load.around;
  // The blocks the reach meets (one more each way: the block of a point on a
  // square's side is the rounding's).
  const std::uint32_t c0 = grid.column(around.x0), c1 = grid.column(around.x1);
  const std::uint32_t r0 = grid.row(around.y0), r1 = grid.row(around.y1);
  for (std::uint32_t r = r0 > 0 ? r0 - 1 : 0; r <= std::min(r1 + 1, grid.ny - 1); ++r) {
    for (std::uint32_t c = c0 > 0 ? c0 - 1 : 0; c <= std::min(c1 + 1, grid.nx - 1); ++c) {
      const std::size_t o = std::size_t{r} * grid.nx + c;
      if (o == b || layout.own(o) == 0) continue;
      readPoints(bucketPath(dir, o), theirs);
      for (std::size_t i = 0; i < theirs.size(); ++i) {
        const Point3& p = theirs[i];
        if (p.x < around.x0 || p.x > around.x1 || p.y < around.y0 || p.y > around.y1) continue;
        load.points.push_back(p);
        load.global.push_back(static_cast<std::uint32_t>(layout.first[o] + i));
      }
    }
  }
}

}  // namespace

double circumradius(Point2 a, Point2 b, Point2 c) {
  return circumcircle(a, b, c).radius;
}

BlockTinReport prepareBlocks(const std::vector<PointSource>& sources,
                             const std::filesystem::path& dir, const BlockTinOptions& options,
                             const Progress* progress) {
  if (!(options.maxCircumradius >= 0) || !std::isfinite(options.maxCircumradius))
    throw usageError("the largest circumradius must be a length in metres greater than 0");
  if (options.blockPoints < 16) throw usageError("a block must hold at least 16 points");
  BlockLayout layout;
  BlockTinReport& report = layout.report;
  layout.crs = options.crs;
  for (const PointSource& source : sources) layout.sources.push_back(source.name);
  Stopwatch clock;
  std::filesystem::create_directories(dir / "points");
  const auto spool = dir / "points" / "spool.bin";

  // Spool: the sources into one binary file, checked, with their box.
  tiles::Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double zMin = HUGE_VAL, zMax = -HUGE_VAL;
  for (const PointSource& source : sources) {
    std::size_t index = 0;
    reportProgress(progress, "blocks.spool", source.name, 0, 0);
    source.read([&](std::span<const Point3> points) {
      for (const Point3& p : points) {
        ++index;
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          throw inputError("point " + std::to_string(index) + " has a non-finite coordinate",
                           fileLocation(source.name), "remove the point or give it a real value");
        if (outOfRange(p.x) || outOfRange(p.y))
          throw inputError("point " + std::to_string(index) +
                               " has x or y outside the supported range (0 or 1e-50 to 1e60 in "
                               "magnitude)",
                           fileLocation(source.name), "check the file's units and CRS");
        box.x0 = std::min(box.x0, p.x);
        box.y0 = std::min(box.y0, p.y);
        box.x1 = std::max(box.x1, p.x);
        box.y1 = std::max(box.y1, p.y);
        zMin = std::min(zMin, p.z);
        zMax = std::max(zMax, p.z);
      }
      appendPoints(spool, points);
      report.inputPoints += points.size();
    });
  }
  if (report.inputPoints < 3)
    throw geometryError("fewer than three points to triangulate", {}, "give at least three points");
  if (report.inputPoints > std::numeric_limits<std::uint32_t>::max() - 2)
    throw inputError("more than 4 294 967 293 points: a .tin numbers its vertices with 32 bits", {},
                     "split the area into several TINs");
  report.extent = box;
  report.zMin = zMin;
  report.zMax = zMax;
  report.times.push_back({"spool", clock.lap()});

  // The blocks: squares holding about blockPoints each on average.
  BlockGrid& grid = layout.grid;
  grid.x0 = box.x0;
  grid.y0 = box.y0;
  const double w = box.x1 - box.x0, h = box.y1 - box.y0;
  const double share = double(options.blockPoints) / double(report.inputPoints);
  grid.side = std::sqrt(std::max(w * h, 1e-300) * share);
  // At most 2^20 blocks, none thinner than the data's own scale allows.
  grid.side = std::max(
      {grid.side, std::max(w, h) / 1024, std::max(std::fabs(box.x1), std::fabs(box.y1)) * 1e-12});
  if (w * h == 0) grid.side = std::max(grid.side, std::max(w, h) * share);
  if (!(grid.side > 0)) grid.side = 1;
  grid.nx = static_cast<std::uint32_t>(std::floor(w / grid.side)) + 1;
  grid.ny = static_cast<std::uint32_t>(std::floor(h / grid.side)) + 1;
  const double spacing = std::sqrt(std::max(w * h, 0.0) / double(report.inputPoints));
  layout.radius = options.maxCircumradius > 0 ? options.maxCircumradius : 8 * spacing;
  if (!(layout.radius > 0))
    throw geometryError("the points lie on one line: no triangle", {},
                        "give points that span an area");

  // Bucket: each point into its block's file.
  {
    std::vector<std::vector<Point3>> buffers(grid.count());
    const std::size_t flushAt = std::clamp<std::size_t>(
        (std::size_t{16} << 20) / sizeof(Point3) / grid.count(), 256, 1 << 16);
    ProgressTicker ticker(progress, "blocks.bucket", "", report.inputPoints);
    std::size_t done = 0;
    forEachChunk(spool, [&](std::span<const Point3> points) {
      for (const Point3& p : points) {
        const std::size_t b = grid.blockOf(p);
        buffers[b].push_back(p);
        if (buffers[b].size() >= flushAt) {
          appendPoints(bucketPath(dir, b), buffers[b]);
          buffers[b].clear();
        }
      }
      ticker.step(done += points.size());
    });
    for (std::size_t b = 0; b < buffers.size(); ++b) appendPoints(bucketPath(dir, b), buffers[b]);
    ticker.finish();
  }
  std::filesystem::remove(spool);
  report.times.push_back({"bucket", clock.lap()});

  // Deduplicate each block; its vertices' first number in the TIN.
  layout.first.assign(grid.count() + 1, 0);
  {
    ProgressTicker ticker(progress, "blocks.deduplicate", "", grid.count());
    for (std::size_t b = 0; b < grid.count(); ++b) {
      std::vector<Point3> points = readPoints(bucketPath(dir, b));
      if (!points.empty()) layout.tasks.push_back(b);
      std::vector<std::uint32_t> order(points.size());
      std::iota(order.begin(), order.end(), 0u);
      std::stable_sort(order.begin(), order.end(), [&](std::uint32_t i, std::uint32_t j) {
        return lessXY(points[i], points[j]);
      });
      std::vector<std::uint8_t> repeat(points.size(), 0);
      for (std::size_t k = 1; k < order.size(); ++k)
        if (points[order[k]].xy() == points[order[k - 1]].xy()) repeat[order[k]] = 1;
      std::size_t kept = 0;
      for (std::size_t i = 0; i < points.size(); ++i)
        if (!repeat[i]) points[kept++] = points[i];
      if (kept < points.size()) {
        report.duplicates += points.size() - kept;
        points.resize(kept);
        std::filesystem::remove(bucketPath(dir, b));
        appendPoints(bucketPath(dir, b), points);
      }
      layout.first[b + 1] = layout.first[b] + kept;
      ticker.step(b + 1);
    }
    ticker.finish();
  }
  report.times.push_back({"deduplicate", clock.lap()});
  std::filesystem::create_directories(dir / "triangles");
  writeLayout(dir, layout);
  return readLayout(dir).report;
}

std::size_t blockTasks(const std::filesystem::path& dir) {
  return readLayout(dir).tasks.size();
}

std::vector<std::size_t> untriangulatedBlocks(const std::filesystem::path& dir) {
  const std::size_t tasks = blockTasks(dir);
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < tasks; ++k)
    if (!std::filesystem::exists(trianglesPath(dir, k))) out.push_back(k);
  return out;
}

BlockResult triangulateBlock(const std::filesystem::path& dir, std::size_t task, unsigned threads) {
  const BlockLayout layout = readLayout(dir);
  if (task >= layout.tasks.size())
    throw usageError("block task " + std::to_string(task) + " is not one of the " +
                     std::to_string(layout.tasks.size()) + " of " + dir.string());
  // What a task holds at its peak is the triangulation: the points are
  // handed to it and let go, and the kept triangles go to the file as they
  // are found (its counts patched in at the end).
  LoadedBlock load;
  {
    std::vector<Point3> theirs;
    loadBlock(layout, dir, layout.tasks[task], load, theirs);
  }
  std::vector<std::uint32_t>().swap(load.global);
  BlockResult result;
  result.triangulated = load.points.size();
  AtomicFile file(trianglesPath(dir, task));
  file.write(kTriMagic.data(), kTriMagic.size());
  std::array<std::uint64_t, 3> counts{};
  file.write(counts.data(), sizeof counts);
  constexpr std::size_t kChunk = 1 << 14;
  std::vector<std::array<std::uint32_t, 3>> kept;
  kept.reserve(kChunk);
  const auto flush = [&] {
    file.write(kept.data(), kept.size() * sizeof kept[0]);
    result.kept += kept.size();
    kept.clear();
  };
  if (!collinear(load.points)) {  // collinear: no triangle within reach, none of its own
    CdtOptions cdtOptions;
    cdtOptions.canonicalTies = true;
    cdtOptions.threads = threads;
    Cdt cdt(cdtOptions);
    cdt.insertPoints(load.points);
    const auto loaded = static_cast<std::uint32_t>(load.points.size());
    std::vector<Point3>().swap(load.points);  // the triangulation holds them: mesh.point
    cdt.finalize();
    const Mesh& mesh = cdt.mesh();
    std::vector<std::uint32_t> loadedOf(mesh.vertexCount(), 0);
    for (std::uint32_t i = 0; i < loaded; ++i) loadedOf[cdt.meshVertex(VertexId(i)).value] = i;
    const tiles::Rect& around = load.around;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const auto v = mesh.vertices(TriangleId(t));
      const std::array<std::uint32_t, 3> corner{loadedOf[v[0].value], loadedOf[v[1].value],
                                                loadedOf[v[2].value]};
      std::size_t least = 0;
      for (const std::size_t i : {1, 2})
        if (lessXY(mesh.point(v[i]), mesh.point(v[least]))) least = i;
      if (corner[least] >= load.own) continue;  // its least corner's block keeps it
      const Circle circle =
          circumcircle(mesh.point(v[0]).xy(), mesh.point(v[1]).xy(), mesh.point(v[2]).xy());
      if (!(circle.radius <= layout.radius)) {
        ++result.leftOut;
        continue;
      }
      // The premise of the proof, checked: the circle is inside what was read.
      if (circle.center.x - circle.radius < around.x0 ||
          circle.center.x + circle.radius > around.x1 ||
          circle.center.y - circle.radius < around.y0 ||
          circle.center.y + circle.radius > around.y1)
        throw internalError("a kept triangle's circle leaves its block's surroundings");
      kept.push_back(corner);
      if (kept.size() == kChunk) flush();
    }
  }
  flush();
  counts = {result.triangulated, result.leftOut, result.kept};
  file.writeAt(kTriMagic.size(), counts.data(), sizeof counts);
  file.commit();
  return result;
}

BlockTinReport assembleBlocks(const std::filesystem::path& dir, const std::filesystem::path& output,
                              const Progress* progress) {
  const BlockLayout layout = readLayout(dir);
  BlockTinReport report = layout.report;
  for (std::size_t k = 0; k < layout.tasks.size(); ++k)
    if (!std::filesystem::exists(trianglesPath(dir, k)))
      throw inputError("block task " + std::to_string(k) + " of " +
                           std::to_string(layout.tasks.size()) + " has no triangles",
                       fileLocation(dir.string()),
                       "run it (tinsmith tin --blocks DIR --block " + std::to_string(k) +
                           ", or tinsmith slurm-tin … --resume --submit), then assemble again");
  Stopwatch clock;
  TinStreamWriter writer(output, layout.crs);
  LoadedBlock load;
  std::vector<Point3> theirs;
  for (std::size_t b = 0; b < layout.grid.count(); ++b) {
    if (layout.own(b) == 0) continue;
    readPoints(bucketPath(dir, b), theirs);
    writer.addVertices(theirs);
  }
  report.times.push_back({"write vertices", clock.lap()});
  ProgressTicker ticker(progress, "blocks.assemble", "", layout.tasks.size());
  std::vector<TinData::Triangle> triangles;
  std::vector<Point3> corners;
  for (std::size_t k = 0; k < layout.tasks.size(); ++k) {
    const auto path = trianglesPath(dir, k);
    std::ifstream in(path, std::ios::binary);
    std::array<char, 8> magic{};
    std::array<std::uint64_t, 3> counts{};
    in.read(magic.data(), magic.size());
    in.read(reinterpret_cast<char*>(counts.data()), sizeof counts);
    std::vector<std::array<std::uint32_t, 3>> kept(in && magic == kTriMagic ? counts[2] : 0);
    in.read(reinterpret_cast<char*>(kept.data()),
            static_cast<std::streamsize>(kept.size() * sizeof kept[0]));
    if (!in || magic != kTriMagic || in.peek() != std::char_traits<char>::eof())
      throw inputError("block task " + std::to_string(k) + "'s triangles are damaged",
                       fileLocation(path.string()), "remove the file and run the task again");
    report.triangulated += counts[0];
    report.largestTriangulated = std::max<std::size_t>(report.largestTriangulated, counts[0]);
    report.leftOut += counts[1];
    if (kept.empty()) continue;
    loadBlock(layout, dir, layout.tasks[k], load, theirs);
    triangles.clear();
    corners.clear();
    for (const auto& t : kept) {
      if (std::max({t[0], t[1], t[2]}) >= load.points.size())
        throw inputError("block task " + std::to_string(k) + "'s triangles are damaged",
                         fileLocation(path.string()), "remove the file and run the task again");
      triangles.push_back({load.global[t[0]], load.global[t[1]], load.global[t[2]]});
      for (const std::uint32_t c : t) corners.push_back(load.points[c]);
    }
    writer.addTriangles(triangles, corners);
    ticker.step(k + 1);
  }
  ticker.finish();
  report.triangles = writer.triangleCount();
  if (report.triangles == 0) {
    const double w = report.extent.x1 - report.extent.x0, h = report.extent.y1 - report.extent.y0;
    throw geometryError(
        "no triangle has a circumradius within " + std::to_string(layout.radius) + " m", {},
        "give a larger --max-circumradius (the points' mean spacing is " +
            std::to_string(std::sqrt(std::max(w * h, 0.0) / double(report.vertices))) + " m)");
  }
  std::vector<TinFeature> features;
  for (const auto& source : layout.sources) features.push_back({FeatureKind::Other, source});
  writer.commit(features);
  report.times.push_back({"assemble", clock.lap()});
  report.totalSeconds = 0;
  for (const auto& t : report.times) report.totalSeconds += t.seconds;
  return report;
}

BlockTinReport buildTinByBlocks(const std::vector<PointSource>& sources,
                                const std::filesystem::path& output, const BlockTinOptions& options,
                                const Progress* progress) {
  const ScratchDir scratch(output);
  prepareBlocks(sources, scratch.path(), options, progress);
  Stopwatch clock;
  const std::size_t tasks = blockTasks(scratch.path());
  ProgressTicker ticker(progress, "blocks.triangulate", "", tasks);
  for (std::size_t k = 0; k < tasks; ++k) {
    triangulateBlock(scratch.path(), k, options.threads);
    ticker.step(k + 1);
  }
  ticker.finish();
  const double triangulate = clock.lap();
  BlockTinReport report = assembleBlocks(scratch.path(), output, progress);
  report.times.insert(report.times.end() - 2, {"triangulate", triangulate});
  report.totalSeconds += triangulate;
  return report;
}

std::string BlockTinReport::summary() const {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "TIN built by blocks\n";
  s << "  input: " << inputPoints << " points, " << duplicates << " exact duplicates dropped\n";
  s << "  blocks: " << blocks << " with points of " << gridBlocks << ", " << blockSide
    << " m square; each triangulated with the points within " << 2 * maxCircumradius
    << " m of it: at most " << largestTriangulated << " points, "
    << (vertices ? double(triangulated) / double(vertices) : 0.0) << "x the vertices in all\n";
  s << "  result: " << vertices << " vertices, " << triangles << " triangles; " << leftOut
    << " Delaunay triangles with a circumradius over " << maxCircumradius << " m left out\n";
  s << std::setprecision(3) << "  extent: x " << extent.x0 << " .. " << extent.x1 << ", y "
    << extent.y0 << " .. " << extent.y1 << "; z " << zMin << " .. " << zMax << " m\n";
  s << "  time:";
  for (const auto& t : times) s << " " << t.stage << " " << t.seconds << " s;";
  s << " total " << totalSeconds << " s\n";
  return s.str();
}

std::string BlockTinReport::toJson() const {
  nlohmann::ordered_json j;
  j["inputPoints"] = inputPoints;
  j["duplicates"] = duplicates;
  j["vertices"] = vertices;
  j["triangles"] = triangles;
  j["leftOut"] = leftOut;
  j["maxCircumradius"] = maxCircumradius;
  j["blocks"] = {{"withPoints", blocks},
                 {"grid", gridBlocks},
                 {"side", blockSide},
                 {"largestTriangulated", largestTriangulated},
                 {"triangulated", triangulated}};
  j["extent"] = {extent.x0, extent.y0, extent.x1, extent.y1};
  j["z"] = {zMin, zMax};
  nlohmann::ordered_json times = nlohmann::ordered_json::object();
  for (const auto& t : this->times) times[t.stage] = t.seconds;
  j["seconds"] = times;
  j["totalSeconds"] = totalSeconds;
  return j.dump(2) + "\n";
}

}  // namespace tinsmith::ingest
