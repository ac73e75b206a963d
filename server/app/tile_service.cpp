#include "server/app/tile_service.hpp"

#include "core/base/error.hpp"
#include "core/encode/quantized_mesh.hpp"
#include "core/tiles/tileset_json.hpp"
#include "server/app/break_lines.hpp"
#include "server/app/elevation.hpp"
#include "server/app/index_page.hpp"
#include "server/http/error_status.hpp"
#include "server/http/representation.hpp"

namespace tinsmith::server {

namespace {

constexpr const char* kJson = "application/json";
constexpr std::size_t kGzipAtLeast = 1024;  // smaller JSON is not worth compressing

std::string allowFor(RouteKind route) {
  return routeAllowsPost(route) ? "GET, HEAD, POST, OPTIONS" : "GET, HEAD, OPTIONS";
}

Response notFound(const std::string& message) {
  return errorResponse(404, ErrorKind::Input, message);
}

/// A 500 whose details (store paths, library messages) go to the log only.
Response internalFailure(ErrorKind kind, const std::string& what) {
  Response r = errorResponse(500, kind, "the server failed to answer; its log has the details");
  r.failure = what;
  return r;
}

/// f()'s response, or the response for what it threw.
template <class F>
Response guarded(F&& f) {
  try {
    return f();
  } catch (const ParameterError& e) {
    return errorResponse(400, ErrorKind::Input, e.what(), e.parameter);
  } catch (const Error& e) {
    const int status = httpStatusFor(e.kind());
    return status >= 500 ? internalFailure(e.kind(), e.what())
                         : errorResponse(status, e.kind(), e.what());
  } catch (const std::exception& e) {
    return internalFailure(ErrorKind::Internal, e.what());
  }
}

Response busy() {
  Response r = errorResponse(503, ErrorKind::Internal,
                             "the server is busy with other slow requests (tile builds, large "
                             "batches); try again in a moment");
  r.addHeader("Retry-After", std::to_string(kBusyRetrySeconds));
  return r;
}

Response redirect(const std::string& location) {
  Response r = errorResponse(301, ErrorKind::Input, "moved to " + location);
  r.addHeader("Location", location);
  return r;
}

/// The part of `target` under `base`: "/…" for "/base/…" (all of it when
/// base is ""), "" for "/base" and "/base?…" (to be redirected to "/base/"),
/// nullopt when the target is not under base.
std::optional<std::string_view> underBase(std::string_view target, const std::string& base) {
  if (base.empty()) return target;
  if (!target.starts_with(base)) return std::nullopt;
  target.remove_prefix(base.size());
  if (target.empty() || target.front() == '?') return std::string_view{};
  if (target.front() != '/') return std::nullopt;  // "/basement" is not under "/base"
  return target;
}

constexpr const char* kNoViewer =
    "The viewer is not installed, so this page only lists what the server holds. "
    "Install its files with tools/setup.sh (npm ci in server/viewer) and restart, "
    "or give tinsmith serve --viewer DIR (a folder holding index.html and node_modules; "
    "the Docker image has it in /usr/share/tinsmith/viewer).";
constexpr const char* kNoThree =
    "The three.js viewer's libraries (three, 3d-tiles-renderer) are not installed: "
    "run tools/setup.sh (npm ci in server/viewer), or give tinsmith serve --viewer DIR.";

}  // namespace

std::string normalizeBasePath(std::string_view text) {
  std::string out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t slash = text.find('/', at);
    const std::string_view segment =
        text.substr(at, slash == std::string_view::npos ? slash : slash - at);
    at = slash == std::string_view::npos ? text.size() : slash + 1;
    if (segment.empty()) {
      if (at == 1 || at == text.size()) continue;  // a leading or trailing '/'
      throw usageError("--base-path '" + std::string(text) + "' has an empty segment",
                       "write /a/b");
    }
    const bool ok = segment.size() <= 64 && segment != "." && segment != ".." &&
                    segment.find_first_not_of(
                        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                        "0123456789._~-") == std::string_view::npos;
    if (!ok)
      throw usageError("--base-path '" + std::string(text) + "': '" + std::string(segment) +
                           "' is not a plain path segment",
                       "use letters, digits and . _ ~ - between the slashes");
    out += "/";
    out += segment;
  }
  return out;
}

