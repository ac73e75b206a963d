// `tinsmith export`: export a TIN: OBJ or PLY (ASCII, full precision), an EXR
// or GeoTIFF heightmap (`--cell` metres), or the whole TIN as one glTF binary
// (ingest/export/glb_export.hpp: Draco or plain, ECEF or local frame).
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "core/base/error.hpp"
#include "ingest/export/glb_export.hpp"
#include "ingest/export/mesh_export.hpp"
#include "ingest/export/rasterise.hpp"
#include "ingest/tiles/tile_job.hpp"
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
  std::string compression = "draco";
  std::string frame = "ecef";
  std::optional<double> maxPositionError;
  std::string geoid;
};

ingest::GlbExportOptions glbOptions(const ExportOptions& o) {
  ingest::GlbExportOptions g;
  const auto compression = ingest::parseCompression(o.compression);
  if (!compression)
    throw usageError("--compression must be draco or none (got '" + o.compression + "')");
  const auto frame = ingest::parseGlbFrame(o.frame);
  if (!frame) throw usageError("--frame must be ecef or local (got '" + o.frame + "')");
  g.compression = *compression;
  g.frame = *frame;
  g.maxPositionError = o.maxPositionError;
  g.geoid = o.geoid;
  ingest::checkGlbExportOptions(g);
  return g;
}

void reportGlb(const std::string& path, const ingest::GlbExport& g) {
  std::ostringstream s;
  s << "wrote " << path << ": " << g.vertices << " vertices, " << g.triangles << " triangles, "
    << g.bytes.size() << " bytes";
  if (g.positionBits > 0)
    s << " (Draco, " << g.positionBits << "-bit positions";
  else
    s << " (plain";
  s << ", every vertex within " << g.positionErrorBound << " m)\n";
  std::cerr << s.str();
}
}  // namespace

void addExportCommand(CLI::App& app) {
  auto opt = std::make_shared<ExportOptions>();
  auto* cmd =
      app.add_subcommand("export",
                         "Export a TIN: OBJ, PLY, EXR or GeoTIFF heightmap, single glb, or the "
                         ".tin itself in this tinsmith's format");
  cmd->add_option("tin", opt->tin, "The .tin file")->required();
  cmd->add_option("--format", opt->format,
                  "obj | ply | exr | tif | glb | tin (the same TIN in the .tin format this "
                  "tinsmith writes, e.g. for an older file that tiling in shards refuses)")
      ->required();
  addOutputOption(*cmd, opt->output, "File to write")->required();
  cmd->add_option("--cell", opt->cell, "Raster cell size in metres (exr, tif)");
  auto* glbGroup =
      cmd->add_option_group("glb", "--format glb: the whole TIN as one glTF 2.0 binary");
  std::vector<CLI::Option*> glbOnly{
      glbGroup->add_option("--compression", opt->compression, "draco or none (default draco)"),
      glbGroup->add_option("--frame", opt->frame,
                           "ecef: ECEF about the TIN's centre, placed on the globe by the node "
                           "matrix as a tile is (CesiumJS); local: the TIN's x, y, z minus a "
                           "whole-metre offset kept in asset.extras.tinsmith.offset, y up "
                           "(Blender, DCC tools) (default ecef)"),
      glbGroup->add_option("--max-position-error", opt->maxPositionError,
                           "Draco: farthest a decoded position may lie from its TIN vertex, in "
                           "metres, float32 rounding included (default 0.01, as the finest "
                           "tiles; on a TIN over about 12 km, float32's rounding + 0.001)"),
      glbGroup->add_option("--geoid", opt->geoid,
                           "ecef: egm96 when the TIN's z are EGM96 heights, as `tile --geoid` "
                           "(default: z are ellipsoidal heights)")};
  cmd->callback([opt, glbOnly] {
    const std::string& f = opt->format;
    if (f != "obj" && f != "ply" && f != "exr" && f != "tif" && f != "glb" && f != "tin")
      throw usageError("unknown --format '" + f + "'", "use one of obj, ply, exr, tif, glb, tin");
    if ((f == "exr" || f == "tif") && !opt->cell)
      throw usageError("--format " + f + " needs --cell (the raster cell size in metres)",
                       "e.g. --cell 1.0");
    if (opt->cell && !(*opt->cell > 0))
      throw usageError("--cell must be a positive number of metres");
    for (const auto* o : glbOnly) {
      if (f != "glb" && o->count() > 0)
        throw usageError(o->get_name() + " is for --format glb", "leave it out for " + f);
    }
    if (f == "glb") {
      // Every option is checked before the TIN is read or the output touched.
      const ingest::GlbExportOptions options = glbOptions(*opt);
      const TinData tin = ingest::readTinFile(opt->tin);
      reportGlb(opt->output, ingest::writeGlb(opt->output, tin, options, opt->tin));
      return;
    }
    const TinData tin = ingest::readTinFile(opt->tin);
    if (f == "obj") {
      ingest::writeObj(opt->output, tin);
    } else if (f == "ply") {
      ingest::writePly(opt->output, tin);
    } else if (f == "tin") {
      ingest::writeTinFile(opt->output, tin);
    } else {
      ingest::writeHeightmap(tin, *opt->cell, f, opt->output);
    }
    std::cerr << "wrote " << opt->output << ": " << tin.vertices.size() << " vertices, "
              << tin.triangles.size() << " triangles\n";
  });
}

}  // namespace tinsmith::cli
