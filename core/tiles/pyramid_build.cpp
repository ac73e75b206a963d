#include "core/tiles/pyramid_build.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "core/tiles/tile_mosaic.hpp"

namespace tinsmith::tiles {

double skirtDepth(const Tiler& tiler, const TileId& id, double error) {
  return std::max(2.0 * error, tiler.zoomTolerance(id.z));
}

std::optional<std::string> whyNotInPyramid(const Tiler& tiler, const ContentOptions& content,
                                           const TileId& root) {
  for (TileId a = root; a.z > 0;) {
    a = a.parent();
    // Above the mosaic zoom every tile with terrain refines: an ancestor
    // there holds the terrain its zoom-K descendant (checked) holds.
    if (a.z < tiler.mosaicZoom()) break;
    const TileSurface s = tiler.buildTile(a);
    if (s.empty()) return "its ancestor " + a.name() + " holds no terrain";
    const TileRecord r = encodeTile(s, skirtDepth(tiler, a, s.error), content).record;
    if (!tiler.refines(a, r.error, r.reachableError))
      return "its ancestor " + a.name() + " meets the tolerance and has no children";
  }
  return std::nullopt;
}

void requireInPyramid(const Tiler& tiler, const ContentOptions& content, const TileId& root) {
  if (!tiler.geometry().inside(root))
    throw usageError("tile " + root.name() + " is outside the pyramid");
  if (const auto why = whyNotInPyramid(tiler, content, root)) {
    throw usageError("tile " + root.name() + " is not in the pyramid: " + *why,
                     "choose a subtree under a refined tile (tinsmith info lists them)");
  }
}

PyramidSummary buildPyramid(const Tiler& tiler, const ContentOptions& content, const TileId& root,
                            int threads, const PyramidCallbacks& callbacks, int untilZoom) {
  const TileEncoder encode = [&](const TileSurface& s) {
    return encodeTile(s, skirtDepth(tiler, s.id, s.error), content);
  };
  return buildPyramid(tiler, encode, root, threads, callbacks, untilZoom);
}

namespace {

/// The walk down from `level` (tiles of one zoom): each zoom's tiles built
/// on workers, emitted in order, their refined tiles' children the next
/// zoom's. `keep` takes each surface it builds of the first zoom, once it is
/// encoded (on a worker thread).
PyramidSummary walk(const Tiler& tiler, const TileEncoder& encode, std::vector<TileId> level,
                    int threads, const PyramidCallbacks& callbacks, int untilZoom,
                    const std::function<void(TileSurface&&)>& keep) {
  const unsigned workers = resolveThreads(threads);

  PyramidSummary summary;
  if (!level.empty() && level.front().z >= untilZoom) level.clear();
  const int keepZoom = level.empty() ? -1 : level.front().z;
  while (!level.empty()) {
    const int z = level.front().z;
    std::sort(level.begin(), level.end(), rowMajorLess);
    std::vector<std::optional<TileRecord>> records(level.size());
    std::vector<std::optional<TileContent>> built(level.size());
    std::vector<std::size_t> todo;
    for (std::size_t i = 0; i < level.size(); ++i) {
      if (callbacks.existing) records[i] = callbacks.existing(level[i]);
      if (records[i]) {
        ++summary.reused;
      } else {
        todo.push_back(i);
      }
    }
    // Build on workers; emit in order as soon as the prefix is done. A worker
    // stops taking tiles after a failure; the tiles it took are all before
    // any it did not, so the loop below meets the failure before waiting on
    // a tile nobody builds.
    std::atomic<std::size_t> next{0};
    std::vector<std::atomic<bool>> ready(level.size());
    for (std::size_t i = 0; i < level.size(); ++i) ready[i] = records[i].has_value();
    std::exception_ptr failure;
    std::mutex failureMutex;
    std::atomic<bool> stop{false};
    auto work = [&] {
      while (!stop) {
        const std::size_t k = next++;
        if (k >= todo.size()) return;
        const std::size_t i = todo[k];
        try {
          TileSurface s = tiler.buildTile(level[i]);
          if (!s.empty()) built[i] = encode(s);
          if (keep && z == keepZoom) keep(std::move(s));
        } catch (...) {
          std::lock_guard lock(failureMutex);
          if (!failure) failure = std::current_exception();
          stop = true;
        }
        ready[i] = true;
        ready[i].notify_all();
      }
    };
    // The calling thread emits; the pool builds.
    std::vector<std::jthread> pool;
    const auto n = std::min<std::size_t>(workers, std::max<std::size_t>(todo.size(), 1));
    for (std::size_t w = 0; w < n; ++w) pool.emplace_back(work);
    std::vector<TileId> nextLevel;
    std::size_t done = 0;
    for (std::size_t i = 0; i < level.size(); ++i) {
      ready[i].wait(false);
      {
        std::lock_guard lock(failureMutex);
        if (failure) break;
      }
      if (built[i]) {
        records[i] = built[i]->record;
        try {
          if (callbacks.emit) callbacks.emit(*built[i]);
        } catch (...) {
          std::lock_guard lock(failureMutex);
          failure = std::current_exception();
          stop = true;
          break;
        }
        built[i].reset();
        ++summary.built;
      }
      if (callbacks.progress) callbacks.progress(z, ++done, level.size());
      if (!records[i]) continue;  // an empty tile
      summary.records.push_back(*records[i]);
      if (tiler.refines(level[i], records[i]->error, records[i]->reachableError)) {
        for (int c = 0; c < 4; ++c) nextLevel.push_back(level[i].child(c));
      }
    }
    pool.clear();  // joins: `failure` is final after this
    if (failure) std::rethrow_exception(failure);
    level = z + 1 < untilZoom ? std::move(nextLevel) : std::vector<TileId>{};
  }
  return summary;
}

/// The tiles above frame.mosaicZoom from its zoom-K surfaces (row by row,
/// 4^K), each tile encoded by `encoderFor` the mosaic's Tiler.
PyramidSummary topOf(const PyramidFrame& frame, std::vector<TileSurface> zoomK,
                     const std::function<TileEncoder(const Tiler&)>& encoderFor, int threads,
                     const PyramidCallbacks& callbacks, int untilZoom) {
  const int k = frame.mosaicZoom;
  if (k < 1 || zoomK.size() != (std::size_t{1} << (2 * k)))
    throw internalError("buildMosaicTop: " + std::to_string(zoomK.size()) +
                        " surfaces for the mosaic of zoom " + std::to_string(k));
  std::vector<double> errors(zoomK.size());  // by slot
  for (std::size_t i = 0; i < zoomK.size(); ++i) {
    const TileId& id = zoomK[i].id;
    if (!zoomK[i].empty() && (id.z != k || std::size_t{id.y} * (1U << k) + id.x != i))
      throw internalError("buildMosaicTop: surface " + std::to_string(i) + " is of tile " +
                          id.name());
    errors[i] = zoomK[i].error;
  }
  const TileMosaic mosaic = mosaicOf(zoomK, frame.crs);
  decltype(zoomK)().swap(zoomK);
  if (mosaic.tin.triangles.empty()) return {};
  // Each tile's E the largest error of the zoom-K tiles under it.
  const Tiler mosaicTiler(mosaic.tin, mosaicTopOptions(frame, k, k, std::move(errors)));
  return walk(mosaicTiler, encoderFor(mosaicTiler), {TileId{}}, threads, callbacks,
              std::min(untilZoom, k), {});
}

}  // namespace

PyramidSummary buildPyramid(const Tiler& tiler, const TileEncoder& encode, const TileId& root,
                            int threads, const PyramidCallbacks& callbacks, int untilZoom) {
  if (!tiler.geometry().inside(root))
    throw usageError("tile " + root.name() + " is outside the pyramid");
  const int k = tiler.mosaicZoom();
  const auto& handOver = callbacks.mosaicSurface;
  if (root.z >= k) {
    return walk(tiler, encode, {root}, threads, callbacks, untilZoom,
                root.z == k && handOver ? [&](TileSurface&& s) { handOver(s); }
                                        : std::function<void(TileSurface &&)>{});
  }
  if (root.z > 0)
    throw usageError("tile " + root.name() + " lies above the mosaic zoom " + std::to_string(k) +
                     ": it is built only with the whole top");

  // Zoom K and below from the TIN, zoom K's surfaces kept for the mosaic
  // (or handed over, with the top left to the caller).
  const std::uint32_t side = 1U << k;
  std::vector<TileId> roots;
  for (std::uint32_t y = 0; y < side; ++y)
    for (std::uint32_t x = 0; x < side; ++x) roots.push_back({k, x, y});
  if (handOver)
    return walk(tiler, encode, roots, threads, callbacks, untilZoom,
                [&](TileSurface&& s) { handOver(s); });
  const auto slot = [side](const TileId& id) { return std::size_t{id.y} * side + id.x; };
  std::vector<std::optional<TileSurface>> kept(roots.size());
  PyramidSummary below = walk(tiler, encode, roots, threads, callbacks, untilZoom,
                              [&](TileSurface&& s) { kept[slot(s.id)] = std::move(s); });
  // Those the walk did not build (the caller had them, or it stops above
  // zoom K) are built again: the mosaic is of every one. Their progress is
  // zoom K's, reported by the calling thread (one of the workers).
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < kept.size(); ++i)
    if (!kept[i]) missing.push_back(i);
  const auto caller = std::this_thread::get_id();
  std::atomic<std::size_t> next{0}, done{0};
  runWorkers(resolveThreads(threads), [&] {
    for (std::size_t j; (j = next++) < missing.size();) {
      kept[missing[j]] = tiler.buildTile(roots[missing[j]]);
      const std::size_t d = ++done;
      if (callbacks.progress && std::this_thread::get_id() == caller)
        callbacks.progress(k, d, missing.size());
    }
  });
  if (callbacks.progress && !missing.empty()) callbacks.progress(k, missing.size(), missing.size());
  std::vector<TileSurface> surfaces;
  surfaces.reserve(kept.size());
  for (auto& s : kept) surfaces.push_back(std::move(*s));
  decltype(kept)().swap(kept);

  PyramidSummary top = topOf(
      frameOf(tiler), std::move(surfaces), [&](const Tiler&) { return encode; }, threads, callbacks,
      untilZoom);
  top.records.insert(top.records.end(), below.records.begin(), below.records.end());
  top.built += below.built;
  top.reused += below.reused;
  return top;
}

PyramidSummary buildMosaicTop(const PyramidFrame& frame, std::vector<TileSurface> zoomK,
                              const ContentOptions& content, int threads,
                              const PyramidCallbacks& callbacks) {
  return topOf(
      frame, std::move(zoomK),
      [&](const Tiler& mosaicTiler) -> TileEncoder {
        return [&](const TileSurface& s) {
          return encodeTile(s, skirtDepth(mosaicTiler, s.id, s.error), content);
        };
      },
      threads, callbacks, 1 << 20);
}

}  // namespace tinsmith::tiles
