#include "server/app/server_config.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "core/base/error.hpp"
#include "ingest/config/toml_nodes.hpp"

namespace tinsmith::server {

namespace fs = std::filesystem;

bool parseLogFormat(std::string_view name, LogFormat& out) {
  if (name == "text") {
    out = LogFormat::Text;
  } else if (name == "json") {
    out = LogFormat::Json;
  } else {
    return false;
  }
  return true;
}

namespace {

using ingest::lineOf;
using ingest::typeName;

struct Reader {
  fs::path file;
  ServerSettings& settings;

  [[noreturn]] void fail(const std::string& problem, std::int64_t line,
                         const std::string& hint = {}) const {
    SourceLocation where;
    where.file = file.string();
    if (line > 0) where.line = line;
    throw inputError(problem, where, hint);
  }
  [[noreturn]] void wrongType(const std::string& key, const toml::node& node,
                              const std::string& expected) const {
    fail("server." + key + " must be " + expected + ", not " + typeName(node), lineOf(node),
         node.is_string()         ? "write it without quotes"
         : expected == "a string" ? "put it in quotes"
                                  : "");
  }
  std::string string(const std::string& key, const toml::node& node) const {
    if (const auto* s = node.as_string()) return s->get();
    wrongType(key, node, "a string");
  }
  bool boolean(const std::string& key, const toml::node& node) const {
    if (const auto* b = node.as_boolean()) return b->get();
    wrongType(key, node, "true or false");
  }
  std::int64_t integer(const std::string& key, const toml::node& node, std::int64_t lo,
                       std::int64_t hi) const {
    const auto* i = node.as_integer();
    if (!i) wrongType(key, node, "an integer");
    if (i->get() < lo || i->get() > hi)
      fail("server." + key + " must be " + std::to_string(lo) + " to " + std::to_string(hi) +
               " (got " + std::to_string(i->get()) + ")",
           lineOf(node));
    return i->get();
  }
  double number(const std::string& key, const toml::node& node, double lo, double hi) const {
    double v = 0;
    if (const auto* f = node.as_floating_point()) {
      v = f->get();
    } else if (const auto* i = node.as_integer()) {
      v = static_cast<double>(i->get());
    } else {
      wrongType(key, node, "a number");
    }
    if (!(v >= lo && v <= hi)) {
      std::ostringstream m;
      m << "server." << key << " must be " << lo << " to " << hi << " seconds (got " << v << ")";
      fail(m.str(), lineOf(node));
    }
    return v;
  }
};

using Apply = std::function<void(const Reader&, const std::string&, const toml::node&)>;

/// Every key of [server], with what it does to the settings. The ranges are
/// those of the flags (tools/cli/cmd_serve.cpp).
const std::map<std::string, Apply>& serverKeys() {
  static const std::map<std::string, Apply> keys = {
      {"stores",
       [](const Reader& r, const std::string& key, const toml::node& node) {
         const auto* array = node.as_array();
         if (!array) r.wrongType(key, node, "an array of paths");
         r.settings.stores.clear();
         for (const auto& item : *array) {
           if (!item.is_string()) r.wrongType(key, item, "an array of paths (strings)");
           fs::path p = item.as_string()->get();
           if (p.is_relative()) p = r.file.parent_path() / p;
           r.settings.stores.push_back(p.lexically_normal().string());
         }
       }},
      {"host", [](const Reader& r, const std::string& k,
                  const toml::node& n) { r.settings.host = r.string(k, n); }},
      {"port",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.port = static_cast<int>(r.integer(k, n, 0, 65535));
       }},
      {"cors", [](const Reader& r, const std::string& k,
                  const toml::node& n) { r.settings.cors = r.string(k, n); }},
      {"cache_mb",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.cacheMb = static_cast<std::size_t>(r.integer(k, n, 0, 1 << 20));
       }},
      {"threads",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.threads = static_cast<int>(r.integer(k, n, 0, 256));
       }},
      {"workers",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.workers = static_cast<int>(r.integer(k, n, 0, 256));
       }},
      {"queue",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.queue = static_cast<int>(r.integer(k, n, 0, 100000));
       }},
      {"max_connections",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.maxConnections = static_cast<int>(r.integer(k, n, 1, 1000000));
       }},
      {"read_timeout",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.readTimeout = r.number(k, n, 0.1, 3600.0);
       }},
      {"idle_timeout",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.idleTimeout = r.number(k, n, 0.1, 3600.0);
       }},
      {"reload",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         r.settings.reloadSeconds = r.number(k, n, 0.0, 86400.0);
       }},
      {"quiet", [](const Reader& r, const std::string& k,
                   const toml::node& n) { r.settings.quiet = r.boolean(k, n); }},
      {"log_format",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         const std::string name = r.string(k, n);
         if (!parseLogFormat(name, r.settings.logFormat))
           r.fail("server.log_format must be \"text\" or \"json\" (got \"" + name + "\")",
                  lineOf(n));
       }},
      {"viewer",
       [](const Reader& r, const std::string& k, const toml::node& n) {
         fs::path p = r.string(k, n);
         if (!p.empty() && p.is_relative()) p = r.file.parent_path() / p;
         r.settings.viewer = p.lexically_normal().string();
       }},
      {"base_path", [](const Reader& r, const std::string& k,
                       const toml::node& n) { r.settings.basePath = r.string(k, n); }},
      {"on_demand", [](const Reader& r, const std::string& k,
                       const toml::node& n) { r.settings.onDemand = r.boolean(k, n); }},
  };
  return keys;
}

std::string allowedKeys() {
  std::string list;
  for (const auto& [key, apply] : serverKeys()) list += (list.empty() ? "" : ", ") + key;
  return list;
}

}  // namespace

std::set<std::string> applyServerConfigText(std::string_view text, const fs::path& file,
                                            ServerSettings& settings) {
  const Reader reader{fs::absolute(file).lexically_normal(), settings};
  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    reader.fail("not valid TOML: " + std::string(e.description()),
                static_cast<std::int64_t>(e.source().begin.line));
  }
  for (const auto& [key, node] : root) {
    const std::string name(key.str());
    bool known = false;  // [server], or a table of the build config, not read here
    for (const char* t : ingest::kConfigTables) known = known || name == t;
    if (!known)
      reader.fail("unknown top-level key '" + name + "'", lineOf(node),
                  "tinsmith serve reads [server]; a build config may also have [project], "
                  "[[layer]], [tin], [fit] and [tiles] (see config/README.md)");
  }
  std::set<std::string> present;
  const auto* node = root.get("server");
  if (!node) return present;
  const auto* table = node->as_table();
  if (!table) reader.fail("'server' must be a table, written [server]", lineOf(*node));
  for (const auto& [key, value] : *table) {
    const std::string name(key.str());
    const auto it = serverKeys().find(name);
    if (it == serverKeys().end())
      reader.fail("unknown key '" + name + "' in [server]", lineOf(value),
                  "allowed keys: " + allowedKeys() + " (see tinsmith serve --help)");
    it->second(reader, name, value);
    present.insert(name);
  }
  return present;
}

std::set<std::string> applyServerConfig(const fs::path& file, ServerSettings& settings) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    SourceLocation where;
    where.file = file.string();
    throw inputError("cannot read the config file", where, "check the path and its permissions");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return applyServerConfigText(text.str(), file, settings);
}

}  // namespace tinsmith::server
