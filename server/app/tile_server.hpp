// A whole tile server: the catalog of stores, the routes, the metrics, the
// access log and the HTTP server, wired together. `tinsmith serve` runs one;
// tests run one on an ephemeral loopback port.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "server/app/metrics.hpp"
#include "server/app/server_config.hpp"
#include "server/app/tile_service.hpp"
#include "server/app/tileset_catalog.hpp"
#include "server/http/http_server.hpp"

namespace tinsmith::server {

struct TileServerOptions {
  std::vector<std::filesystem::path> stores;
  ServerOptions http;
  ServiceOptions service;
  /// Worker threads for slow requests (0: one per core), and how many such
  /// requests may wait for one before the next is answered 503 (see
  /// server/app/work_pool.hpp, TileService).
  std::size_t workers = 0;
  std::size_t queue = 64;
  /// One line per request (access log) to `log`; null: none (--quiet).
  std::FILE* log = stderr;
  LogFormat logFormat = LogFormat::Text;
  /// How often the stores are checked for a replacement (see
  /// TilesetCatalog::refresh); zero: never.
  std::chrono::milliseconds reloadInterval{2000};
  /// Where reloads and failures (5xx, with their details) are reported;
  /// null: nowhere.
  std::FILE* notices = stderr;
};

class TileServer {
 public:
  /// Opens the stores and binds. Throws usageError/inputError for stores
  /// that cannot be served, ioError when the address cannot be bound.
  explicit TileServer(TileServerOptions options);
  ~TileServer();

  [[nodiscard]] unsigned short port() const { return http_->port(); }
  /// The connections served at once (HttpServer::effectiveMaxConnections).
  [[nodiscard]] std::size_t maxConnections() const { return http_->effectiveMaxConnections(); }
  [[nodiscard]] const TilesetCatalog& catalog() const { return catalog_; }
  [[nodiscard]] const Metrics& metrics() const { return metrics_; }
  /// Serves until stop() (see HttpServer::run), checking the stores for
  /// replacements every reloadInterval meanwhile.
  void run();
  /// Graceful shutdown; thread-safe.
  void stop();
  /// Checks the stores for replacements and new ones now, as every
  /// reloadInterval does (TilesetCatalog::refresh), and reports on
  /// `notices`; returns the lines reported. Thread-safe (one check at a
  /// time).
  std::vector<std::string> reload();

 private:
  void logExchange(const Exchange& exchange);

  TileServerOptions options_;
  TilesetCatalog catalog_;
  Metrics metrics_;
  WorkPool pool_;  // shut down before the HTTP server goes: its tasks hold connections
  TileService service_;
  std::mutex logMutex_;
  std::unique_ptr<HttpServer> http_;
  std::mutex reloadMutex_;  // one catalog refresh at a time
  std::mutex watchMutex_;  // with watchChanged_, guards stopping_
  std::condition_variable watchChanged_;
  bool stopping_ = false;
};

/// The access-log line of one exchange (no newline): peer, time (UTC),
/// "METHOD target", status, bytes, milliseconds, cache; the target's bytes
/// outside printable ASCII, '"' and '\\' escaped as \xNN, cut at 512 bytes.
std::string accessLogLine(const Exchange& exchange);

/// The same as one JSON object (no newline): {"peer", "time", "method",
/// "target" (bytes that are not UTF-8 replaced by U+FFFD, cut at 512),
/// "status", "bytes", "ms", "cache": "hit"|"miss"|null, "completed"}.
std::string accessLogJson(const Exchange& exchange);

}  // namespace tinsmith::server