TileService::TileService(const TilesetCatalog& catalog, Metrics& metrics, ServiceOptions options,
                         WorkPool* pool)
    : catalog_(catalog),
      metrics_(metrics),
      options_(std::move(options)),
      pool_(pool),
      cache_(options_.cacheBytes),
      onDemand_(cache_, metrics_, options_.notices) {}

std::shared_ptr<const TileService::Listing> TileService::listing() {
  std::lock_guard lock(listingMutex_);
  const std::uint64_t version = catalog_.version();
  if (listing_ && listing_->version == version) return listing_;
  auto fresh = std::make_shared<Listing>();
  fresh->version = version;
  const auto tilesets = catalog_.tilesets();
  nlohmann::ordered_json list;
  list["tilesets"] = nlohmann::ordered_json::array();
  for (const auto& t : tilesets) {
    auto summary = t->summary();
    if (!options_.basePath.empty() && summary.contains("links"))
      for (auto& [name, link] : summary["links"].items())
        if (link.is_string()) link = options_.basePath + link.get<std::string>();
    list["tilesets"].push_back(std::move(summary));
  }
  fresh->tilesets = makeContent(list.dump(2) + "\n", true);
  const bool cesium = options_.viewer && options_.viewer->hasCesium();
  fresh->index =
      makeContent(indexPageHtml(tilesets, options_.basePath, cesium ? "" : kNoViewer), true);
  fresh->threeFallback = makeContent(indexPageHtml(tilesets, options_.basePath, kNoThree), true);
  listing_ = std::move(fresh);
  return listing_;
}

Response TileService::handle(const Request& request) {
  RouteKind kind = RouteKind::Unknown;
  Response response = guarded([&] {
    const auto rest = underBase(request.target, options_.basePath);
    const auto target = rest && !rest->empty() ? parseRequestTarget(*rest) : std::nullopt;
    if (!rest) return notFound("this server answers under " + options_.basePath + "/ only");
    if (rest->empty() && !options_.basePath.empty()) {
      kind = RouteKind::Index;
      return redirect(options_.basePath + "/" + request.target.substr(options_.basePath.size()));
    }
    if (!target)
      return errorResponse(400, ErrorKind::Input,
                           "malformed request target (bad escape, '..', '\\', NUL or "
                           "control byte, empty segment)",
                           "target");
    auto matched = matchRoute(*target);
    if (auto* error = std::get_if<RouteError>(&matched))
      return errorResponse(400, ErrorKind::Input, error->message, error->parameter);
    const Route& route = std::get<Route>(matched);
    kind = route.kind;
    return dispatch(request, *target, route);
  });
  finish(response, kind, request.method == "HEAD");
  return response;
}

void TileService::finish(Response& response, RouteKind route, bool head) const {
  response.route = route;
  response.head = head;
  addCors(response);
}

Response TileService::onPool(const Request& request, RouteKind route,
                             std::function<Response(const Request&)> work) {
  if (!pool_) return work(request);
  const bool head = request.method == "HEAD";
  // The request outlives this call (the connection's copy is reused for its
  // next request): the task keeps its own.
  auto held = std::make_shared<const Request>(request);
  Response later;
  later.deferred = [this, route, head, held, work = std::move(work)](Responder done) {
    const bool taken = pool_->trySubmit([this, route, head, held, work, done] {
      Response answer = guarded([&] { return work(*held); });
      finish(answer, route, head);
      done(std::move(answer));
    });
    if (taken) return;
    Response refused = busy();
    finish(refused, route, head);
    done(std::move(refused));
  };
  return later;
}

std::vector<std::pair<std::string, std::string>> corsHeaders(const std::string& cors) {
  if (cors.empty()) return {};
  std::vector<std::pair<std::string, std::string>> out{
      {"Access-Control-Allow-Origin", cors},
      {"Access-Control-Expose-Headers", "ETag, Content-Length, Content-Range"}};
  if (cors != "*") out.emplace_back("Vary", "Origin");
  return out;
}

void TileService::addCors(Response& response) const {
  for (auto& [name, value] : corsHeaders(options_.cors)) response.addHeader(name, value);
}

