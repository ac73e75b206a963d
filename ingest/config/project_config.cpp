#include "ingest/config/project_config.hpp"

#include <ogr_spatialref.h>
#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include "core/base/error.hpp"
#include "ingest/config/toml_nodes.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "ingest/readers/synthetic_reader.hpp"

namespace tinsmith::ingest {

std::string_view toString(LayerKind kind) {
  switch (kind) {
    case LayerKind::Contours:
      return "contours";
    case LayerKind::Points:
      return "points";
    case LayerKind::Road:
      return "road";
    case LayerKind::River:
      return "river";
    case LayerKind::Boundary:
      return "boundary";
    case LayerKind::Hole:
      return "hole";
    case LayerKind::Lake:
      return "lake";
    case LayerKind::Dem:
      return "dem";
  }
  return "?";
}

std::optional<LayerKind> parseLayerKind(std::string_view name) {
  for (auto k : {LayerKind::Contours, LayerKind::Points, LayerKind::Road, LayerKind::River,
                 LayerKind::Boundary, LayerKind::Hole, LayerKind::Lake, LayerKind::Dem}) {
    if (toString(k) == name) return k;
  }
  return std::nullopt;
}

FeatureKind featureKind(LayerKind kind) {
  switch (kind) {
    case LayerKind::Contours:
      return FeatureKind::Contour;
    case LayerKind::Points:
      return FeatureKind::SpotHeight;
    case LayerKind::Road:
      return FeatureKind::Road;
    case LayerKind::River:
      return FeatureKind::River;
    case LayerKind::Boundary:
      return FeatureKind::Boundary;
    case LayerKind::Hole:
      return FeatureKind::Hole;
    case LayerKind::Lake:
      return FeatureKind::Lake;
    case LayerKind::Dem:
      return FeatureKind::Raster;
  }
  return FeatureKind::Other;
}

GeometryClass geometryClass(LayerKind kind) {
  switch (kind) {
    case LayerKind::Points:
      return GeometryClass::Points;
    case LayerKind::Contours:
    case LayerKind::Road:
    case LayerKind::River:
      return GeometryClass::Lines;
    case LayerKind::Boundary:
    case LayerKind::Hole:
    case LayerKind::Lake:
      return GeometryClass::Areas;
    case LayerKind::Dem:
      return GeometryClass::Raster;
  }
  return GeometryClass::Points;
}

void checkProjectCrs(const std::string& crs, const std::string& where) {
  ensureGdalReady();
  OGRSpatialReference srs;
  if (crs.empty() || srs.SetFromUserInput(crs.c_str()) != OGRERR_NONE) {
    throw inputError(where + ": '" + crs + "' is not a CRS GDAL/PROJ knows", {},
                     "write it as \"EPSG:code\" (e.g. \"EPSG:32612\" for UTM 12N) or as WKT");
  }
  if (srs.IsGeographic() || !srs.IsProjected()) {
    throw inputError(
        where + ": '" + crs + "' (" + (srs.GetName() ? srs.GetName() : "?") +
            ") is not a projected CRS; tinsmith builds TINs in projected metres",
        {},
        "choose a projected CRS in metres, such as the UTM zone of the data (e.g. \"EPSG:32619\")");
  }
  const char* unitName = nullptr;
  const double unit = srs.GetLinearUnits(&unitName);
  if (std::abs(unit - 1.0) > 1e-9) {
    throw inputError(where + ": '" + crs + "' has linear unit '" + (unitName ? unitName : "?") +
                         "'; tinsmith needs metres (heights and tolerances are metres)",
                     {},
                     "choose a projected CRS in metres (e.g. the data's UTM zone; a config "
                     "reprojects layers given in feet into it, and heights must be metres)");
  }
}

namespace {

struct Context {
  std::string file;  // config file name for messages

