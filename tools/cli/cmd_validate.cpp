// `tinsmith validate`: check a TIN: topology, orientation, constraints, Delaunay property.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addValidateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("validate", "Check a TIN: topology, orientation, constraints, Delaunay property");
  cmd->add_option("tin", "The .tin file")->required();
  cmd->add_flag("--json")->description("Print JSON");
  cmd->callback([] { throw notImplemented("tinsmith validate"); });
}

}  // namespace tinsmith::cli
