// Small helpers over toml++ nodes shared by the config readers (the project
// config here, the server's [server] table): where a node is and what it is,
// for messages that name the line and the type found. Include only from .cpp
// files that already use toml++.
#pragma once

#include <toml++/toml.h>

#include <cstdint>

namespace tinsmith::ingest {

/// The 1-based line a node starts on.
inline std::int64_t lineOf(const toml::node& node) { return static_cast<std::int64_t>(node.source().begin.line); }

/// "a string", "an integer", … — the node's type as a message says it.
inline const char* typeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    default: return "a date/time";
  }
}

/// The top-level tables of a project config; [server] is read by the server
/// (server/app/server_config), the others by ingest/config.
inline constexpr const char* kConfigTables[] = {"project", "layer", "tin", "fit", "tiles", "server"};

}  // namespace tinsmith::ingest
