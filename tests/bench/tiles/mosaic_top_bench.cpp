// The top of the pyramid fitted to the mosaic of a zoom's tiles instead of
// the TIN (issue 24's second step, docs/benchmarks.md): what it costs and
// whether its tiles keep their tolerance against the TIN itself.
//
//   mosaic_top_bench SITE.tin TOLERANCE K [M [THREADS [MAX_TRIANGLES]]]
//
// Tiles SITE.tin as `tinsmith tile --tolerance TOLERANCE` plans it (ECEF,
// Draco). Builds every zoom-M tile (M ≥ K, by default K), joins them
// (tiles::mosaicOf), and builds every tile above zoom K twice: from the
// TIN, as today, and from the mosaic with a Tiler of the same pyramid
// (fixed: the same square, finest zoom and tolerances; mosaicError E, the
// largest error of the zoom-M tiles under a tile: refined to its zoom's
// tolerance less E, declaring its error against the mosaic plus E). Each
// tile of both is then measured
// against SITE.tin exactly (tiles::maxVerticalDifference, vertical, before
// encoding): the mosaic's must be within what it declares. Prints a line
// per tile and a summary; exits 1 when a mosaic tile is over its
// declaration. Never run by ctest.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base/parallel.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tile_mosaic.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tinfile/tin_file.hpp"

using namespace tinsmith;
using tiles::TileId;

