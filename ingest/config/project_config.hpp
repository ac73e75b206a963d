// config: the TOML project file (documented key by key in config/README.md).
//
//   [project]  name, crs ("EPSG:xxxx" or WKT; projected, metres)
//   [[layer]]  path, kind, layer, name, z, z_value, crs, weight, and for text
//              files x, y, delimiter, header; for rasters band, nodata
//   [tin]      snap_tolerance, flat_triangle_repair, river_descent, strict
//   [tiles]    tolerance, max_triangles, max_zoom, lambda, compression, frame,
//              geoid (the options of `tinsmith tile`), output (the store)
//   [fit], [server]  accepted; their keys are kept as raw TOML text (see
//              ProjectConfig::extraTables); `tinsmith serve --config` reads
//              [server] itself (server/app/server_config.hpp)
//
// A layer's path may be a "synthetic:…" spec (readers.synthetic,
// ingest/readers/synthetic_reader.hpp) instead of a file; it is checked here.
//
// Every problem is a tinsmith::Error (kind Input) whose location names the
// config file and the line, and whose message names the key: unknown keys,
// wrong types, out-of-range values, missing files, a geographic project CRS.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/tin/tin_data.hpp"
#include "ingest/readers/text_points.hpp"
#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::ingest {

/// The `kind` of a layer, as written in the config.
enum class LayerKind { Contours, Points, Road, River, Boundary, Hole, Lake, Dem };

std::string_view toString(LayerKind kind);
/// "contours" → LayerKind::Contours; nullopt for an unknown name.
std::optional<LayerKind> parseLayerKind(std::string_view name);
/// The interchange kind the TIN builder uses (core/tin/tin_data.hpp).
FeatureKind featureKind(LayerKind kind);

/// Which geometry a layer kind takes.
enum class GeometryClass { Points, Lines, Areas, Raster };
GeometryClass geometryClass(LayerKind kind);

struct LayerConfig {
  std::string name;            ///< `name`, else the file name (plus ":layer")
  std::filesystem::path path;  ///< absolute: resolved against the config's folder;
                               ///< or a "synthetic:…" spec as written (readers.synthetic)
  std::string layer;           ///< layer inside a multi-layer dataset; empty: the first
  LayerKind kind = LayerKind::Points;
  std::string zAttribute;        ///< `z`: attribute (or CSV column) holding z; empty: 3D geometry
  std::optional<double> zValue;  ///< `z_value`: every vertex gets this z (e.g. a coastline at 0)
  std::string crs;               ///< `crs` override of the file's own CRS; empty: the file's
  double weight = 1.0;           ///< `weight` (> 0), used by the fitter
  // Text point files (.csv, .txt, .xyz, .tsv).
  std::string xColumn, yColumn;                   ///< `x`, `y` column names; empty: detect
  TextDelimiter delimiter = TextDelimiter::Auto;  ///< `delimiter`
  TextHeader header = TextHeader::Auto;           ///< `header` = true | false
  // Rasters (kind = "dem").
  int band = 1;                  ///< `band`, 1-based
  std::optional<double> nodata;  ///< `nodata` override of the raster's own
  std::int64_t configLine = 0;   ///< line of the [[layer]] in the config file
};

/// A layer named on the command line, not in a config: its name, its file
/// (or synthetic spec) and its kind; every other key at its default.
inline LayerConfig commandLineLayer(std::string name, std::filesystem::path path, LayerKind kind) {
  LayerConfig config;
  config.name = std::move(name);
  config.path = std::move(path);
  config.kind = kind;
  return config;
}

struct TinOptions {
  double snapTolerance = 0.001;  ///< metres: points and vertices closer than this are merged
  bool flatTriangleRepair = true;
  bool riverDescent = true;
  bool strict = false;  ///< data errors (crossing contours) are fatal
};

/// [tiles]: how `tinsmith build` tiles the TIN. Keys left out keep
/// TileJobOptions' defaults (those of `tinsmith tile`); command-line flags
/// override them.
struct TilesConfig {
  TileJobOptions job;  ///< tiler, compression, frame, geoid; nothing else is set
  std::filesystem::path
      output;  ///< `output`: absolute (resolved against the config's folder); empty: not given
  std::int64_t configLine = 0;  ///< line of [tiles]; 0: no [tiles] table
};

struct ProjectConfig {
  std::filesystem::path file;  ///< the config file (absolute)
  std::string name;            ///< [project] name; default: the config file's stem
  std::string crs;             ///< [project] crs as written: "EPSG:26912" or WKT
  std::vector<LayerConfig> layers;
  TinOptions tin;
  TilesConfig tiles;
  /// Tables whose parsers live elsewhere ("fit", "server"), each as
  /// TOML text holding only that table, plus the line where it starts.
  struct RawTable {
    std::string toml;
    std::int64_t line = 0;
  };
  std::map<std::string, RawTable> extraTables;
};

/// Reads and checks a project config. Relative layer paths are resolved
/// against the config file's folder and each must exist. Throws tinsmith::Error.
ProjectConfig loadProjectConfig(const std::filesystem::path& file);

/// Same, from text; `file` names it in errors and anchors relative paths.
ProjectConfig parseProjectConfig(std::string_view text, const std::filesystem::path& file);

/// Throws unless `crs` is a known, projected CRS in metres (the project CRS).
/// `where` names the key in errors.
void checkProjectCrs(const std::string& crs, const std::string& where);

}  // namespace tinsmith::ingest
