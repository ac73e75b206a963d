// `tinsmith export`: export a TIN: OBJ, PLY, EXR or GeoTIFF heightmap, single glb.
#include "core/base/error.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

void addExportCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Export a TIN: OBJ, PLY, EXR or GeoTIFF heightmap, single glb");
  cmd->add_option("tin", "The .tin file")->required();
  cmd->add_option("--format", "obj | ply | exr | tif | glb")->required();
  cmd->add_option("-o,--output", "File to write")->required();
  cmd->add_option("--cell", "Raster cell size in metres (exr, tif)");
  cmd->callback([] { throw notImplemented("tinsmith export"); });
}

}  // namespace tinsmith::cli
