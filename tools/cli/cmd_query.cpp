// `tinsmith query`: elevation, normal and slope of a TIN at points.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addQueryCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("query", "Elevation, normal and slope of a TIN at points");
  cmd->add_option("tin", "The .tin file")->required();
  cmd->add_option("x", "Easting in the TIN's CRS");
  cmd->add_option("y", "Northing in the TIN's CRS");
  cmd->add_flag("--json")->description("Print JSON");
  cmd->callback([] { throw notImplemented("tinsmith query"); });
}

}  // namespace tinsmith::cli
