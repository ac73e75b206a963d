#include "server/app/on_demand.hpp"

#include <chrono>

#include "core/tiles/tileset_json.hpp"

namespace tinsmith::server {

OnDemandTiles::OnDemandTiles(ContentCache& cache, Metrics& metrics, std::FILE* notices)
    : cache_(cache), metrics_(metrics), notices_(notices) {}

std::shared_ptr<const Content> OnDemandTiles::fetch(const Tileset& tileset, const tiles::TileId& id,
                                                    const std::string& cacheKey) {
  if (!tileset.hasTin() || !tileset.references(id)) return nullptr;
  std::promise<std::shared_ptr<const Content>> promise;
  Result result;
  {
    std::lock_guard lock(mutex_);
    // Built and cached since this request missed the cache: no second build.
    if (auto cached = cache_.find(cacheKey)) return cached;
    if (const auto it = inFlight_.find(cacheKey); it != inFlight_.end()) {
      result = it->second;
    } else {
      inFlight_.emplace(cacheKey, promise.get_future().share());
    }
  }
  if (result.valid()) {
    metrics_.countBuildWait();
    return result.get();  // the builder's content, or its exception
  }
  std::shared_ptr<const Content> content;
  try {
    content = build(tileset, id, cacheKey);
    promise.set_value(content);
  } catch (...) {
    promise.set_exception(std::current_exception());
    std::lock_guard lock(mutex_);
    inFlight_.erase(cacheKey);
    throw;
  }
  // Kept (cache and store) before the flight ends: a request that missed
  // both before now finds the flight; one after finds the tile.
  std::lock_guard lock(mutex_);
  inFlight_.erase(cacheKey);
  return content;
}

std::shared_ptr<const Content> OnDemandTiles::build(const Tileset& tileset, const tiles::TileId& id,
                                                    const std::string& cacheKey) {
  const auto start = std::chrono::steady_clock::now();
  auto tile = tileset.rebuilder().build(id);
  metrics_.countTileBuilt(std::chrono::steady_clock::now() - start);
  if (!tile) return nullptr;
  std::string why;
  if (!tileset.keep(tiles::tileContentKey(id), tile->glb, why) && !why.empty() && notices_)
    std::fprintf(notices_,
                 "tinsmith serve: tiles built on demand for '%s' are kept in memory only: %s\n",
                 tileset.id().c_str(), why.c_str());
  auto content = makeContent(std::move(tile->glb), false);
  cache_.insert(cacheKey, content);
  return content;
}

}  // namespace tinsmith::server
