#include "server/app/tile_server.hpp"

#include <cmath>
#include <ctime>
#include <nlohmann/json.hpp>
#include <thread>

namespace tinsmith::server {

std::string accessLogLine(const Exchange& e) {
  std::string target;
  for (std::size_t i = 0; i < e.request.target.size() && i < 512; ++i) {
    const auto c = static_cast<unsigned char>(e.request.target[i]);
    if (c < 0x20 || c > 0x7e || c == '"' || c == '\\') {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      target += hex;
    } else {
      target += static_cast<char>(c);
    }
  }
  if (e.request.target.size() > 512) target += "…";
  std::string method = e.request.method.substr(0, 16);
  for (char& c : method)
    if (c < 'A' || c > 'Z') c = '?';
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char time[32];
  std::strftime(time, sizeof time, "%Y-%m-%dT%H:%M:%SZ", &utc);
  char tail[128];
  std::snprintf(tail, sizeof tail, "\" %d %zu %.3fms%s%s", e.response.status, e.bytesWritten,
                std::chrono::duration<double, std::milli>(e.elapsed).count(),
                e.response.cacheHit ? " hit" : "", e.completed ? "" : " aborted");
  return std::string(e.peer) + " " + time + " \"" + (method.empty() ? "-" : method) + " " +
         target + tail;
}

namespace {

ServiceOptions withNotices(ServiceOptions service, std::FILE* notices) {
  service.notices = notices;
  return service;
}

}  // namespace

std::string accessLogJson(const Exchange& e) {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char time[32];
  std::strftime(time, sizeof time, "%Y-%m-%dT%H:%M:%SZ", &utc);
  nlohmann::ordered_json j;
  j["peer"] = std::string(e.peer);
  j["time"] = time;
  j["method"] = e.request.method.substr(0, 16);
  j["target"] = e.request.target.substr(0, 512);
  j["status"] = e.response.status;
  j["bytes"] = e.bytesWritten;
  j["ms"] = std::round(std::chrono::duration<double, std::milli>(e.elapsed).count() * 1000) / 1000;
  j["cache"] = e.response.route == RouteKind::Tile || e.response.route == RouteKind::TilesetJson ||
                       e.response.route == RouteKind::ExternalTileset
                   ? nlohmann::ordered_json(e.response.cacheHit ? "hit" : "miss")
                   : nlohmann::ordered_json();
  j["completed"] = e.completed;
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

TileServer::TileServer(TileServerOptions options)
    : options_(std::move(options)),
      catalog_(options_.stores),
      pool_(options_.workers, options_.queue),
      service_(catalog_, metrics_, withNotices(options_.service, options_.notices), &pool_) {
  metrics_.watchPool(&pool_);
  options_.http.transportHeaders = corsHeaders(options_.service.cors);
  http_ = std::make_unique<HttpServer>(
      options_.http, [this](const Request& r) { return service_.handle(r); },
      [this](const Exchange& e) { logExchange(e); },
      [this](int delta) { metrics_.countConnection(delta); });
}

TileServer::~TileServer() {
  pool_.shutdown();
  http_.reset();
}

void TileServer::run() {
  std::thread watcher;
  if (options_.reloadInterval.count() > 0) {
    watcher = std::thread([this] {
      std::unique_lock lock(watchMutex_);
      while (!watchChanged_.wait_for(lock, options_.reloadInterval, [this] { return stopping_; })) {
        lock.unlock();
        reload();
        lock.lock();
      }
    });
  }
  http_->run();
  // Requests still on a worker after the grace are not answered: their
  // builds finish, queued ones are dropped.
  pool_.shutdown();
  stop();  // run() can also end by itself: the watcher stops either way
  if (watcher.joinable()) watcher.join();
}

void TileServer::stop() {
  {
    std::lock_guard lock(watchMutex_);
    stopping_ = true;
  }
  watchChanged_.notify_all();
  http_->stop();
}

std::vector<std::string> TileServer::reload() {
  std::lock_guard lock(reloadMutex_);
  auto lines = catalog_.refresh();
  if (options_.notices)
    for (const auto& line : lines)
      std::fprintf(options_.notices, "tinsmith serve: %s\n", line.c_str());
  return lines;
}

void TileServer::logExchange(const Exchange& e) {
  metrics_.countRequest(e.response.route, e.response.status, e.bytesWritten, e.elapsed);
  if (!e.response.failure.empty() && options_.notices) {  // every 5xx is logged, --quiet or not
    const std::string line = "tinsmith serve: " + std::to_string(e.response.status) + " for " +
                             accessLogLine(e) + ": " + e.response.failure + "\n";
    std::lock_guard lock(logMutex_);
    std::fwrite(line.data(), 1, line.size(), options_.notices);
  }
  if (!options_.log) return;
  const std::string line =
      (options_.logFormat == LogFormat::Json ? accessLogJson(e) : accessLogLine(e)) + "\n";
  std::lock_guard lock(logMutex_);
  std::fwrite(line.data(), 1, line.size(), options_.log);
}

}  // namespace tinsmith::server
