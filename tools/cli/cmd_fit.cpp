// `tinsmith fit`: fit a multilevel least-squares surface over binary triangulations.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addFitCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("fit", "Fit a multilevel least-squares surface over binary triangulations");
  cmd->add_option("points", "XYZ/CSV point file")->required();
  cmd->add_option("--tolerance", "Error criterion: metres, or a percentage of the z range (0.25%)");
  cmd->add_option("--lambda", "Smoothing weight as a multiple of the default lambda_d");
  cmd->add_option("--smoothing", "membrane | umbrella | thin-plate");
  cmd->add_option("--criterion", "error, count:N, curvature:T, or a comma-separated combination");
  cmd->add_option("-o,--output", "The .tin file to write")->required();
  cmd->add_option("--stats", "Per-level statistics as JSON");
  cmd->callback([] { throw notImplemented("tinsmith fit (multilevel least squares)"); });
}

}  // namespace tinsmith::cli