namespace {

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

/// `build(i)` for i < n on `threads` threads (runWorkers: an exception is
/// rethrown here).
template <class F>
void parallelFor(std::size_t n, int threads, F&& build) {
  std::atomic<std::size_t> next{0};
  runWorkers(resolveThreads(threads), [&] {
    for (std::size_t i; (i = next++) < n;) build(i);
  });
}

struct Built {
  TileId id;
  std::size_t triangles = 0, bytes = 0;
  double declared = 0, reachable = 0, measured = 0, allowance = 0;
  bool empty = true;
};

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: mosaic_top_bench SITE.tin TOLERANCE K [M [THREADS [MAX_TRIANGLES]]]\n");
    return 2;
  }
  const TinData tin = ingest::readTinFile(argv[1]);
  const double tolerance = std::atof(argv[2]);
  const int k = std::atoi(argv[3]);
  const int m = argc > 4 ? std::atoi(argv[4]) : k;
  const int threads = argc > 5 ? std::atoi(argv[5]) : 2;
  if (m < k) throw std::invalid_argument("M must be at least K");
  const ingest::ProjGeoReference geo(tin.crs, "");
  tiles::TilerOptions options;
  options.tolerance = tolerance;
  if (argc > 6) options.maxTriangles = std::strtoul(argv[6], nullptr, 10);
  options.threads = threads;
  options.geo = &geo;
  const tiles::Tiler tiler(tin, options);
  tiles::ContentOptions content;
  content.geo = &geo;
  std::printf("TIN %zu vertices, %zu triangles; finest zoom %d, K = %d, M = %d\n",
              tin.vertices.size(), tin.triangles.size(), tiler.finestZoom(), k, m);

  // The zoom-M tiles, as the subtree shards build them.
  auto start = std::chrono::steady_clock::now();
  const std::uint32_t side = 1U << m;
  std::vector<tiles::TileSurface> zoomM(std::size_t{side} * side);
  parallelFor(zoomM.size(), threads, [&](std::size_t i) {
    zoomM[i] = tiler.buildTile(
        {m, static_cast<std::uint32_t>(i % side), static_cast<std::uint32_t>(i / side)});
  });
  const double zoomMSeconds = secondsSince(start);
  const tiles::TileMosaic mosaic = tiles::mosaicOf(zoomM, tin.crs);
  std::printf(
      "zoom %d: %zu tiles in %.2f s; mosaic %zu vertices, %zu triangles, %zu line edges, "
      "largest tile error %.3f m\n",
      m, zoomM.size(), zoomMSeconds, mosaic.tin.vertices.size(), mosaic.tin.triangles.size(),
      mosaic.tin.constrainedEdges.size(), mosaic.maxError);
  std::vector<TileId> top;
  for (int z = 0; z < k; ++z)
    for (std::uint32_t y = 0; y < (1U << z); ++y)
      for (std::uint32_t x = 0; x < (1U << z); ++x) top.push_back({z, x, y});
  const tiles::TinIndex index(tin);
  const auto measure = [&](const tiles::TileSurface& s) {
    return tiles::maxVerticalDifference(s.vertices, s.triangles, index).maxAbs;
  };

  // Today's top: from the TIN.
  std::vector<Built> today(top.size());
  std::vector<tiles::TileSurface> todaySurfaces(top.size());
  start = std::chrono::steady_clock::now();
  parallelFor(top.size(), threads, [&](std::size_t i) {
    tiles::TileSurface& s = todaySurfaces[i];
    s = tiler.buildTile(top[i]);
    Built& b = today[i];
    b.id = top[i];
    if (s.empty()) return;
    const auto c = tiles::encodeTile(s, tiles::skirtDepth(tiler, s.id, s.error), content);
    b = {top[i], s.triangles.size(), c.glb.size(), c.record.error, c.record.reachableError, 0, 0,
         false};
  });
  const double todaySeconds = secondsSince(start);

  // The top from the mosaic.
  start = std::chrono::steady_clock::now();
  std::vector<double> errors;  // of the zoom-M tiles, row by row
  for (const auto& t : zoomM) errors.push_back(t.error);
  const tiles::TilerOptions mosaicOptions =
      tiles::mosaicTopOptions(tiles::frameOf(tiler), k, m, std::move(errors));
  const tiles::Tiler mosaicTiler(mosaic.tin, mosaicOptions);
  std::vector<Built> fromMosaic(top.size());
  std::vector<tiles::TileSurface> mosaicSurfaces(top.size());
  parallelFor(top.size(), threads, [&](std::size_t i) {
    const double e = mosaicOptions.mosaicError(top[i]);
    tiles::TileSurface s = mosaicTiler.buildTile(top[i]);
    Built& b = fromMosaic[i];
    b.id = top[i];
    if (s.empty()) return;
    const auto c = tiles::encodeTile(s, tiles::skirtDepth(mosaicTiler, s.id, s.error), content);
    b = {top[i], s.triangles.size(), c.glb.size(), c.record.error, c.record.reachableError, 0, e,
         false};
    mosaicSurfaces[i] = std::move(s);
  });
  const double mosaicSeconds = secondsSince(start);

  // Both measured against the TIN itself.
  parallelFor(top.size(), threads, [&](std::size_t i) {
    if (!fromMosaic[i].empty) fromMosaic[i].measured = measure(mosaicSurfaces[i]);
    if (!today[i].empty) today[i].measured = measure(todaySurfaces[i]);
  });
  int over = 0;
  std::printf(
      "\n| tile | zoom tolerance | today: triangles / bytes / declared / measured vs TIN "
      "| from the mosaic: E / triangles / bytes / declared (reachable) / measured vs TIN |\n"
      "|---|---|---|---|\n");
  std::size_t todayTriangles = 0, mosaicTriangles = 0, todayBytes = 0, mosaicBytes = 0;
  for (std::size_t i = 0; i < top.size(); ++i) {
    const Built& a = today[i];
    const Built& b = fromMosaic[i];
    if (a.empty && b.empty) continue;
    const bool bad = b.measured > b.declared;
    over += bad;
    todayTriangles += a.triangles;
    mosaicTriangles += b.triangles;
    todayBytes += a.bytes;
    mosaicBytes += b.bytes;
    std::printf(
        "| %s | %.2f | %zu / %zu / %.2f / %.2f | %.2f / %zu / %zu / %.2f (%.2f) / %.2f%s |\n",
        top[i].name().c_str(), tiler.zoomTolerance(top[i].z), a.triangles, a.bytes, a.declared,
        a.measured, b.allowance, b.triangles, b.bytes, b.declared, b.reachable, b.measured,
        bad ? " OVER" : "");
  }
  std::printf(
      "\ntop tiles: today %zu triangles, %zu bytes in %.2f s (the whole-TIN Tiler's "
      "top tiles); from the mosaic %zu triangles, %zu bytes in %.2f s (its Tiler "
      "made and its tiles); %d over their declaration\n",
      todayTriangles, todayBytes, todaySeconds, mosaicTriangles, mosaicBytes, mosaicSeconds, over);
  return over ? 1 : 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "mosaic_top_bench: %s\n", e.what());
  return 2;
}