Response TileService::dispatch(const Request& request, const RequestTarget& target,
                               const Route& route) {
  if (route.kind == RouteKind::Unknown)
    return notFound("no route for this path (see / for what this server holds)");
  const std::string& method = request.method;
  if (method == "OPTIONS") {  // CORS preflight
    Response r;
    r.status = 204;
    r.addHeader("Allow", allowFor(route.kind));
    if (!options_.cors.empty()) {
      r.addHeader("Access-Control-Allow-Methods", allowFor(route.kind));
      r.addHeader("Access-Control-Allow-Headers",
                  "Accept, Accept-Encoding, Content-Type, If-None-Match, Range");
      r.addHeader("Access-Control-Max-Age", "86400");
    }
    return r;
  }
  const bool post = method == "POST" && routeAllowsPost(route.kind);
  if (method != "GET" && method != "HEAD" && !post) {
    Response r = errorResponse(405, ErrorKind::Input,
                               "method " + method.substr(0, 32) + " is not allowed here");
    r.addHeader("Allow", allowFor(route.kind));
    return r;
  }

  switch (route.kind) {
    case RouteKind::Index:
      if (options_.viewer && options_.viewer->hasCesium())
        return serveViewer(request, "viewer/index.html", true);
      return serveContent(request, *listing()->index, "text/html; charset=utf-8", "no-cache",
                          false);
    case RouteKind::ThreePage:
      if (options_.viewer && options_.viewer->hasThree())
        return serveViewer(request, "viewer/three.html", true);
      return serveContent(request, *listing()->threeFallback, "text/html; charset=utf-8",
                          "no-cache", false);
    case RouteKind::ViewerAsset:
      return serveViewer(request, route.asset, false);
    case RouteKind::Health: {
      Response r;
      r.addHeader("Content-Type", kJson);
      r.addHeader("Cache-Control", "no-store");
      r.setBody("{\"status\":\"ok\",\"tilesets\":" + std::to_string(catalog_.tilesets().size()) +
                "}\n");
      return r;
    }
    case RouteKind::Metrics: {
      Response r;
      r.addHeader("Content-Type", "text/plain; version=0.0.4; charset=utf-8");
      r.addHeader("Cache-Control", "no-store");
      r.setBody(metrics_.prometheusText());
      return r;
    }
    case RouteKind::Tilesets:
      return serveContent(request, *listing()->tilesets, kJson, "no-cache", false);
    default:
      break;
  }

  const auto tileset = catalog_.find(route.tileset);  // held for the whole request
  if (!tileset) return notFound("no tileset '" + route.tileset + "' (see /tilesets)");
  switch (route.kind) {
    case RouteKind::TilesetJson:
      return serveStored(request, tileset, "tileset.json", nullptr);
    case RouteKind::ExternalTileset:
    case RouteKind::Tile: {
      const bool tile = route.kind == RouteKind::Tile;
      if (route.outsidePyramid || route.tile.z > tileset->maxZoom())
        return notFound("the tile is outside the pyramid of '" + tileset->id() + "' (zooms 0 to " +
                        std::to_string(tileset->maxZoom()) + ")");
      const std::string key =
          tile ? tiles::tileContentKey(route.tile) : "tilesets/" + route.tile.name() + ".json";
      return serveStored(request, tileset, key, tile ? &route.tile : nullptr);
    }
    case RouteKind::TerrainLayer:
    case RouteKind::TerrainTile:
      if (!tileset->hasTerrain())
        return notFound("tileset '" + tileset->id() +
                        "' holds no Cesium terrain (tinsmith tile --scheme both makes it)");
      if (route.kind == RouteKind::TerrainLayer)
        return serveStored(request, tileset, "terrain/layer.json", nullptr);
      if (route.outsidePyramid)
        return notFound("the tile is outside the geographic grid (2^(z+1) columns, 2^z rows)");
      return serveTerrainTile(request, tileset, route.tile);
    case RouteKind::Elevation:
    case RouteKind::Profile:
      if (!tileset->hasTin())
        return notFound("tileset '" + tileset->id() + "' carries no TIN, so it has no elevations");
      break;
    case RouteKind::Lines:
      if (!tileset->hasTin())
        return notFound("tileset '" + tileset->id() + "' carries no TIN, so it has no break lines");
      return serveLines(request, tileset);
    default:
      break;
  }
  switch (route.kind) {
    case RouteKind::Elevation: {
      if (post)
        return batch(request, route.kind, [this, tileset](const Request& r) {
          return serveJson(r, elevationBatch(*tileset, r.body).dump(), "no-store");
        });
      auto answer = elevationAt(*tileset, target);
      if (answer["z"].is_null())
        return notFound("the point is outside the TIN of '" + tileset->id() + "'");
      return serveJson(request, answer.dump(), kTilesetCacheControl);
    }
    case RouteKind::Profile: {
      if (post)
        return batch(request, route.kind, [this, tileset](const Request& r) {
          return serveJson(r, profileBatch(*tileset, r.body).dump(), "no-store");
        });
      return serveJson(request, profileAlong(*tileset, target).dump(), kTilesetCacheControl);
    }
    default:
      break;
  }
  return notFound("no route for this path");
}

