// `tinsmith serve`: serve tile stores over HTTP: tilesets, tiles, elevation,
// break lines, the viewer pages, health and metrics (DESIGN.md "Server").
//   tinsmith serve STORE|FOLDER [MORE…] [--config FILE] [--host H] [--port P]
//                  [--cors ORIGIN|off] [--cache-mb N] [--threads N] [--workers N]
//                  [--queue N] [--viewer DIR]
//                  [--base-path /P] [--quiet] [--log-format text|json] [--on-demand] …
// Every flag is also a key of a config file's [server] table
// (server/app/server_config.hpp); flags given win over the file.
// The viewer's files are looked for, when --viewer is not given, beside the
// executable (../share/tinsmith/viewer), in /usr/share/tinsmith/viewer and in
// the source tree it was built from (server/viewer, after tools/setup.sh).
// SIGTERM and SIGINT shut it down gracefully (requests in flight finish) and
// it exits 0; SIGHUP checks the stores for replacements and new ones at once
// (as --reload does periodically) and logs what it found.
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/base/error.hpp"
#include "server/app/server_config.hpp"
#include "server/app/tile_server.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"

namespace tinsmith::cli {

namespace {

using server::ServerSettings;

/// Copies one setting from the flags into the settings when its flag was
/// given on the command line (flags win over the config file).
struct FlagOverride {
  const CLI::Option* option;
  std::function<void(ServerSettings& to, const ServerSettings& from)> copy;
};

template <typename T>
FlagOverride overrides(const CLI::Option* option, T ServerSettings::*member) {
  return {option,
          [member](ServerSettings& to, const ServerSettings& from) { to.*member = from.*member; }};
}

/// The viewer folder: --viewer as given, else the first usable default;
/// null when there is none (the server then says what to install).
std::shared_ptr<const server::ViewerAssets> viewerAssets(const std::string& given) {
  namespace fs = std::filesystem;
  if (!given.empty()) return std::make_shared<const server::ViewerAssets>(given);
  std::vector<fs::path> candidates;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(self.parent_path().parent_path() / "share" / "tinsmith" / "viewer");
  candidates.emplace_back("/usr/share/tinsmith/viewer");
#ifdef TINSMITH_SOURCE_VIEWER_DIR
  candidates.emplace_back(TINSMITH_SOURCE_VIEWER_DIR);
#endif
  const auto root = server::findViewerRoot(candidates);
  return root ? std::make_shared<const server::ViewerAssets>(*root) : nullptr;
}

std::chrono::milliseconds seconds(double s) {
  return std::chrono::milliseconds(static_cast<long long>(s * 1000));
}

/// Blocks the signals serveUntilSignalled waits for, in this thread and so
/// in every thread started after (the server's inherit the mask; its
/// workers block every signal). Called before the server is made, so a
/// signal that comes as soon as it listens is waited for, not fatal.
sigset_t blockServeSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  sigaddset(&signals, SIGUSR1);  // wakes the waiter when the server stops by itself
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

/// Runs `server` until SIGTERM or SIGINT, reloading the stores on SIGHUP:
/// one thread waits for `signals` (blockServeSignals) with sigwait, so no
/// code runs in a signal handler.
void serveUntilSignalled(server::TileServer& server, const sigset_t& signals) {
  std::thread waiter([&] {
    int received = 0;
    while (sigwait(&signals, &received) == 0 && received == SIGHUP) {
      // Logged with --quiet too, as reloads are (it is not access log).
      std::cerr << "tinsmith serve: SIGHUP: checking the stores" << std::endl;
      if (server.reload().empty()) std::cerr << "tinsmith serve: no store changed" << std::endl;
    }
    server.stop();
  });
  server.run();
  pthread_kill(waiter.native_handle(), SIGUSR1);
  waiter.join();
}

}  // namespace

void addServeCommand(CLI::App& app) {
  // Flags land in `flags`; the callback starts from the defaults, applies
  // the config file's [server], then every flag that was given. A new flag
  // needs a member of ServerSettings, a key in server/app/server_config.cpp
  // and an `overrides` line here.
  auto flags = std::make_shared<ServerSettings>();
  auto configFile = std::make_shared<std::string>();
  auto given = std::make_shared<std::vector<FlagOverride>>();
  auto* cmd = app.add_subcommand("serve", "Serve tile stores over HTTP: tilesets, tiles, elevation, viewer");
  auto add = [&](CLI::Option* option, auto member) {
    given->push_back(overrides(option, member));
    return option;
  };
  add(cmd->add_option("stores", flags->stores,
                      "Tile stores (.3dtiles archives or store directories), or folders of them"),
      &ServerSettings::stores);
  cmd->add_option("--config", *configFile,
                  "TOML file whose [server] table sets any of these options (keys: the flags' "
                  "names with _ for -, e.g. cache_mb; stores = [paths] relative to the file). "
                  "A whole build config works; flags given here win over it")
      ->check(CLI::ExistingFile);
  add(cmd->add_option("--host", flags->host, "Address to listen on")->capture_default_str(),
      &ServerSettings::host);
  add(cmd->add_option("--port", flags->port, "Port to listen on (0: any free port)")
          ->check(CLI::Range(0, 65535))
          ->capture_default_str(),
      &ServerSettings::port);
  add(cmd->add_option("--cors", flags->cors,
                      "Access-Control-Allow-Origin for every response: * , one origin, or off")
          ->capture_default_str(),
      &ServerSettings::cors);
  add(cmd->add_option("--cache-mb", flags->cacheMb,
                      "Memory for hot tiles and tileset files, MiB (0: none)")
          ->check(CLI::Range(0, 1 << 20))
          ->capture_default_str(),
      &ServerSettings::cacheMb);
  add(addThreadsOption(*cmd, flags->threads, "I/O threads", {}, 256), &ServerSettings::threads);
  add(cmd->add_option("--workers", flags->workers,
                      "Threads for slow requests: tile builds (--on-demand), large elevation "
                      "and profile batches, so the I/O threads keep answering (0: one per core)")
          ->check(CLI::Range(0, 256))
          ->capture_default_str(),
      &ServerSettings::workers);
  add(cmd->add_option("--queue", flags->queue,
                      "Slow requests that may wait for a worker; more are answered 503 with "
                      "Retry-After")
          ->check(CLI::Range(0, 100000))
          ->capture_default_str(),
      &ServerSettings::queue);
  add(cmd->add_option("--max-connections", flags->maxConnections,
                      "Open connections at most; more get 503 and are closed")
          ->check(CLI::Range(1, 1000000))
          ->capture_default_str(),
      &ServerSettings::maxConnections);
  add(cmd->add_option("--read-timeout", flags->readTimeout,
                      "Seconds a new connection has to send its first request whole")
          ->check(CLI::Range(0.1, 3600.0))
          ->capture_default_str(),
      &ServerSettings::readTimeout);
  add(cmd->add_option("--idle-timeout", flags->idleTimeout,
                      "Seconds a keep-alive connection has to send its next request whole")
          ->check(CLI::Range(0.1, 3600.0))
          ->capture_default_str(),
      &ServerSettings::idleTimeout);
  add(cmd->add_option("--reload", flags->reloadSeconds,
                      "Seconds between checks for stores replaced on disk or new in a served "
                      "folder (0: never)")
          ->check(CLI::Range(0.0, 86400.0))
          ->capture_default_str(),
      &ServerSettings::reloadSeconds);
  add(addQuietFlag(*cmd, flags->quiet, "No access log (one line per request on stderr)"),
      &ServerSettings::quiet);
  add(cmd->add_option("--log-format", flags->logFormat,
                      "Access log lines: text, or json (one JSON object per line)")
          ->transform(CLI::CheckedTransformer(std::map<std::string, server::LogFormat>{
              {"text", server::LogFormat::Text}, {"json", server::LogFormat::Json}}))
          ->option_text("text|json (default: text)"),
      &ServerSettings::logFormat);
  add(cmd->add_flag("--on-demand", flags->onDemand,
                    "Build tiles the tileset references but the store lacks from the store's "
                    "TIN (once per tile; kept in memory and written into a writable store)"),
      &ServerSettings::onDemand);
  add(cmd->add_option(
          "--viewer", flags->viewer,
          "Folder of the viewer's pages and libraries (default: beside the "
          "executable, /usr/share/tinsmith/viewer, or the source tree's server/viewer)"),
      &ServerSettings::viewer);
  add(cmd->add_option("--base-path", flags->basePath,
                      "Answer under this path prefix (e.g. /terrain, behind a reverse proxy)"),
      &ServerSettings::basePath);
  cmd->footer(
      "Routes: / (the CesiumJS viewer), /three (three.js viewer), /viewer/… (their\n"
      "files), /health, /metrics (Prometheus), /tilesets,\n"
      "/tilesets/ID/tileset.json, /tilesets/ID/tilesets/Z/X/Y.json,\n"
      "/tilesets/ID/tiles/Z/X/Y.glb, /tilesets/ID/elevation?x=&y= (or lon=&lat=; POST\n"
      "{\"points\": [[x, y], …]}), /tilesets/ID/profile?line=x,y;x,y&spacing=S (or\n"
      "lonlat=; POST {\"line\": …}), /tilesets/ID/lines.geojson (break lines, GeoJSON).\n"
      "ID is a store's file name without .3dtiles.\n"
      "Config: --config FILE reads FILE's [server] table, e.g.\n"
      "  [server]\n"
      "  stores = [\"../out/red-butte.3dtiles\"]\n"
      "  port = 8080\n"
      "  cors = \"off\"\n"
      "  cache_mb = 512\n"
      "  log_format = \"json\"\n"
      "SIGTERM/SIGINT: requests in flight finish, then exit 0.\n"
      "SIGHUP: check the stores for replacements and new ones now (as --reload does\n"
      "every few seconds), log what changed, and go on serving.\n\n" +
      cmd->get_footer());
  cmd->callback([flags, configFile, given] {
    ServerSettings opt;
    if (!configFile->empty()) server::applyServerConfig(*configFile, opt);
    for (const auto& g : *given)
      if (g.option->count() > 0) g.copy(opt, *flags);
    if (opt.stores.empty())
      throw usageError("no stores to serve",
                       "name .3dtiles files or folders, or set stores = [...] in [server] of "
                       "the --config file");
    server::TileServerOptions o;
    for (const auto& s : opt.stores) o.stores.emplace_back(s);
    o.http.host = opt.host;
    o.http.port = static_cast<unsigned short>(opt.port);
    o.http.threads = opt.threads;
    o.workers = static_cast<std::size_t>(opt.workers);
    o.queue = static_cast<std::size_t>(opt.queue);
    o.http.limits.maxConnections = static_cast<std::size_t>(opt.maxConnections);
    o.http.limits.readTimeout = seconds(opt.readTimeout);
    o.http.limits.idleTimeout = seconds(opt.idleTimeout);
    o.service.cors = opt.cors == "off" ? "" : opt.cors;
    o.service.cacheBytes = opt.cacheMb << 20;
    o.service.onDemand = opt.onDemand;
    o.log = opt.quiet ? nullptr : stderr;
    o.logFormat = opt.logFormat;
    o.reloadInterval = seconds(opt.reloadSeconds);
    o.service.basePath = server::normalizeBasePath(opt.basePath);
    o.service.viewer = viewerAssets(opt.viewer);
    const auto viewer = o.service.viewer;
    const std::string base = o.service.basePath;
    const sigset_t signals = blockServeSignals();
    server::TileServer server(std::move(o));
    std::cerr << "tinsmith serve: " << server.catalog().tilesets().size()
              << " tileset(s) on http://" << opt.host << ":" << server.port() << base << "/"
              << std::endl;
    if (server.maxConnections() < static_cast<std::size_t>(opt.maxConnections))
      std::cerr << "tinsmith serve: the descriptor limit (ulimit -n) leaves room for "
                << server.maxConnections() << " connections, not --max-connections "
                << opt.maxConnections << "; more get 503 (raise the hard limit to serve more)"
                << std::endl;
    if (!viewer || !viewer->hasCesium())
      std::cerr << "tinsmith serve: the viewer is not installed (run tools/setup.sh, or give "
                   "--viewer DIR); "
                   "/ lists the stores"
                << std::endl;
    else
      std::cerr << "tinsmith serve: viewer from " << viewer->root().string() << " ("
                << viewer->size() << " files)" << std::endl;
    serveUntilSignalled(server, signals);
    if (!opt.quiet) std::cerr << "tinsmith serve: stopped" << std::endl;
  });
}

}  // namespace tinsmith::cli
