// `tinsmith info`: describe a .tin file or a tile store.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addInfoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("info", "Describe a .tin file or a tile store");
  cmd->add_option("file", "A .tin file or a tile store")->required();
  cmd->add_flag("--json")->description("Print JSON");
  cmd->callback([] { throw notImplemented("tinsmith info"); });
}

}  // namespace tinsmith::cli
