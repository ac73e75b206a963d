// Ingest benchmark: a synthetic GeoPackage of contours, spot heights and break
// lines (made with OGR in a temporary folder, stored in EPSG:4326 so the
// reprojection stage does real work) → read → reproject → clean → TIN build
// (builders.tin: triangulation, flat-triangle repair, validation) → .tin
// file, with wall time and peak memory per stage. As in `tinsmith tin`, the
// .tin file is written from the triangulation's mesh at the end of the TIN
// build (buildTinInto), so the last stage is "TIN build + write .tin"; the
// write's own time and peak are listed with the build's stages.
//
//   ingest_bench [--contour-vertices N] [--spot-heights N] [--breakline-vertices N]
//                [--dir DIR] [--keep]
//
// Stages are entries of a list (see main): each gets the shared BenchContext,
// runs, and is measured apart. Memory: the process peak is getrusage()'s
// ru_maxrss (the kernel's high-water mark of the resident set — the figure
// /usr/bin/time -v reports); "peak so far" is that mark after each stage, so
// the stage that raises it is the one that sets the peak. A stage's own peak
// ("stage peak") comes from a sampler thread reading /proc/self/statm every
// millisecond (it can miss a spike shorter than that; the ru_maxrss column
// cannot). The high-water mark is never reset: resetting it (clear_refs)
// also resets what getrusage() and /usr/bin/time see, which then report only
// the last stage's peak. The TIN build's own stages (from its progress ticks)
// get a stage peak each too.
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>
#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "core/base/allocator.hpp"
#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/build/tin_builder.hpp"
#include "ingest/filters/clean.hpp"
#include "ingest/pipeline/load_layers.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace {

using namespace tinsmith;
using namespace tinsmith::ingest;

struct Sizes {
  long contourVertices = 1000000;
  long spotHeights = 100000;
  long breaklineVertices = 10000;
};

class RssSampler;

/// What the stages share.
struct BenchContext {
  Sizes sizes;
  std::filesystem::path dir;
  std::filesystem::path gpkg;
  ProjectConfig config;
  std::vector<IngestedLayer> layers;
  CleaningReport cleaning;
  std::size_t cleanedVertices = 0;
  BuildResult tin;  ///< the report only: the TIN goes to the file
  double writeSeconds = 0.0;
  RssSampler* sampler = nullptr;
  /// The TIN build's own stages, one per progress tick of the builder (and
  /// the write): name, CPU seconds, peak RSS kB (sampled).
  struct Part {
    std::string name;
    double cpu = 0;
    long peakKb = 0;
  };
  std::vector<Part> buildParts;
};

struct Stage {
  std::string name;
  std::function<void(BenchContext&)> run;
  bool counted = true;  ///< part of the ingest total (generation is not)
};

/// The resident set now, in kB (/proc/self/statm, second field, in pages).
long residentKb(int statmFd) {
  char buf[128];
  const ssize_t n = ::pread(statmFd, buf, sizeof buf - 1, 0);
  if (n <= 0) return -1;
  buf[n] = '\0';
  long size = 0, resident = 0;
  if (std::sscanf(buf, "%ld %ld", &size, &resident) != 2) return -1;
  return resident * (::sysconf(_SC_PAGESIZE) / 1024);
}

/// The process's peak resident set so far, in kB (ru_maxrss).
long maxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

