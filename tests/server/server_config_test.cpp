// The [server] table of a config file (server/app/server_config.hpp): every
// key sets its setting, a whole build config is accepted, and mistakes are
// errors naming the file, the line, the key and what is allowed. Then
// through the binary: `tinsmith serve --config` serves with the file's
// values, and flags given on the command line win over them.
#include "server/app/server_config.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

#include "core/base/error.hpp"
#include "tests/server/server_test_support.hpp"

extern char** environ;

namespace tinsmith::test {
namespace {

using server::ServerSettings;

std::string failureOf(const std::string& text) {
  ServerSettings s;
  try {
    server::applyServerConfigText(text, "/etc/tinsmith/site.toml", s);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ServerConfig, EveryKeySetsItsSetting) {
  ServerSettings s;
  const auto present = server::applyServerConfigText(R"(
[server]
stores = ["stores/a.3dtiles", "/srv/b.3dtiles"]
host = "0.0.0.0"
port = 9090
cors = "https://maps.example.org"
cache_mb = 64
threads = 3
workers = 5
queue = 7
max_connections = 500
read_timeout = 2.5
idle_timeout = 7
reload = 0
quiet = true
log_format = "json"
on_demand = true
viewer = "viewer"
base_path = "/maps/terrain"
)",
                                                     "/etc/tinsmith/site.toml", s);
  EXPECT_EQ(present.size(), 17u);
  ASSERT_EQ(s.stores.size(), 2u);
  EXPECT_EQ(s.stores[0], "/etc/tinsmith/stores/a.3dtiles");  // relative to the file
  EXPECT_EQ(s.stores[1], "/srv/b.3dtiles");
  EXPECT_EQ(s.host, "0.0.0.0");
  EXPECT_EQ(s.port, 9090);
  EXPECT_EQ(s.cors, "https://maps.example.org");
  EXPECT_EQ(s.cacheMb, 64u);
  EXPECT_EQ(s.threads, 3);
  EXPECT_EQ(s.workers, 5);
  EXPECT_EQ(s.queue, 7);
  EXPECT_EQ(s.maxConnections, 500);
  EXPECT_DOUBLE_EQ(s.readTimeout, 2.5);
  EXPECT_DOUBLE_EQ(s.idleTimeout, 7.0);
  EXPECT_DOUBLE_EQ(s.reloadSeconds, 0.0);
  EXPECT_TRUE(s.quiet);
  EXPECT_EQ(s.logFormat, server::LogFormat::Json);
  EXPECT_TRUE(s.onDemand);
  EXPECT_EQ(s.viewer, "/etc/tinsmith/viewer");
  EXPECT_EQ(s.basePath, "/maps/terrain");
}

TEST(ServerConfig, KeysLeftOutKeepTheirValuesAndNoTableChangesNothing) {
  ServerSettings s;
  s.port = 1234;
  EXPECT_TRUE(server::applyServerConfigText("[tiles]\ntolerance = 5\n", "b.toml", s).empty());
  EXPECT_EQ(s.port, 1234);
  server::applyServerConfigText("[server]\ncors = \"off\"\n", "b.toml", s);
  EXPECT_EQ(s.port, 1234);
  EXPECT_EQ(s.cors, "off");
}

TEST(ServerConfig, TheRedButteBuildConfigIsAServeConfig) {
  ServerSettings s;
  const auto present = server::applyServerConfig(
      std::filesystem::path(TINSMITH_SOURCE_DIR) / "config/red-butte.toml", s);
  EXPECT_TRUE(present.contains("stores"));
  ASSERT_EQ(s.stores.size(), 1u);
  EXPECT_EQ(std::filesystem::path(s.stores[0]).filename(), "red-butte.3dtiles");
  EXPECT_EQ(std::filesystem::path(s.stores[0]).parent_path().filename(), "out");
}

TEST(ServerConfig, MistakesNameTheFileTheLineTheKeyAndWhatIsAllowed) {
  const std::string unknown = failureOf("[server]\nport = 80\nprot = 8080\n");
  EXPECT_NE(unknown.find("site.toml"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("line 3"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown key 'prot' in [server]"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("cache_mb"), std::string::npos) << unknown;  // the allowed list
  EXPECT_NE(unknown.find("port"), std::string::npos) << unknown;

  const std::string type = failureOf("[server]\nport = \"8080\"\n");
  EXPECT_NE(type.find("site.toml"), std::string::npos) << type;
  EXPECT_NE(type.find("server.port must be an integer, not a string"), std::string::npos) << type;
  EXPECT_NE(type.find("without quotes"), std::string::npos) << type;

  EXPECT_NE(
      failureOf("[server]\nport = 70000\n").find("server.port must be 0 to 65535 (got 70000)"),
      std::string::npos);
  EXPECT_NE(failureOf("[server]\nquiet = 1\n").find("server.quiet must be true or false"),
            std::string::npos);
  EXPECT_NE(failureOf("[server]\nstores = \"a.3dtiles\"\n").find("server.stores must be an array"),
            std::string::npos);
  EXPECT_NE(failureOf("[server]\nlog_format = \"xml\"\n")
                .find("server.log_format must be \"text\" or \"json\" (got \"xml\")"),
            std::string::npos);
  EXPECT_NE(
      failureOf("[server]\nread_timeout = 0\n").find("server.read_timeout must be 0.1 to 3600"),
      std::string::npos);
  EXPECT_NE(failureOf("server = 1\n").find("'server' must be a table"), std::string::npos);
  const std::string table = failureOf("[sever]\nport = 1\n");
  EXPECT_NE(table.find("unknown top-level key 'sever'"), std::string::npos) << table;
  EXPECT_NE(table.find("[server]"), std::string::npos) << table;
  EXPECT_NE(failureOf("[server\n").find("not valid TOML"), std::string::npos);
}

/// `tinsmith serve ARGS` in the background, its stderr in `log`; the port it
/// listens on read from its first line (0 when it exits first).
struct ServeProcess {
  pid_t pid = -1;
  std::filesystem::path log;
  unsigned short port = 0;

  ServeProcess(const std::string& args, const std::filesystem::path& logFile) : log(logFile) {
    const std::string command = "exec " + std::string(TINSMITH_BINARY) + " serve " + args +
                                " </dev/null >/dev/null 2>" + log.string();
    const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
    if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0)
      pid = -1;
    const std::regex listening(R"(on http://[^:]+:(\d+)/)");
    for (int i = 0; i < 200 && pid > 0; ++i) {
      std::smatch m;
      const std::string text = readFile(log);
      if (std::regex_search(text, m, listening)) {
        port = static_cast<unsigned short>(std::stoi(m[1]));
        return;
      }
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  /// SIGTERM, then the exit code.
  int stop() {
    if (pid <= 0) return -1;
    ::kill(pid, SIGTERM);
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  ~ServeProcess() { stop(); }
};

TEST(ServerConfig, ServeTakesTheFilesValuesAndFlagsWinOverThem) {
  const auto dir = scratchDir("server-config-" + std::to_string(::getpid()));
  std::filesystem::copy_file(testStoreDir() / "hill.3dtiles", dir / "hill.3dtiles");
  // Port 1 cannot be bound by a test (and is overridden); the store path is
  // relative to the file.
  std::ofstream(dir / "serve.toml") << "[project]\nname = \"hill\"\n\n[server]\n"
                                       "stores = [\"hill.3dtiles\"]\nport = 1\n"
                                       "cors = \"https://maps.example.org\"\ncache_mb = 0\n"
                                       "log_format = \"json\"\nreload = 0\n";
  ServeProcess serve("--config " + (dir / "serve.toml").string() + " --port 0", dir / "serve.log");
  ASSERT_GT(serve.port, 0) << readFile(dir / "serve.log");
  for (int i = 0; i < 2; ++i) {
    const auto r = httpGet(serve.port, "/tilesets/hill/tiles/0/0/0.glb");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.header("access-control-allow-origin"), "https://maps.example.org");
  }
  // cache_mb = 0: both reads went to the store.
  const std::string metrics = httpGet(serve.port, "/metrics").body;
  EXPECT_NE(metrics.find("tinsmith_tile_cache_hits_total 0\n"), std::string::npos) << metrics;
  EXPECT_EQ(serve.stop(), 0);
  // log_format = "json": each access-log line is one JSON object.
  std::istringstream lines(readFile(dir / "serve.log"));
  std::string line;
  int logged = 0;
  while (std::getline(lines, line)) {
    if (!line.starts_with("{")) continue;
    const auto j = nlohmann::json::parse(line);
    EXPECT_TRUE(j.contains("status") && j.contains("target") && j.contains("ms")) << line;
    ++logged;
  }
  EXPECT_EQ(logged, 3);

  // A flag beats the file: --cors off, --log-format text, --quiet.
  ServeProcess quiet("--config " + (dir / "serve.toml").string() +
                         " --port 0 --cors off --quiet --log-format text",
                     dir / "quiet.log");
  ASSERT_GT(quiet.port, 0) << readFile(dir / "quiet.log");
  const auto r = httpGet(quiet.port, "/tilesets/hill/tileset.json");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.header("access-control-allow-origin"), "");
  EXPECT_EQ(quiet.stop(), 0);
  EXPECT_EQ(readFile(dir / "quiet.log").find("GET /tilesets"), std::string::npos);

  // A bad key stops serve before it binds, naming the file and the key.
  std::ofstream(dir / "bad.toml") << "[server]\ncache = 64\n";
  const auto bad = runTinsmith("serve --config " + (dir / "bad.toml").string());
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("bad.toml"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("unknown key 'cache' in [server]"), std::string::npos) << bad.err;
  // No stores at all: a usage error that says where they can come from.
  std::ofstream(dir / "none.toml") << "[server]\nport = 0\n";
  const auto none = runTinsmith("serve --config " + (dir / "none.toml").string());
  EXPECT_NE(none.exitCode, 0);
  EXPECT_NE(none.err.find("no stores to serve"), std::string::npos) << none.err;
}

TEST(ServerConfig, HelpDocumentsTheConfigAndTheNewFlags) {
  const auto help = runTinsmith("serve --help");
  EXPECT_EQ(help.exitCode, 0);
  for (const char* text : {"--config", "[server]", "--log-format", "--on-demand", "cache_mb"})
    EXPECT_NE(help.out.find(text), std::string::npos) << text;
}

}  // namespace
}  // namespace tinsmith::test

namespace tinsmith::test {
namespace {

TEST(AccessLog, TheJsonFormIsOneValidObjectWhateverTheTarget) {
  server::Request request;
  request.method = "GET";
  request.target = std::string("/tiles/\"quoted\"\\back\x01\xff\xfe") + std::string(600, 'a');
  server::Response response;
  response.status = 404;
  response.route = server::RouteKind::Tile;
  const server::Exchange exchange{
      request, response, "127.0.0.1:5000", 123, std::chrono::microseconds(1500), true};
  const std::string line = server::accessLogJson(exchange);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  const auto j = nlohmann::json::parse(line);  // valid JSON, bad UTF-8 replaced
  EXPECT_EQ(j["peer"], "127.0.0.1:5000");
  EXPECT_EQ(j["method"], "GET");
  EXPECT_EQ(j["status"], 404);
  EXPECT_EQ(j["bytes"], 123);
  EXPECT_DOUBLE_EQ(j["ms"].get<double>(), 1.5);
  EXPECT_EQ(j["cache"], "miss");
  EXPECT_EQ(j["completed"], true);
  EXPECT_TRUE(j["target"].get<std::string>().starts_with("/tiles/\"quoted\"\\back\x01"));
  EXPECT_LE(j["target"].get<std::string>().size(), 512u + 6);  // cut; U+FFFD is 3 bytes
  EXPECT_TRUE(std::regex_match(j["time"].get<std::string>(),
                               std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
}

}  // namespace
}  // namespace tinsmith::test
