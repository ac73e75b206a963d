// The routes' answers (DESIGN.md "Server"), over a TilesetCatalog: the
// handler the HTTP server calls for every request. HTTP semantics live here
// once for every route: Content-Type, strong ETag and If-None-Match → 304,
// Cache-Control, CORS, brotli or gzip for JSON, HEAD, byte ranges for tiles, 405 with
// Allow, JSON error bodies. handle() never throws: a failure is a response
// (500 for anything unexpected).
//
// Slow work leaves the I/O thread (given a WorkPool): with --on-demand, a
// tile the memory cache lacks (its store read, and its build when the store
// lacks it too); a POST batch of elevations or profiles over
// kDeferBatchBytes; the first break-line GeoJSON of a store. Such a request's
// response is deferred (message.hpp) and answered from a worker, or at once
// 503 with Retry-After when the pool's queue is full. Cached tiles, tileset
// files, /health and /metrics are answered inline.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "server/app/content_cache.hpp"
#include "server/app/metrics.hpp"
#include "server/app/on_demand.hpp"
#include "server/app/tileset_catalog.hpp"
#include "server/app/viewer_assets.hpp"
#include "server/app/work_pool.hpp"
#include "server/http/message.hpp"

namespace tinsmith::server {

struct ServiceOptions {
  std::string cors = "*";  ///< Access-Control-Allow-Origin; empty: no CORS headers
  std::size_t cacheBytes = 256u << 20;
  /// Build tiles the store lacks from its TIN (server/app/on_demand.hpp).
  bool onDemand = false;
  /// Where on-demand notices go (a store kept in memory only); null: nowhere.
  std::FILE* notices = stderr;
  /// The viewer's pages and libraries (/, /three, /viewer/…); null: none,
  /// and "/" lists the stores and says what to install.
  std::shared_ptr<const ViewerAssets> viewer;
  /// "" or a path prefix ("/maps/terrain": no trailing '/') under which
  /// every route answers (a reverse proxy's location); see
  /// normalizeBasePath().
  std::string basePath;
};

/// A --base-path value as ServiceOptions keeps it: "" for "" or "/";
/// "/a/b" for "/a/b/" or "a/b". Throws usageError unless every segment is
/// 1-64 of [A-Za-z0-9._~-] and not "." or "..".
std::string normalizeBasePath(std::string_view text);

/// POST bodies from this size on are answered on the worker pool.
inline constexpr std::size_t kDeferBatchBytes = 4096;
/// Retry-After of a 503 for a full queue, seconds.
inline constexpr int kBusyRetrySeconds = 1;

/// Cache-Control values: tiles change only when their store is rebuilt;
/// tileset files and the list may change with it, so they are short.
inline constexpr const char* kTileCacheControl = "public, max-age=86400";
inline constexpr const char* kTilesetCacheControl = "public, max-age=60, must-revalidate";

/// The CORS headers every response carries for Access-Control-Allow-Origin
/// `cors` (TileServiceOptions::cors); none when it is empty.
std::vector<std::pair<std::string, std::string>> corsHeaders(const std::string& cors);

class TileService {
 public:
  /// `pool` (null: slow work runs inline) must outlive the responses this
  /// defers to it.
  TileService(const TilesetCatalog& catalog, Metrics& metrics, ServiceOptions options,
              WorkPool* pool = nullptr);
  [[nodiscard]] Response handle(const Request& request);

 private:
  /// The /tilesets body and the index page, rebuilt when the catalog swapped
  /// a store in.
  struct Listing {
    std::uint64_t version = 0;
    std::shared_ptr<const Content> tilesets, index, threeFallback;
  };
  std::shared_ptr<const Listing> listing();

  Response dispatch(const Request& request, const RequestTarget& target, const Route& route);
  /// What handle() does to every answer: its route, HEAD, CORS.
  void finish(Response& response, RouteKind route, bool head) const;
  /// `work`'s answer to `request`, deferred to the pool (inline without
  /// one); `work` runs on a worker with a copy of the request, so it holds
  /// what else it reads (the Tileset).
  Response onPool(const Request& request, RouteKind route,
                  std::function<Response(const Request&)> work);
  /// A POST batch: answered inline when its body is small, else on the pool.
  Response batch(const Request& request, RouteKind route,
                 std::function<Response(const Request&)> answer);
  /// `tile`: the tile whose content `key` is; null for a tileset file.
  Response serveStored(const Request& request, const std::shared_ptr<const Tileset>& tileset,
                       const std::string& key, const tiles::TileId* tile);
  /// serveStored past a cache miss: the store, then (--on-demand) a build.
  Response serveUncached(const Request& request, const Tileset& tileset, const std::string& key,
                         const tiles::TileId* tile, const std::string& cacheKey);
  /// A tile (`tile`) or tileset file: its content type and Cache-Control.
  Response serveStoredContent(const Request& request, const Content& content, bool tile) const;
  /// A Cesium terrain tile with the extensions the request's Accept asks
  /// for (the store holds every one), gzipped when accepted.
  Response serveTerrainTile(const Request& request, const std::shared_ptr<const Tileset>& tileset,
                            const tiles::TileId& gridTile);
  Response serveContent(const Request& request, const Content& content, const char* contentType,
                        const char* cacheControl, bool ranges) const;
  Response serveViewer(const Request& request, const std::string& asset, bool page);
  Response serveLines(const Request& request, const std::shared_ptr<const Tileset>& tileset);
  Response serveJson(const Request& request, const std::string& json, const char* cacheControl) const;
  void addCors(Response& response) const;

  const TilesetCatalog& catalog_;
  Metrics& metrics_;
  ServiceOptions options_;
  WorkPool* pool_;
  ContentCache cache_;
  OnDemandTiles onDemand_;
  std::mutex listingMutex_;
  std::shared_ptr<const Listing> listing_;
};

}  // namespace tinsmith::server