Response TileService::batch(const Request& request, RouteKind route,
                            std::function<Response(const Request&)> answer) {
  if (request.body.size() < kDeferBatchBytes) return answer(request);
  return onPool(request, route, std::move(answer));
}

Response TileService::serveStored(const Request& request,
                                  const std::shared_ptr<const Tileset>& tileset,
                                  const std::string& key, const tiles::TileId* tileId) {
  const bool tile = tileId != nullptr;
  const std::string cacheKey = std::to_string(tileset->generation()) + '/' + key;
  if (const auto content = cache_.find(cacheKey)) {
    metrics_.countCache(true);
    Response r = serveStoredContent(request, *content, tile);
    r.cacheHit = true;
    return r;
  }
  metrics_.countCache(false);
  if (tile && options_.onDemand) {  // the store may lack it: a build of seconds
    return onPool(request, RouteKind::Tile,
                  [this, tileset, key, id = *tileId, cacheKey](const Request& r) {
                    return serveUncached(r, *tileset, key, &id, cacheKey);
                  });
  }
  return serveUncached(request, *tileset, key, tileId, cacheKey);
}

Response TileService::serveUncached(const Request& request, const Tileset& tileset,
                                    const std::string& key, const tiles::TileId* tileId,
                                    const std::string& cacheKey) {
  const bool tile = tileId != nullptr;
  std::shared_ptr<const Content> content;
  auto bytes = tileset.store().get(key);
  if (!bytes && tile && options_.onDemand) {
    content = onDemand_.fetch(tileset, *tileId, cacheKey);
  } else if (bytes) {
    content = makeContent(std::move(*bytes), !tile);
    cache_.insert(cacheKey, content);
  }
  if (!content)
    return notFound("tileset '" + tileset.id() + "' has no " + key +
                    (tile ? " (the pyramid is not refined there)" : ""));
  return serveStoredContent(request, *content, tile);
}

Response TileService::serveStoredContent(const Request& request, const Content& content,
                                         bool tile) const {
  return serveContent(request, content, tile ? "model/gltf-binary" : kJson,
                      tile ? kTileCacheControl : kTilesetCacheControl, tile);
}

Response TileService::serveTerrainTile(const Request& request,
                                       const std::shared_ptr<const Tileset>& tileset,
                                       const tiles::TileId& t) {
  const std::vector<std::uint8_t> extensions = quantizedMeshExtensionsAccepted(request.accept);
  const std::string key = "terrain/" + std::to_string(t.z) + "/" + std::to_string(t.x) + "/" +
                          std::to_string(t.y) + ".terrain";
  std::string cacheKey = std::to_string(tileset->generation()) + '/' + key + '#';
  for (const std::uint8_t e : extensions) cacheKey += std::to_string(e);
  auto serve = [&](const Content& content) {
    Response r =
        serveContent(request, content, "application/vnd.quantized-mesh", kTileCacheControl, true);
    r.addHeader("Vary", "Accept");
    return r;
  };
  if (const auto content = cache_.find(cacheKey)) {
    metrics_.countCache(true);
    Response r = serve(*content);
    r.cacheHit = true;
    return r;
  }
  metrics_.countCache(false);
  const auto bytes = tileset->store().get(key);
  if (!bytes)
    return notFound("tileset '" + tileset->id() + "' has no terrain tile " + t.name() +
                    " (layer.json lists the tiles it has)");
  std::string shipped;
  try {
    shipped = encode::withExtensions(*bytes, extensions);
  } catch (const Error& e) {
    // The request is fine; the store is not.
    return internalFailure(ErrorKind::Io, "tileset '" + tileset->id() + "': the stored " + key +
                                              " is damaged (" + e.what() +
                                              "); rebuild the store's terrain");
  }
  const auto content = makeContent(shipped, true, false);
  cache_.insert(cacheKey, content);
  return serve(*content);
}

