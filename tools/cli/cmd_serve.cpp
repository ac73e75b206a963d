// `tinsmith serve`: serve tile stores over HTTP: tilesets, tiles, elevation, viewer.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addServeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("serve", "Serve tile stores over HTTP: tilesets, tiles, elevation, viewer");
  cmd->add_option("stores", "Tile stores (.3dtiles archives or directories)")->required();
  cmd->add_option("--host", "Address to listen on (default 127.0.0.1)");
  cmd->add_option("--port", "Port to listen on (default 8080)");
  cmd->callback([] { throw notImplemented("tinsmith serve (the HTTP tile server)"); });
}

}  // namespace tinsmith::cli
