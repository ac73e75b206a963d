// `tinsmith build`: run the whole job from a config: ingest → TIN → tiles → store.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addBuildCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("build", "Run the whole job from a config: ingest → TIN → tiles → store");
  cmd->add_option("config", "Project config (TOML), see config/README.md")->required();
  cmd->add_option("-o,--output", "Tile store to write (.3dtiles archive or directory)");
  cmd->add_option("--threads", "Worker threads (default: all cores)");
  cmd->add_flag("--resume")->description("Keep tiles already in the store and build only the missing ones");
  cmd->callback([] { throw notImplemented("tinsmith build (the whole pipeline; it lands with the ingest, fitting and tiling stages)"); });
}

}  // namespace tinsmith::cli