/// Samples the resident set every millisecond on its own thread and keeps
/// the maximum since the last restart(): a stage's own peak, without touching
/// the kernel's high-water mark.
class RssSampler {
 public:
  RssSampler() : fd_(::open("/proc/self/statm", O_RDONLY | O_CLOEXEC)) {
    max_ = now();
    thread_ = std::thread([this] {
      while (!stop_.load(std::memory_order_relaxed)) {
        sample();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
  }
  ~RssSampler() {
    stop_ = true;
    thread_.join();
    if (fd_ >= 0) ::close(fd_);
  }
  RssSampler(const RssSampler&) = delete;
  RssSampler& operator=(const RssSampler&) = delete;
  [[nodiscard]] long now() const { return fd_ >= 0 ? residentKb(fd_) : -1; }
  /// The maximum since the last restart (a sample taken now included); starts anew.
  long restart() {
    sample();
    const long kb = now();
    subMax_ = kb;
    return max_.exchange(kb);
  }
  /// The same for a stage inside a stage: restarts only the inner maximum.
  long restartInner() {
    sample();
    return subMax_.exchange(now());
  }

 private:
  void sample() {
    const long kb = now();
    for (std::atomic<long>* m : {&max_, &subMax_}) {
      long seen = m->load(std::memory_order_relaxed);
      while (kb > seen && !m->compare_exchange_weak(seen, kb)) {
      }
    }
  }
  int fd_;
  std::atomic<long> max_{0};
  std::atomic<long> subMax_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Terrain of the synthetic site: smooth, in metres.
double terrain(double x, double y) {
  return 1600.0 + 0.02 * y + 15.0 * std::sin(x / 700.0) * std::cos(y / 900.0);
}

void generate(BenchContext& ctx) {
  ensureGdalReady();
  auto* driver = GetGDALDriverManager()->GetDriverByName("GPKG");
  std::filesystem::remove(ctx.gpkg);
  std::unique_ptr<GDALDataset> ds(
      driver->Create(ctx.gpkg.string().c_str(), 0, 0, 0, GDT_Unknown, nullptr));
  if (!ds) throw ioError("cannot create the benchmark GeoPackage", {ctx.gpkg.string()});
  OGRSpatialReference utm, geographic;
  utm.importFromEPSG(32612);
  geographic.importFromEPSG(4326);
  utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  geographic.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> toGeographic(
      OGRCreateCoordinateTransformation(&utm, &geographic));
  const double x0 = 420000.0, y0 = 4500000.0;

  // Contours: rows of wavy lines 10 m apart (amplitude 3 m: they never meet),
  // 1000 vertices each, 20 m along.
  const long perLine = 1000;
  const long lines = std::max(1L, ctx.sizes.contourVertices / perLine);
  {
    auto* layer = ds->CreateLayer("contours", &geographic, wkbLineString, nullptr);
    OGRFieldDefn elev("elev", OFTReal);
    layer->CreateField(&elev);
    ds->StartTransaction();
    for (long c = 0; c < lines; ++c) {
      OGRLineString line;
      line.setNumPoints(static_cast<int>(perLine));
      for (long i = 0; i < perLine; ++i) {
        const double x = x0 + static_cast<double>(i) * 20.0;
        const double y =
            y0 + static_cast<double>(c) * 10.0 + 3.0 * std::sin(static_cast<double>(i) / 8.0);
        line.setPoint(static_cast<int>(i), x, y);
      }
      line.transform(toGeographic.get());
      OGRFeature feature(layer->GetLayerDefn());
      feature.SetField("elev", 1600.0 + static_cast<double>(c));
      feature.SetGeometry(&line);
      if (layer->CreateFeature(&feature) != OGRERR_NONE)
        throw ioError("cannot write a benchmark feature");
    }
    ds->CommitTransaction();
  }
  // Spot heights: uniform random, 1% of them repeated exactly.
  const double width = static_cast<double>(perLine) * 20.0;
  const double height = static_cast<double>(lines) * 10.0;
  {
    auto* layer = ds->CreateLayer("spots", &geographic, wkbPoint, nullptr);
    OGRFieldDefn elev("elev", OFTReal);
    layer->CreateField(&elev);
    std::mt19937_64 random(2026);
    std::uniform_real_distribution<double> ux(0.0, width), uy(0.0, height);
    ds->StartTransaction();
    double lastX = x0, lastY = y0;  // the previous point, repeated every 100th
    for (long i = 0; i < ctx.sizes.spotHeights; ++i) {
      double x = x0 + ux(random), y = y0 + uy(random);
      if (i % 100 == 99) x = lastX, y = lastY;
      lastX = x;
      lastY = y;
      OGRPoint p(x, y);
      p.transform(toGeographic.get());
      OGRFeature feature(layer->GetLayerDefn());
      feature.SetField("elev", terrain(x, y));
      feature.SetGeometry(&p);
      if (layer->CreateFeature(&feature) != OGRERR_NONE)
        throw ioError("cannot write a benchmark feature");
    }
    ds->CommitTransaction();
  }
  // Break lines: 3D roads running up the slope, 1000 vertices each.
  {
    auto* layer = ds->CreateLayer("roads", &geographic, wkbLineString25D, nullptr);
    ds->StartTransaction();
    const long roads = std::max(1L, ctx.sizes.breaklineVertices / perLine);
    for (long r = 0; r < roads; ++r) {
      OGRLineString line;
      for (long i = 0; i < perLine; ++i) {
        const double x = x0 + (static_cast<double>(r) + 0.5) * width / static_cast<double>(roads) +
                         40.0 * std::sin(static_cast<double>(i) / 30.0);
        const double y = y0 + static_cast<double>(i) * height / static_cast<double>(perLine);
        line.addPoint(x, y, terrain(x, y));
      }
      line.transform(toGeographic.get());
      OGRFeature feature(layer->GetLayerDefn());
      feature.SetGeometry(&line);
      if (layer->CreateFeature(&feature) != OGRERR_NONE)
        throw ioError("cannot write a benchmark feature");
    }
    ds->CommitTransaction();
  }
  ds.reset();

  const auto toml = ctx.dir / "bench.toml";
  std::ofstream(toml)
      << "[project]\ncrs = \"EPSG:32612\"\n"
      << "[[layer]]\npath = \"bench.gpkg\"\nlayer = \"contours\"\nkind = \"contours\"\nz = "
         "\"elev\"\n"
      << "[[layer]]\npath = \"bench.gpkg\"\nlayer = \"spots\"\nkind = \"points\"\nz = \"elev\"\n"
      << "[[layer]]\npath = \"bench.gpkg\"\nlayer = \"roads\"\nkind = \"road\"\n"
      << "[tin]\nsnap_tolerance = 0.001\n";
  ctx.config = loadProjectConfig(toml);
}

std::size_t countVertices(const std::vector<IngestedLayer>& layers) {
  std::size_t n = 0;
  for (const auto& l : layers) n += l.vertexCount();
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  returnLargeBlocksToSystem();  // as the tinsmith binary does
  BenchContext ctx;
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--contour-vertices")
      ctx.sizes.contourVertices = std::stol(next());
    else if (arg == "--spot-heights")
      ctx.sizes.spotHeights = std::stol(next());
    else if (arg == "--breakline-vertices")
      ctx.sizes.breaklineVertices = std::stol(next());
    else if (arg == "--dir")
      ctx.dir = next();
    else if (arg == "--keep")
      keep = true;
    else {
      std::fprintf(stderr,
                   "usage: ingest_bench [--contour-vertices N] [--spot-heights N] "
                   "[--breakline-vertices N] [--dir DIR] [--keep]\n");
      return 2;
    }
  }
  if (ctx.dir.empty())
    ctx.dir = std::filesystem::temp_directory_path() /
              ("tinsmith-ingest-bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(ctx.dir);
  ctx.gpkg = ctx.dir / "bench.gpkg";

  std::vector<Stage> stages{
      {"generate (not counted)", generate, false},
      {"read", [](BenchContext& c) { c.layers = readLayers(c.config); }},
      {"reproject", [](BenchContext& c) { reprojectLayers(c.layers, c.config.crs); }},
      {"clean",
       [](BenchContext& c) {
         CleanOptions options;
         options.tolerance = c.config.tin.snapTolerance;
         c.cleaning = cleanLayers(c.layers, options);
       }},
      {"TIN build + write .tin",
       [](BenchContext& c) {
         c.cleanedVertices = countVertices(c.layers);
         auto layers = toBuildLayers(std::move(c.layers));
         // Each progress tick of the builder starts one of its stages.
         std::string current;
         double cpuStart = cpuSeconds();
         auto endPart = [&c, &cpuStart](const std::string& name) {
           const long peak = c.sampler->restartInner();
           const double now = cpuSeconds();
           if (!name.empty()) c.buildParts.push_back({name, now - cpuStart, peak});
           cpuStart = now;
         };
         Progress progress;
         progress.callback = [&current, &endPart](std::string_view, std::string_view detail,
                                                  std::uint64_t, std::uint64_t) {
           endPart(current);
           current = detail;
         };
         // As `tinsmith tin` does: the .tin file is written from the
         // triangulation's mesh before the triangulation is freed.
         auto write = [&c, &current, &endPart](const Mesh& mesh) {
           endPart(current);  // "done": the summary after validation
           current.clear();
           const auto start = std::chrono::steady_clock::now();
           writeTinFile(c.dir / "bench.tin", mesh);
           c.writeSeconds =
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
           endPart("write .tin");
         };
         c.sampler->restartInner();
         c.tin.report = buildTinInto(std::move(layers), buildOptionsFrom(c.config), write, &progress);
       }},
  };

  try {
    RssSampler sampler;
    ctx.sampler = &sampler;
    std::printf(
        "| stage | wall s | CPU s | stage peak RSS MB | peak so far MB | RSS after MB |\n"
        "|---|---:|---:|---:|---:|---:|\n");
    double total = 0.0;
    double totalCpu = 0.0;
    double readClean = 0.0, triangulation = 0.0;
    std::size_t inputVertices = 0;
    long baselineKb = -1;  // RSS before the first counted stage: libraries, not data
    for (const auto& stage : stages) {
      if (stage.counted && baselineKb < 0) baselineKb = sampler.now();
      sampler.restart();
      const auto start = std::chrono::steady_clock::now();
      const double cpuStart = cpuSeconds();
      stage.run(ctx);
      const double cpu = cpuSeconds() - cpuStart;
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const long stagePeak = sampler.restart();
      const long peakSoFar = maxRssKb();
      const long rss = sampler.now();
      if (stage.name == "read") inputVertices = countVertices(ctx.layers);
      if (stage.name == "read" || stage.name == "reproject" || stage.name == "clean") readClean += seconds;
      if (stage.name.rfind("TIN build", 0) == 0) triangulation = seconds - ctx.writeSeconds;
      if (stage.counted) {
        total += seconds;
        totalCpu += cpu;
      }
      std::printf("| %s | %.3f | %.3f | %.1f | %.1f | %.1f |\n", stage.name.c_str(), seconds, cpu,
                  stagePeak / 1024.0, peakSoFar / 1024.0, rss / 1024.0);
    }
    // The kernel's high-water mark: exact, and what /usr/bin/time -v reports.
    // The generation stage comes first and stays far below the build's peak.
    const long peakKb = maxRssKb();
    std::printf("| **total (GeoPackage → .tin)** | **%.3f** | **%.3f** | | **%.1f** | |\n\n", total,
                totalCpu, peakKb / 1024.0);
    std::printf("share of the total: read + reproject + clean %.0f%%, TIN build %.0f%%, rest %.0f%%\n",
                100 * readClean / total, 100 * triangulation / total,
                100 * (total - readClean - triangulation) / total);
    std::printf("reading and cleaning / TIN build = %.2f (goal: <= 1)\n", readClean / triangulation);
    std::printf("TIN build stages:");
    for (const auto& t : ctx.tin.report.times) std::printf(" %s %.3f s;", t.stage.c_str(), t.seconds);
    std::printf(" write .tin %.3f s;", ctx.writeSeconds);
    std::printf("\nTIN build stages by progress tick (CPU s, sampled peak RSS MB):");
    for (const auto& part : ctx.buildParts)
      std::printf(" %s %.3f s %.1f MB;", part.name.c_str(), part.cpu, part.peakKb / 1024.0);
    std::printf("\nTIN: %zu vertices, %zu triangles, %zu constrained edges; %zu crossings split, "
                "%zu flat triangles before repair, %zu after\n",
                ctx.tin.report.vertices, ctx.tin.report.triangles, ctx.tin.report.constrainedEdges,
                ctx.tin.report.crossings, ctx.tin.report.flatBefore, ctx.tin.report.flatAfter);
    std::printf("input vertices: %zu (contours %ld, spot heights %ld, break lines %ld)\n",
                inputVertices, ctx.sizes.contourVertices, ctx.sizes.spotHeights,
                ctx.sizes.breaklineVertices);
    std::printf(
        "baseline RSS %.1f MB; peak RSS (ru_maxrss) %.1f MB; above baseline %.1f MB = %.0f bytes "
        "per input vertex\n",
        baselineKb / 1024.0, peakKb / 1024.0, (peakKb - baselineKb) / 1024.0,
        inputVertices ? (peakKb - baselineKb) * 1024.0 / static_cast<double>(inputVertices) : 0.0);
    const auto& r = ctx.cleaning;
    std::printf(
        "cleaning: %llu snapped, %llu repeated vertices, %llu degenerate, %llu points merged (%llu "
        "z conflicts), "
        "%llu points on break-line vertices, %llu contour crossings, %llu self-crossings\n",
        static_cast<unsigned long long>(r.verticesSnapped),
        static_cast<unsigned long long>(r.repeatedVerticesDropped),
        static_cast<unsigned long long>(r.degenerateFeaturesDropped),
        static_cast<unsigned long long>(r.duplicatePointsMerged),
        static_cast<unsigned long long>(r.duplicatePointZConflicts),
        static_cast<unsigned long long>(r.pointsOnBreakLineVertices),
        static_cast<unsigned long long>(r.contourCrossings),
        static_cast<unsigned long long>(r.contourSelfCrossings));
    std::printf("vertices after cleaning: %zu\n", ctx.cleanedVertices);
  } catch (const Error& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
  if (!keep) std::filesystem::remove_all(ctx.dir);
  return 0;
}