  [[noreturn]] void fail(const std::string& problem, std::int64_t line,
                         const std::string& hint = {}) const {
    SourceLocation where;
    where.file = file;
    if (line > 0) where.line = line;
    throw inputError(problem, where, hint);
  }
};

/// A value as the config wrote it, for messages: 0, -2.5, "zstd".
std::string written(const toml::node& node) {
  if (const auto* s = node.as_string()) return "\"" + s->get() + "\"";
  std::ostringstream out;
  node.visit([&out](const auto& value) { out << value; });
  return out.str();
}

void checkKeys(const Context& ctx, const toml::table& table, const std::string& tableName,
               const std::set<std::string>& allowed) {
  for (const auto& [key, node] : table) {
    if (!allowed.count(std::string(key.str()))) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      ctx.fail("unknown key '" + std::string(key.str()) + "' in " + tableName, lineOf(node),
               "allowed keys: " + list + " (see config/README.md)");
    }
  }
}

[[noreturn]] void failType(const Context& ctx, const toml::node& node, const std::string& name,
                           const std::string& expected) {
  ctx.fail(name + " must be " + expected + ", not " + typeName(node) + " (" + written(node) + ")",
           lineOf(node),
           node.is_string() ? "write " + expected + " without quotes"
                            : (expected == "a string" ? "put it in quotes" : ""));
}

std::optional<std::string> getString(const Context& ctx, const toml::table& t,
                                     const std::string& key, const std::string& tableName) {
  const auto* node = t.get(key);
  if (!node) return std::nullopt;
  if (const auto* s = node->as_string()) return s->get();
  failType(ctx, *node, tableName + "." + key, "a string");
}

std::optional<double> getNumber(const Context& ctx, const toml::table& t, const std::string& key,
                                const std::string& tableName) {
  const auto* node = t.get(key);
  if (!node) return std::nullopt;
  if (const auto* f = node->as_floating_point()) {
    if (!std::isfinite(f->get()))
      ctx.fail(tableName + "." + key + " must be finite", lineOf(*node));
    return f->get();
  }
  if (const auto* i = node->as_integer()) return static_cast<double>(i->get());
  failType(ctx, *node, tableName + "." + key, "a number");
}

std::optional<std::int64_t> getInteger(const Context& ctx, const toml::table& t,
                                       const std::string& key, const std::string& tableName) {
  const auto* node = t.get(key);
  if (!node) return std::nullopt;
  if (const auto* i = node->as_integer()) return i->get();
  failType(ctx, *node, tableName + "." + key, "an integer");
}

std::optional<bool> getBool(const Context& ctx, const toml::table& t, const std::string& key,
                            const std::string& tableName) {
  const auto* node = t.get(key);
  if (!node) return std::nullopt;
  if (const auto* b = node->as_boolean()) return b->get();
  failType(ctx, *node, tableName + "." + key, "true or false");
}

std::int64_t keyLine(const toml::table& t, const std::string& key) {
  const auto* node = t.get(key);
  return node ? lineOf(*node) : lineOf(t);
}

LayerConfig parseLayer(const Context& ctx, const toml::table& t, std::size_t index,
                       const std::filesystem::path& baseDir) {
  const std::string tn = "[[layer]] #" + std::to_string(index + 1);
  checkKeys(ctx, t, tn,
            {"path", "layer", "kind", "z", "z_value", "crs", "weight", "name", "x", "y",
             "delimiter", "header", "band", "nodata"});
  LayerConfig layer;
  layer.configLine = lineOf(t);

  const auto path = getString(ctx, t, "path", tn);
  if (!path || path->empty())
    ctx.fail(tn + " has no 'path'", layer.configLine, "give the data file's path");
  const bool synthetic = isSyntheticSpec(*path);
  layer.path = std::filesystem::path(*path);
  if (!synthetic) {
    if (layer.path.is_relative()) layer.path = baseDir / layer.path;
    layer.path = layer.path.lexically_normal();
  }

  const auto kind = getString(ctx, t, "kind", tn);
  if (!kind)
    ctx.fail(tn + " has no 'kind'", layer.configLine,
             "kind = contours | points | road | river | boundary | hole | lake | dem");
  const auto parsed = parseLayerKind(*kind);
  if (!parsed) {
    ctx.fail(tn + ".kind: unknown kind '" + *kind + "'", keyLine(t, "kind"),
             "kind = contours | points | road | river | boundary | hole | lake | dem");
  }
  layer.kind = *parsed;

  layer.layer = getString(ctx, t, "layer", tn).value_or("");
  layer.zAttribute = getString(ctx, t, "z", tn).value_or("");
  layer.zValue = getNumber(ctx, t, "z_value", tn);
  if (layer.zValue && !layer.zAttribute.empty()) {
    ctx.fail(tn + ": give either 'z' (an attribute) or 'z_value' (a fixed z), not both",
             keyLine(t, "z_value"));
  }
  layer.crs = getString(ctx, t, "crs", tn).value_or("");
  if (!layer.crs.empty()) {
    OGRSpatialReference srs;
    ensureGdalReady();
    if (srs.SetFromUserInput(layer.crs.c_str()) != OGRERR_NONE) {
      ctx.fail(tn + ".crs: '" + layer.crs + "' is not a CRS GDAL/PROJ knows", keyLine(t, "crs"),
               "write it as \"EPSG:code\" or as WKT");
    }
  }
  layer.weight = getNumber(ctx, t, "weight", tn).value_or(1.0);
  if (!(layer.weight > 0.0)) ctx.fail(tn + ".weight must be greater than 0", keyLine(t, "weight"));

  layer.xColumn = getString(ctx, t, "x", tn).value_or("");
  layer.yColumn = getString(ctx, t, "y", tn).value_or("");
  if (const auto d = getString(ctx, t, "delimiter", tn)) {
    if (*d == "auto")
      layer.delimiter = TextDelimiter::Auto;
    else if (*d == "comma" || *d == ",")
      layer.delimiter = TextDelimiter::Comma;
    else if (*d == "semicolon" || *d == ";")
      layer.delimiter = TextDelimiter::Semicolon;
    else if (*d == "tab" || *d == "\t")
      layer.delimiter = TextDelimiter::Tab;
    else if (*d == "whitespace" || *d == " ")
      layer.delimiter = TextDelimiter::Whitespace;
    else
      ctx.fail(tn + ".delimiter: unknown delimiter '" + *d + "'", keyLine(t, "delimiter"),
               "delimiter = auto | comma | semicolon | tab | whitespace");
  }
  if (const auto h = getBool(ctx, t, "header", tn))
    layer.header = *h ? TextHeader::Present : TextHeader::Absent;
  if (const auto b = getInteger(ctx, t, "band", tn)) {
    if (*b < 1 || *b > 65535) ctx.fail(tn + ".band must be 1 or more", keyLine(t, "band"));
    layer.band = static_cast<int>(*b);
  }
  layer.nodata = getNumber(ctx, t, "nodata", tn);

  const bool rasterKey = t.contains("band") || t.contains("nodata");
  if (rasterKey && layer.kind != LayerKind::Dem) {
    ctx.fail(tn + ": 'band' and 'nodata' apply to kind = \"dem\" only",
             keyLine(t, t.contains("band") ? "band" : "nodata"));
  }

  if (synthetic) {
    if (!layer.zAttribute.empty())
      ctx.fail(tn + ".z: a synthetic layer has no attributes", keyLine(t, "z"),
               "leave 'z' out (z comes from the spec's surface), or use z_value");
    if (t.contains("x") || t.contains("y") || t.contains("delimiter") || t.contains("header") ||
        rasterKey || t.contains("layer"))
      ctx.fail(
          tn + ": a synthetic layer takes none of layer, x, y, delimiter, header, band, nodata",
          layer.configLine, "they describe files; the spec says everything else");
    try {
      checkSyntheticSpec(*path, layer.kind);
    } catch (const Error& e) {
      ctx.fail(tn + ".path: " + e.where().file + ": " + e.problem(), keyLine(t, "path"), e.hint());
    }
  }
  std::error_code ec;
  if (!synthetic && !std::filesystem::exists(layer.path, ec)) {
    ctx.fail(tn + ".path: file not found: " + layer.path.string(), keyLine(t, "path"),
             "paths are relative to the config file's folder");
  }

  if (const auto name = getString(ctx, t, "name", tn)) {
    layer.name = *name;
  } else if (synthetic) {
    layer.name = *path;
  } else {
    layer.name = layer.path.filename().string();
    if (!layer.layer.empty()) layer.name += ":" + layer.layer;
  }
  return layer;
}

TilesConfig parseTiles(const Context& ctx, const toml::table& t,
                       const std::filesystem::path& baseDir) {
  const std::string tn = "tiles";
  checkKeys(ctx, t, "[tiles]",
            {"tolerance", "max_triangles", "max_zoom", "lambda", "compression", "frame", "geoid",
             "scheme", "attribution", "output"});
  // "tiles.KEY = VALUE: PROBLEM", at the key's line.
  auto bad = [&](const std::string& key, const std::string& problem, const std::string& hint) {
    ctx.fail("tiles." + key + " = " + written(*t.get(key)) + ": " + problem, keyLine(t, key), hint);
  };
  TilesConfig tiles;
  tiles.configLine = lineOf(t);
  auto& tiler = tiles.job.tiler;
  if (const auto v = getNumber(ctx, t, "tolerance", tn)) {
    if (!(*v > 0))
      bad("tolerance", "must be greater than 0 (metres)",
          "the finest zoom's largest vertical error against the TIN, e.g. tolerance = 1");
    tiler.tolerance = *v;
  }
  if (const auto v = getInteger(ctx, t, "max_triangles", tn)) {
    if (*v < 64)
      bad("max_triangles", "must be at least 64",
          "about how many triangles a tile may hold; the default is 32768");
    tiler.maxTriangles = static_cast<std::size_t>(*v);
  }
  if (const auto v = getInteger(ctx, t, "max_zoom", tn)) {
    if (*v < 0 || *v > 30)
      bad("max_zoom", "must be 0 to 30", "leave it out to stop 6 zooms below the planned finest");
    tiler.maxZoom = static_cast<int>(*v);
  }
  if (const auto v = getNumber(ctx, t, "lambda", tn)) {
    if (!(*v > 0))
      bad("lambda", "must be greater than 0 (a multiple of λ_d)", "the default is 0.01");
    tiler.lambdaFactor = *v;
  }
  if (const auto v = getString(ctx, t, "compression", tn)) {
    const auto c = parseCompression(*v);
    if (!c) bad("compression", "unknown compression", "compression = \"draco\" | \"none\"");
    tiles.job.compression = *c;
  }
  if (const auto v = getString(ctx, t, "frame", tn)) {
    const auto f = parseContentFrame(*v);
    if (!f)
      bad("frame", "unknown frame", "frame = \"ecef\" (on the globe) | \"local\" (ENU metres)");
    tiles.job.frame = *f;
  }
  if (const auto v = getString(ctx, t, "geoid", tn)) {
    if (!isKnownGeoid(*v))
      bad("geoid", "unknown geoid",
          "geoid = \"egm96\" when z are EGM96 (≈ mean sea level) heights, \"\" when ellipsoidal");
    tiles.job.geoid = *v;
  }
  if (const auto v = getString(ctx, t, "scheme", tn)) {
    const auto sc = parseTileScheme(*v);
    if (!sc)
      bad("scheme", "unknown scheme",
          "scheme = \"3d-tiles\" | \"quantized-mesh\" (Cesium terrain) | \"both\"");
    tiles.job.scheme = *sc;
  }
  if (const auto v = getString(ctx, t, "attribution", tn)) tiles.job.attribution = *v;
  if (const auto v = getString(ctx, t, "output", tn)) {
    if (v->empty())
      bad("output", "is empty", "give the tile store's path: NAME.3dtiles or a directory");
    std::filesystem::path out(*v);
    if (out.is_relative()) out = baseDir / out;
    tiles.output = out.lexically_normal();
  }
  return tiles;
}

}  // namespace

