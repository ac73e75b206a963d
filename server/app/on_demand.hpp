// --on-demand: tiles a store lacks but its tileset references, built from the
// store's TIN (ingest/tiles/tile_rebuild.hpp: the bytes `tinsmith tile`
// writes for that id) when first asked for, each once however many requests
// ask at the same time (single flight: the first builds, the others wait for
// its result), then kept: in the memory cache, and written into the store
// when it can be opened for writing (atomically: see Tileset::keep).
//
// A tile the tileset does not reference (outside the pyramid, or under a tile
// that meets the tolerance) is not built: it stays a 404. Builds run on the
// request's I/O thread, so a zoom's first tile (which makes the zoom's fit)
// holds that thread for as long as the fit takes; the tiles after it take
// tens of milliseconds.
#pragma once

#include <cstdio>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "core/tiles/pyramid.hpp"
#include "server/app/content_cache.hpp"
#include "server/app/metrics.hpp"
#include "server/app/tileset_catalog.hpp"

namespace tinsmith::server {

class OnDemandTiles {
 public:
  /// `notices` gets a line when a store cannot be written (once per store);
  /// null: nowhere.
  OnDemandTiles(ContentCache& cache, Metrics& metrics, std::FILE* notices);

  /// The content of tile `id` of `tileset`, which the store lacks: built (or
  /// waited for), kept, and returned; null when the tileset does not
  /// reference the tile, carries no TIN, or the tile holds no terrain.
  /// `cacheKey` is the tile's key in the cache. Throws what the build throws
  /// (to every request waiting for it); the next request tries again.
  std::shared_ptr<const Content> fetch(const Tileset& tileset, const tiles::TileId& id,
                                       const std::string& cacheKey);

 private:
  using Result = std::shared_future<std::shared_ptr<const Content>>;
  std::shared_ptr<const Content> build(const Tileset& tileset, const tiles::TileId& id,
                                       const std::string& cacheKey);

  ContentCache& cache_;
  Metrics& metrics_;
  std::FILE* notices_;
  std::mutex mutex_;
  std::unordered_map<std::string, Result> inFlight_;
};

}  // namespace tinsmith::server
