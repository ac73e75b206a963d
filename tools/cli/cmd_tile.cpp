// `tinsmith tile`: cut a TIN into level-of-detail 3D Tiles (Draco glTF).
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addTileCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("tile", "Cut a TIN into level-of-detail 3D Tiles (Draco glTF)");
  cmd->add_option("tin", "The .tin file to tile")->required();
  cmd->add_option("-o,--output", "Tile store: .3dtiles archive (default) or directory")->required();
  cmd->add_option("--max-zoom", "Deepest tile zoom");
  cmd->add_option("--threads", "Worker threads (default: all cores)");
  cmd->add_flag("--resume")->description("Keep tiles already in the store");
  cmd->callback([] { throw notImplemented("tinsmith tile (level-of-detail 3D Tiles)"); });
}

}  // namespace tinsmith::cli
