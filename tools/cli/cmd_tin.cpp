// `tinsmith tin`: build a constrained Delaunay TIN from points and break lines.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addTinCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("tin", "Build a constrained Delaunay TIN from points and break lines");
  cmd->add_option("config", "Project config (TOML); or give --points/--breaklines");
  cmd->add_option("--points", "XYZ/CSV point file(s)");
  cmd->add_option("--breaklines", "Break lines: GeoJSON (Multi)LineString with 3D coordinates, or text polylines");
  cmd->add_option("-o,--output", "The .tin file to write")->required();
  cmd->callback([] { throw notImplemented("tinsmith tin (the constrained Delaunay TIN)"); });
}

}  // namespace tinsmith::cli