Response TileService::serveViewer(const Request& request, const std::string& asset, bool page) {
  const ViewerAssets::Asset* found = options_.viewer ? options_.viewer->find(asset) : nullptr;
  if (!found)
    return notFound(options_.viewer ? "the viewer has no file " + asset
                                    : std::string("the viewer is not installed (see /)"));
  const auto content = options_.viewer->content(*found);
  if (!content) return internalFailure(ErrorKind::Io, "cannot read " + found->file.string());
  return serveContent(request, *content, found->contentType,
                      page || !found->library ? kPageCacheControl : kLibraryCacheControl, false);
}

Response TileService::serveLines(const Request& request,
                                 const std::shared_ptr<const Tileset>& tileset) {
  const std::string cacheKey = std::to_string(tileset->generation()) + "/lines.geojson";
  const auto serve = [this](const Request& r, const Content& content) {
    return serveContent(r, content, "application/geo+json", kTilesetCacheControl, false);
  };
  if (const auto content = cache_.find(cacheKey)) return serve(request, *content);
  // The first time: the whole TIN's break lines, on a worker.
  return onPool(request, RouteKind::Lines, [this, tileset, cacheKey, serve](const Request& r) {
    auto content = makeContent(breakLinesGeoJson(*tileset).dump() + "\n", true);
    cache_.insert(cacheKey, content);
    return serve(r, *content);
  });
}

Response TileService::serveJson(const Request& request, const std::string& json,
                                const char* cacheControl) const {
  const bool big = json.size() >= kGzipAtLeast;
  const bool brotli = big && acceptsBrotli(request.acceptEncoding);
  const bool gzip = big && !brotli && acceptsGzip(request.acceptEncoding);
  return serveContent(request, *makeContent(json + "\n", gzip, brotli), kJson, cacheControl, false);
}

Response TileService::serveContent(const Request& request, const Content& content,
                                   const char* contentType, const char* cacheControl,
                                   bool ranges) const {
  Response r;
  // brotli before gzip when both are accepted: smaller, and as fast to decode.
  const bool brotli = content.brotli && acceptsBrotli(request.acceptEncoding);
  const bool gzip = !brotli && content.gzip && acceptsGzip(request.acceptEncoding);
  const std::string& etag = brotli ? content.brotliEtag : gzip ? content.gzipEtag : content.etag;
  r.addHeader("Content-Type", contentType);
  r.addHeader("ETag", etag);
  r.addHeader("Cache-Control", cacheControl);
  if (content.gzip || content.brotli) r.addHeader("Vary", "Accept-Encoding");
  if (ranges) r.addHeader("Accept-Ranges", "bytes");
  if (!request.ifNoneMatch.empty() && ifNoneMatchMatches(request.ifNoneMatch, etag)) {
    // RFC 9110 13.1.2: 304 answers only GET and HEAD; any other method fails.
    if (request.method == "GET" || request.method == "HEAD") {
      r.status = 304;
      return r;
    }
    return errorResponse(412, ErrorKind::Input, "If-None-Match matches the current representation",
                         "If-None-Match");
  }
  if (brotli) r.addHeader("Content-Encoding", "br");
  if (gzip) r.addHeader("Content-Encoding", "gzip");
  r.body = brotli ? content.brotli : gzip ? content.gzip : content.bytes;
  if (ranges && !request.range.empty() && (request.ifRange.empty() || request.ifRange == etag)) {
    const auto range = parseRange(request.range, r.body->size());
    const std::string size = std::to_string(r.body->size());
    if (range.kind == RangeRequest::Kind::Unsatisfiable) {
      Response e = errorResponse(416, ErrorKind::Input,
                                 "the range is outside the " + size + " bytes", "Range");
      e.addHeader("Content-Range", "bytes */" + size);
      return e;
    }
    if (range.kind == RangeRequest::Kind::Partial) {
      r.status = 206;
      r.offset = range.first;
      r.length = range.last - range.first + 1;
      r.addHeader("Content-Range", "bytes " + std::to_string(range.first) + "-" +
                                       std::to_string(range.last) + "/" + size);
    }
  }
  return r;
}

}  // namespace tinsmith::server
