// The settings of `tinsmith serve` and the config file's [server] table,
// which has one key per flag (the flag's name without "--", '-' written '_'):
//
//   [server]
//   stores = ["../out/red-butte.3dtiles"]   # relative to the config's folder
//   host = "127.0.0.1"        port = 8080          cors = "*"   # or "off"
//   cache_mb = 256            threads = 0          max_connections = 10000
//   workers = 0               queue = 64
//   read_timeout = 10.0       idle_timeout = 30.0  reload = 2.0
//   quiet = false             log_format = "text"  # or "json"
//   on_demand = false
//   viewer = "viewer"         # a folder, relative to the config's folder
//   base_path = "/terrain"
//
// The file may be a whole build config (config/red-butte.toml): only its
// [server] table is read, and its other top-level tables must be ones a
// build config has. Flags given on the command line win over the file.
// Every problem is an inputError naming the file, the line, the key and
// what it allows.
#pragma once

#include <cstddef>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace tinsmith::server {

enum class LogFormat { Text, Json };

/// "text" | "json" into `out`; false (out unchanged) for any other name.
bool parseLogFormat(std::string_view name, LogFormat& out);

struct ServerSettings {
  std::vector<std::string> stores;
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string cors = "*";  ///< "off": no CORS headers
  std::size_t cacheMb = 256;
  int threads = 0;
  int workers = 0;  ///< threads for slow requests (on-demand builds, large batches); 0: cores
  int queue = 64;   ///< slow requests that may wait for a worker; more get 503
  int maxConnections = 10000;
  double readTimeout = 10, idleTimeout = 30, reloadSeconds = 2;
  bool quiet = false;
  LogFormat logFormat = LogFormat::Text;
  bool onDemand = false;
  std::string viewer;    ///< the viewer's folder; "": the defaults
  std::string basePath;  ///< "" or a path prefix, as --base-path takes it
};

/// Reads the [server] table of the TOML file `file` into `settings`: each
/// key present replaces the setting, relative `stores` are resolved against
/// the file's folder. Returns the keys present. A file without [server]
/// changes nothing. Throws inputError (file, line, key, what is allowed) for
/// an unreadable file, invalid TOML, an unknown key or top-level table, a
/// value of the wrong type or out of range.
std::set<std::string> applyServerConfig(const std::filesystem::path& file,
                                        ServerSettings& settings);

/// Same, from text; `file` names it in messages and anchors relative stores.
std::set<std::string> applyServerConfigText(std::string_view text,
                                            const std::filesystem::path& file,
                                            ServerSettings& settings);

}  // namespace tinsmith::server
