// The block-by-block TIN (block_tin.hpp): spool, bucket, deduplicate, write
// the vertices, triangulate each block with its surroundings.
#include "ingest/build/block_tin.hpp"

#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/geometry/predicates.hpp"
#include "core/tin/tin_data.hpp"
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
  const bool ok =
      f && std::fwrite(points.data(), sizeof(Point3), points.size(), f) == points.size();
  if (f && std::fclose(f) != 0 && ok)
    throw ioError("cannot write a scratch file", fileLocation(path.string()), "is the disk full?");
  if (!ok)
    throw ioError("cannot write a scratch file", fileLocation(path.string()), "is the disk full?");
}

std::vector<Point3> readPoints(const std::filesystem::path& path) {
  std::vector<Point3> points;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return points;  // a block without points has no file
  points.resize(size / sizeof(Point3));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  const bool ok = f && std::fread(points.data(), sizeof(Point3), points.size(), f) == points.size();
  if (f) std::fclose(f);
  if (!ok) throw ioError("cannot read a scratch file", fileLocation(path.string()));
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

}  // namespace

double circumradius(Point2 a, Point2 b, Point2 c) {
  return circumcircle(a, b, c).radius;
}

BlockTinReport buildTinByBlocks(const std::vector<PointSource>& sources,
                                const std::filesystem::path& output, const BlockTinOptions& options,
                                const Progress* progress) {
  if (!(options.maxCircumradius >= 0) || !std::isfinite(options.maxCircumradius))
    throw usageError("the largest circumradius must be a length in metres greater than 0");
  if (options.blockPoints < 16) throw usageError("a block must hold at least 16 points");
  BlockTinReport report;
  Stopwatch clock;
  const ScratchDir scratch(output);
  const auto spool = scratch.path() / "points.bin";

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
  BlockGrid grid;
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
  report.gridBlocks = grid.count();
  const double spacing = std::sqrt(std::max(w * h, 0.0) / double(report.inputPoints));
  report.maxCircumradius = options.maxCircumradius > 0 ? options.maxCircumradius : 8 * spacing;
  if (!(report.maxCircumradius > 0))
    throw geometryError("the points lie on one line: no triangle", {}, "give points that span an area");
  report.blockSide = grid.side;

  // Bucket: each point into its block's file.
  const auto bucket = [&](std::size_t b) {
    return scratch.path() / ("block-" + std::to_string(b) + ".bin");
  };
  {
    std::vector<std::vector<Point3>> buffers(grid.count());
    const std::size_t flushAt = std::clamp<std::size_t>(
        (std::size_t{32} << 20) / sizeof(Point3) / grid.count(), 256, 1 << 16);
    ProgressTicker ticker(progress, "blocks.bucket", "", report.inputPoints);
    std::size_t done = 0;
    forEachChunk(spool, [&](std::span<const Point3> points) {
      for (const Point3& p : points) {
        const std::size_t b = grid.blockOf(p);
        buffers[b].push_back(p);
        if (buffers[b].size() >= flushAt) {
          appendPoints(bucket(b), buffers[b]);
          buffers[b].clear();
        }
      }
      ticker.step(done += points.size());
    });
    for (std::size_t b = 0; b < buffers.size(); ++b) appendPoints(bucket(b), buffers[b]);
    ticker.finish();
  }
  std::filesystem::remove(spool);
  report.times.push_back({"bucket", clock.lap()});

  // Deduplicate each block; its vertices' first global number.
  std::vector<std::uint64_t> first(grid.count() + 1, 0);
  {
    ProgressTicker ticker(progress, "blocks.deduplicate", "", grid.count());
    for (std::size_t b = 0; b < grid.count(); ++b) {
      std::vector<Point3> points = readPoints(bucket(b));
      if (!points.empty()) ++report.blocks;
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
        std::filesystem::remove(bucket(b));
        appendPoints(bucket(b), points);
      }
      first[b + 1] = first[b] + kept;
      ticker.step(b + 1);
    }
    ticker.finish();
  }
  report.vertices = first.back();
  report.times.push_back({"deduplicate", clock.lap()});

  TinStreamWriter writer(output, options.crs);
  for (std::size_t b = 0; b < grid.count(); ++b) writer.addVertices(readPoints(bucket(b)));
  report.times.push_back({"write vertices", clock.lap()});

  // Triangulate each block with every point within 2R (and a hair) of it.
  const double R = report.maxCircumradius;
  const double reach = 2 * R * (1 + 1e-9) + grid.side * 1e-9;
  {
    ProgressTicker ticker(progress, "blocks.triangulate", "", grid.count());
    std::vector<Point3> points;
    std::vector<std::uint32_t> global;  // per loaded point: its TIN vertex
    std::vector<TinData::Triangle> triangles;
    std::vector<Point3> corners;
    for (std::uint32_t row = 0; row < grid.ny; ++row) {
      for (std::uint32_t column = 0; column < grid.nx; ++column) {
        const std::size_t b = std::size_t{row} * grid.nx + column;
        ticker.step(b);
        const std::size_t own = first[b + 1] - first[b];
        if (own == 0) continue;
        points = readPoints(bucket(b));
        global.resize(own);
        std::iota(global.begin(), global.end(), static_cast<std::uint32_t>(first[b]));
        const tiles::Rect square{grid.x0 + column * grid.side, grid.y0 + row * grid.side,
                                 grid.x0 + (column + 1) * grid.side,
                                 grid.y0 + (row + 1) * grid.side};
        const tiles::Rect around{square.x0 - reach, square.y0 - reach, square.x1 + reach,
                                 square.y1 + reach};
        // The neighbours' blocks the reach meets (one more each way: the
        // block of a point on a square's side is the rounding's).
        const std::uint32_t c0 = grid.column(around.x0), c1 = grid.column(around.x1);
        const std::uint32_t r0 = grid.row(around.y0), r1 = grid.row(around.y1);
        for (std::uint32_t r = r0 > 0 ? r0 - 1 : 0; r <= std::min(r1 + 1, grid.ny - 1); ++r) {
          for (std::uint32_t c = c0 > 0 ? c0 - 1 : 0; c <= std::min(c1 + 1, grid.nx - 1); ++c) {
            const std::size_t o = std::size_t{r} * grid.nx + c;
            if (o == b || first[o + 1] == first[o]) continue;
            const std::vector<Point3> theirs = readPoints(bucket(o));
            for (std::size_t i = 0; i < theirs.size(); ++i) {
              const Point3& p = theirs[i];
              if (p.x < around.x0 || p.x > around.x1 || p.y < around.y0 || p.y > around.y1)
                continue;
              points.push_back(p);
              global.push_back(static_cast<std::uint32_t>(first[o] + i));
            }
          }
        }
        report.triangulated += points.size();
        report.largestTriangulated = std::max(report.largestTriangulated, points.size());
        if (collinear(points)) continue;  // no triangle within reach: none of its own

        CdtOptions cdtOptions;
        cdtOptions.canonicalTies = true;
        cdtOptions.threads = options.threads;
        Cdt cdt(cdtOptions);
        cdt.insertPoints(points);
        cdt.finalize();
        const Mesh& mesh = cdt.mesh();
        std::vector<std::uint32_t> loadedOf(mesh.vertexCount(), 0);
        for (std::uint32_t i = 0; i < points.size(); ++i)
          loadedOf[cdt.meshVertex(VertexId(i)).value] = i;
        triangles.clear();
        corners.clear();
        for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
          const auto v = mesh.vertices(TriangleId(t));
          std::array<std::uint32_t, 3> loaded{loadedOf[v[0].value], loadedOf[v[1].value],
                                              loadedOf[v[2].value]};
          std::uint32_t least = loaded[0];
          for (const std::uint32_t k : {loaded[1], loaded[2]})
            if (lessXY(points[k], points[least])) least = k;
          if (least >= own) continue;  // its least corner's block keeps it
          const Circle circle =
              circumcircle(points[loaded[0]].xy(), points[loaded[1]].xy(), points[loaded[2]].xy());
          if (!(circle.radius <= R)) {
            ++report.leftOut;
            continue;
          }
          // The proof's premise, checked: the circle is inside what was read.
          if (circle.center.x - circle.radius < around.x0 ||
              circle.center.x + circle.radius > around.x1 ||
              circle.center.y - circle.radius < around.y0 ||
              circle.center.y + circle.radius > around.y1)
            throw internalError("a kept triangle's circle leaves its block's surroundings");
          triangles.push_back({global[loaded[0]], global[loaded[1]], global[loaded[2]]});
          for (const std::uint32_t k : loaded) corners.push_back(points[k]);
        }
        writer.addTriangles(triangles, corners);
      }
    }
    ticker.finish();
  }
  report.triangles = writer.triangleCount();
  if (report.triangles == 0)
    throw geometryError(
        "no triangle has a circumradius within " + std::to_string(R) + " m", {},
        "give a larger --max-circumradius (the points' mean spacing is " +
                            std::to_string(spacing) + " m)");
  std::vector<TinFeature> features;
  for (const PointSource& source : sources) features.push_back({FeatureKind::Other, source.name});
  writer.commit(features);
  report.times.push_back({"triangulate", clock.lap()});
  for (const auto& t : report.times) report.totalSeconds += t.seconds;
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
