// `tinsmith export`: export a TIN: OBJ or PLY (ASCII, full precision), an EXR
// or GeoTIFF heightmap (`--cell` metres), a single glb (not built yet).
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "core/base/error.hpp"
#include "ingest/export/mesh_export.hpp"
#include "ingest/export/rasterise.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"

namespace tinsmith::cli {

namespace {
struct ExportOptions {
  std::string tin;
  std::string format;
  std::string output;
  std::optional<double> cell;
};
}  // namespace

void addExportCommand(CLI::App& app) {
  auto opt = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand("export", "Export a TIN: OBJ, PLY, EXR or GeoTIFF heightmap, single glb");
  cmd->add_option("tin", opt->tin, "The .tin file")->required();
  cmd->add_option("--format", opt->format, "obj | ply | exr | tif | glb")->required();
  addOutputOption(*cmd, opt->output, "File to write")->required();
  cmd->add_option("--cell", opt->cell, "Raster cell size in metres (exr, tif)");
  cmd->callback([opt] {
    const std::string& f = opt->format;
    if (f != "obj" && f != "ply" && f != "exr" && f != "tif" && f != "glb")
      throw usageError("unknown --format '" + f + "'", "use one of obj, ply, exr, tif, glb");
    if ((f == "exr" || f == "tif") && !opt->cell)
      throw usageError("--format " + f + " needs --cell (the raster cell size in metres)",
                       "e.g. --cell 1.0");
    if (opt->cell && !(*opt->cell > 0))
      throw usageError("--cell must be a positive number of metres");
    if (f == "glb") throw notImplemented("tinsmith export --format glb (a single Draco glTF)");
    const TinData tin = ingest::readTinFile(opt->tin);
    if (f == "obj") {
      ingest::writeObj(opt->output, tin);
    } else if (f == "ply") {
      ingest::writePly(opt->output, tin);
    } else {
      ingest::writeHeightmap(tin, *opt->cell, f, opt->output);
    }
    std::cerr << "wrote " << opt->output << ": " << tin.vertices.size() << " vertices, "
              << tin.triangles.size() << " triangles\n";
  });
}

}  // namespace tinsmith::cli