ProjectConfig parseProjectConfig(std::string_view text, const std::filesystem::path& file) {
  Context ctx{file.filename().string()};
  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    ctx.fail("not valid TOML: " + std::string(e.description()),
             static_cast<std::int64_t>(e.source().begin.line));
  }

  ProjectConfig config;
  config.file = std::filesystem::absolute(file).lexically_normal();
  checkKeys(ctx, root, "the config", {std::begin(kConfigTables), std::end(kConfigTables)});

  const auto* projectNode = root.get("project");
  if (!projectNode) ctx.fail("no [project] table", 1, "add [project] with crs = \"EPSG:...\"");
  const auto* project = projectNode->as_table();
  if (!project) ctx.fail("'project' must be a table", lineOf(*projectNode));
  checkKeys(ctx, *project, "[project]", {"name", "crs"});
  config.name = getString(ctx, *project, "name", "project").value_or(file.stem().string());
  const auto crs = getString(ctx, *project, "crs", "project");
  if (!crs)
    ctx.fail("[project] has no 'crs'", lineOf(*project),
             "add crs = \"EPSG:...\" (projected, metres)");
  config.crs = *crs;
  try {
    checkProjectCrs(config.crs, "project.crs");
  } catch (const Error& e) {
    ctx.fail(e.problem(), keyLine(*project, "crs"), e.hint());
  }

  const auto baseDir = config.file.parent_path();
  if (const auto* layersNode = root.get("layer")) {
    const auto* layers = layersNode->as_array();
    if (!layers || !layers->is_array_of_tables()) {
      ctx.fail("'layer' must be written as [[layer]] tables", lineOf(*layersNode));
    }
    for (std::size_t i = 0; i < layers->size(); ++i) {
      config.layers.push_back(parseLayer(ctx, *layers->get(i)->as_table(), i, baseDir));
    }
  }
  std::set<std::string> names;
  for (const auto& layer : config.layers) {
    if (!names.insert(layer.name).second) {
      ctx.fail("two layers are named '" + layer.name + "'", layer.configLine,
               "give one of them a 'name'");
    }
  }

  if (const auto* tinNode = root.get("tin")) {
    const auto* tin = tinNode->as_table();
    if (!tin) ctx.fail("'tin' must be a table", lineOf(*tinNode));
    checkKeys(ctx, *tin, "[tin]",
              {"snap_tolerance", "flat_triangle_repair", "river_descent", "strict"});
    config.tin.snapTolerance =
        getNumber(ctx, *tin, "snap_tolerance", "tin").value_or(config.tin.snapTolerance);
    if (config.tin.snapTolerance < 0.0) {
      ctx.fail("tin.snap_tolerance must be 0 or more (metres)", keyLine(*tin, "snap_tolerance"));
    }
    config.tin.flatTriangleRepair =
        getBool(ctx, *tin, "flat_triangle_repair", "tin").value_or(config.tin.flatTriangleRepair);
    config.tin.riverDescent =
        getBool(ctx, *tin, "river_descent", "tin").value_or(config.tin.riverDescent);
    config.tin.strict = getBool(ctx, *tin, "strict", "tin").value_or(config.tin.strict);
  }

  if (const auto* tilesNode = root.get("tiles")) {
    const auto* tiles = tilesNode->as_table();
    if (!tiles) ctx.fail("'tiles' must be a table", lineOf(*tilesNode));
    config.tiles = parseTiles(ctx, *tiles, baseDir);
  }

  for (const char* name : {"fit", "server"}) {
    if (const auto* node = root.get(name)) {
      const auto* table = node->as_table();
      if (!table) ctx.fail(std::string("'") + name + "' must be a table", lineOf(*node));
      std::ostringstream out;
      out << toml::table{{name, *table}};
      config.extraTables[name] = {out.str(), lineOf(*node)};
    }
  }
  return config;
}

ProjectConfig loadProjectConfig(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    throw inputError("config file not found", fileLocation(file), "check the path");
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) {
    throw inputError("cannot read the config file", fileLocation(file), "check its permissions");
  }
  return parseProjectConfig(text.str(), file);
}

}  // namespace tinsmith::ingest
