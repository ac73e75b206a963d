#include "ingest/readers/layer_reader.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <memory>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "ingest/readers/raster_reader.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "ingest/readers/text_points.hpp"

namespace tinsmith::ingest {

SourceLocation layerLocation(const LayerConfig& config, std::optional<std::int64_t> fid) {
  SourceLocation where;
  where.file = config.path.filename().string();
  if (!config.layer.empty()) {
    where.layer = config.layer;
  } else if (config.name != where.file) {
    where.layer = config.name;
  }
  where.feature = fid;
  return where;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string crsString(const OGRSpatialReference* srs) {
  if (!srs) return {};
  const char* name = srs->GetAuthorityName(nullptr);
  const char* code = srs->GetAuthorityCode(nullptr);
  if (name && code) return std::string(name) + ":" + code;
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  srs->exportToWkt(&wkt, options);
  std::string out = wkt ? wkt : "";
  CPLFree(wkt);
  return out;
}

bool needsZ(LayerKind kind) {
  return kind == LayerKind::Contours || kind == LayerKind::Points;
}

const char* geometryNoun(GeometryClass c) {
  switch (c) {
    case GeometryClass::Points:
      return "points (Point, MultiPoint)";
    case GeometryClass::Lines:
      return "lines (LineString, MultiLineString)";
    case GeometryClass::Areas:
      return "polygons (Polygon, MultiPolygon) or closed lines";
    case GeometryClass::Raster:
      return "a raster";
  }
  return "?";
}

std::string kindHint(GeometryClass found) {
  switch (found) {
    case GeometryClass::Points:
      return "for point data use kind = \"points\"";
    case GeometryClass::Lines:
      return "for lines use kind = \"contours\", \"road\" or \"river\"";
    case GeometryClass::Areas:
      return "for polygons use kind = \"lake\", \"boundary\" or \"hole\"";
    case GeometryClass::Raster:
      return "for a raster use kind = \"dem\"";
  }
  return {};
}

enum class ZSource { Fixed, Attribute, Geometry };

class OgrLayerReader {
 public:
  OgrLayerReader(const LayerConfig& config, IngestedLayer& out) : config_(config), out_(out) {
    wantClass_ = geometryClass(config.kind);
  }

  void read(OGRLayer& layer, const Progress* progress) {
    auto* defn = layer.GetLayerDefn();
    if (config_.zValue) {
      zSource_ = ZSource::Fixed;
    } else if (!config_.zAttribute.empty()) {
      zSource_ = ZSource::Attribute;
      zField_ = defn->GetFieldIndex(config_.zAttribute.c_str());
      if (zField_ < 0) {
        std::string numeric;
        for (int i = 0; i < defn->GetFieldCount(); ++i) {
          const auto type = defn->GetFieldDefn(i)->GetType();
          if (type == OFTInteger || type == OFTInteger64 || type == OFTReal) {
            numeric +=
                (numeric.empty() ? "" : ", ") + std::string(defn->GetFieldDefn(i)->GetNameRef());
          }
        }
        throw inputError("has no attribute '" + config_.zAttribute + "'", layerLocation(config_),
                         numeric.empty()
                             ? "the layer has no numeric attributes; give 3D geometries or z_value"
                             : "numeric attributes here: " + numeric + "; set z to one of them");
      }
      zType_ = defn->GetFieldDefn(zField_)->GetType();
      if (zType_ != OFTInteger && zType_ != OFTInteger64 && zType_ != OFTReal &&
          zType_ != OFTString) {
        throw inputError("attribute '" + config_.zAttribute + "' is of type " +
                             OGRFieldDefn::GetFieldTypeName(zType_) + ", not a number",
                         layerLocation(config_), "choose a numeric attribute for z");
      }
    } else {
      zSource_ = ZSource::Geometry;
    }

    const GIntBig total = layer.GetFeatureCount(FALSE);
    const std::string detail = config_.name;
    ProgressTicker ticker(progress, "readers.ogr", detail,
                          total > 0 ? static_cast<std::uint64_t>(total) : 0);
    std::uint64_t done = 0;
    layer.ResetReading();
    for (const auto& feature : layer) {
      ticker.step(++done);
      readFeature(*feature);
    }
    ticker.finish();
    if (out_.points.empty() && out_.features.empty()) {
      throw inputError(
          out_.nullGeometriesSkipped ? "has features but none has a geometry" : "holds no features",
          layerLocation(config_), "check the file and the layer name, or remove the layer");
    }
    out_.hasZ = allHaveZ_;
  }

 private:
  void readFeature(OGRFeature& feature) {
    fid_ = feature.GetFID();
    const OGRGeometry* geometry = feature.GetGeometryRef();
    if (!geometry || geometry->IsEmpty()) {
      ++out_.nullGeometriesSkipped;
      return;
    }
    featureZ_ = kNaN;
    if (zSource_ == ZSource::Fixed) featureZ_ = *config_.zValue;
    if (zSource_ == ZSource::Attribute) featureZ_ = attributeZ(feature);
    part_ = 0;
    addGeometry(*geometry);
  }

  double attributeZ(OGRFeature& feature) const {
    const auto where = layerLocation(config_, fid_);
    if (!feature.IsFieldSetAndNotNull(zField_)) {
      throw inputError("attribute '" + config_.zAttribute + "' is empty", where,
                       "give every feature a numeric elevation or drop the feature");
    }
    double z = 0.0;
    if (zType_ == OFTString) {
      std::string_view text = feature.GetFieldAsString(zField_);
      while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
      while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
      const auto result = std::from_chars(text.data(), text.data() + text.size(), z);
      if (text.empty() || result.ec != std::errc() || result.ptr != text.data() + text.size()) {
        throw inputError(
            "attribute '" + config_.zAttribute + "' is not numeric ('" + std::string(text) + "')",
            where, "give every feature a numeric elevation or drop the feature");
      }
    } else {
      z = feature.GetFieldAsDouble(zField_);
    }
    if (!std::isfinite(z)) {
      throw inputError("attribute '" + config_.zAttribute + "' is not finite (NaN or infinity)",
                       where, "give the feature a real elevation or drop it");
    }
    return z;
  }

  [[noreturn]] void wrongGeometry(const OGRGeometry& g, GeometryClass found) const {
    throw inputError(std::string("is a ") + g.getGeometryName() + ", but kind = \"" +
                         std::string(toString(config_.kind)) + "\" takes " +
                         geometryNoun(wantClass_),
                     layerLocation(config_, fid_), kindHint(found));
  }

  void addGeometry(const OGRGeometry& g) {
    if (g.hasCurveGeometry()) {
      std::unique_ptr<OGRGeometry> linear(g.getLinearGeometry());
      if (linear) addGeometry(*linear);
      return;
    }
    switch (wkbFlatten(g.getGeometryType())) {
      case wkbPoint: {
        if (wantClass_ != GeometryClass::Points) wrongGeometry(g, GeometryClass::Points);
        const auto& p = *g.toPoint();
        const auto v = vertex(p.getX(), p.getY(), p.getZ(), p.Is3D());
        out_.points.push_back(v);
        out_.pointIds.push_back(fid_);
        break;
      }
      case wkbLineString: {
        if (wantClass_ == GeometryClass::Points) wrongGeometry(g, GeometryClass::Lines);
        addCurve(*g.toLineString(), 0, wantClass_ == GeometryClass::Areas);
        ++part_;
        break;
      }
      case wkbPolygon: {
        if (wantClass_ == GeometryClass::Points) wrongGeometry(g, GeometryClass::Areas);
        const auto& poly = *g.toPolygon();
        std::int32_t ring = 0;
        for (const auto* r : poly) addCurve(*r, ring++, true);
        ++part_;
        break;
      }
      case wkbMultiPoint:
      case wkbMultiLineString:
      case wkbMultiPolygon:
      case wkbGeometryCollection: {
        for (const auto* child : *g.toGeometryCollection()) addGeometry(*child);
        break;
      }
      default:
        throw inputError(
            std::string("has a geometry type tinsmith does not read (") + g.getGeometryName() + ")",
            layerLocation(config_, fid_), "convert it to points, lines or polygons");
    }
  }

  Point3 vertex(double x, double y, double z, bool is3D) {
    if (!std::isfinite(x) || !std::isfinite(y)) {
      throw inputError("has a coordinate that is not finite", layerLocation(config_, fid_),
                       "fix or drop the feature");
    }
    Point3 p{x, y, featureZ_};
    if (zSource_ == ZSource::Geometry) {
      if (is3D) {
        if (!std::isfinite(z)) {
          throw inputError("has a vertex whose z is not finite", layerLocation(config_, fid_),
                           "fix or drop the feature");
        }
        p.z = z;
      } else {
        if (needsZ(config_.kind)) {
          throw inputError(
              "has 2D geometry and no z attribute is configured", layerLocation(config_, fid_),
              "set z = \"<attribute>\" (or z_value) in the layer, or give 3D geometries");
        }
        allHaveZ_ = false;
      }
    }
    return p;
  }

  void addCurve(const OGRSimpleCurve& curve, std::int32_t ring, bool mustClose) {
    const int n = curve.getNumPoints();
    if (n == 0) return;
    IngestedFeature f;
    f.fid = fid_;
    f.part = part_;
    f.ring = ring;
    const bool is3D = curve.Is3D();
    f.vertices.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      f.vertices.push_back(vertex(curve.getX(i), curve.getY(i), is3D ? curve.getZ(i) : 0.0, is3D));
    }
    f.hasZ = !std::isnan(f.vertices.front().z);
    if (f.vertices.size() >= 2 && f.vertices.front().x == f.vertices.back().x &&
        f.vertices.front().y == f.vertices.back().y) {
      f.vertices.pop_back();
      f.closed = true;
    }
    if (mustClose && !f.closed) {
      throw inputError("is an open line, but kind = \"" + std::string(toString(config_.kind)) +
                           "\" takes polygons or closed lines",
                       layerLocation(config_, fid_), "close the ring, or use a line kind");
    }
    out_.features.push_back(std::move(f));
  }

  const LayerConfig& config_;
  IngestedLayer& out_;
  GeometryClass wantClass_;
  ZSource zSource_ = ZSource::Geometry;
  int zField_ = -1;
  OGRFieldType zType_ = OFTReal;
  std::int64_t fid_ = 0;
  std::int32_t part_ = 0;
  double featureZ_ = kNaN;
  bool allHaveZ_ = true;
};

IngestedLayer emptyLayer(const LayerConfig& config) {
  IngestedLayer layer;
  layer.config = config;
  layer.kind = featureKind(config.kind);
  return layer;
}

void checkExists(const LayerConfig& config) {
  std::error_code ec;
  if (!std::filesystem::exists(config.path, ec)) {
    throw inputError("file not found", fileLocation(config.path),
                     "check the layer's path (relative to the config file)");
  }
}

}  // namespace

bool isTextPointFile(const std::filesystem::path& path) {
  auto ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".csv" || ext == ".txt" || ext == ".xyz" || ext == ".tsv" || ext == ".pts";
}

IngestedLayer readOgrLayer(const LayerConfig& config, const Progress* progress) {
  checkExists(config);
  ensureGdalReady();
  CPLErrorReset();
  GDALDatasetUniquePtr ds(GDALDataset::Open(
      config.path.string().c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) {
    std::string hint = "give a GeoPackage, Shapefile, GeoJSON or another OGR vector format";
    if (config.kind != LayerKind::Dem) {
      std::unique_ptr<GDALDataset> raster(GDALDataset::Open(config.path.string().c_str(),
                                                            GDAL_OF_RASTER | GDAL_OF_READONLY,
                                                            nullptr, nullptr, nullptr));
      if (raster) hint = "this is a raster: use kind = \"dem\"";
    }
    CPLErrorReset();
    throw inputError("cannot open as a vector dataset" + lastGdalError(), fileLocation(config.path),
                     hint);
  }
  OGRLayer* layer = nullptr;
  auto layerNames = [&] {
    std::string names;
    for (auto* l : ds->GetLayers())
      names += (names.empty() ? "'" : ", '") + std::string(l->GetName()) + "'";
    return names;
  };
  if (!config.layer.empty()) {
    layer = ds->GetLayerByName(config.layer.c_str());
    if (!layer) {
      throw inputError("has no layer '" + config.layer + "'", fileLocation(config.path.filename()),
                       "layers in the file: " + layerNames());
    }
  } else if (ds->GetLayerCount() == 0) {
    throw inputError("holds no layers", layerLocation(config), "check the file");
  } else if (ds->GetLayerCount() > 1) {
    throw inputError("holds " + std::to_string(ds->GetLayerCount()) + " layers and none is chosen",
                     layerLocation(config), "set layer = one of " + layerNames());
  } else {
    layer = ds->GetLayer(0);
  }

  auto out = emptyLayer(config);
  out.sourceCrs = config.crs.empty() ? crsString(layer->GetSpatialRef()) : config.crs;
  out.crs = out.sourceCrs;
  OgrLayerReader reader(config, out);
  reader.read(*layer, progress);
  return out;
}

IngestedLayer readTextLayer(const LayerConfig& config) {
  checkExists(config);
  if (config.kind != LayerKind::Points) {
    throw inputError("is a text point file, but kind = \"" + std::string(toString(config.kind)) +
                         "\" takes " + geometryNoun(geometryClass(config.kind)),
                     layerLocation(config),
                     "use kind = \"points\", or give lines/polygons in an OGR format");
  }
  TextPointOptions options;
  options.delimiter = config.delimiter;
  options.header = config.header;
  options.xColumn = config.xColumn;
  options.yColumn = config.yColumn;
  options.zColumn = config.zAttribute;
  options.fixedZ = config.zValue;
  auto table = readTextPointTable(config.path, options);
  auto out = emptyLayer(config);
  out.sourceCrs = config.crs;
  out.crs = config.crs;
  out.hasZ = true;
  out.points = std::move(table.points);
  out.pointIds = std::move(table.lines);
  return out;
}

IngestedLayer readRasterLayer(const LayerConfig& config) {
  checkExists(config);
  RasterReadOptions options;
  options.band = config.band;
  options.nodata = config.nodata;
  const auto grid = readHeightGrid(config.path, options);
  auto out = emptyLayer(config);
  out.sourceCrs = config.crs.empty() ? grid.crs : config.crs;
  out.crs = out.sourceCrs;
  out.points = gridToPoints(grid, &out.pointIds);
  if (config.zValue) {
    for (auto& p : out.points) p.z = *config.zValue;
  }
  out.hasZ = true;
  if (out.points.empty()) {
    throw inputError("raster has no cells with data (all nodata)", layerLocation(config),
                     "check the band and the nodata value");
  }
  return out;
}

IngestedLayer readLayer(const LayerConfig& config, const Progress* progress) {
  if (isSyntheticSpec(config.path.string())) return readSyntheticLayer(config);
  if (config.kind == LayerKind::Dem) return readRasterLayer(config);
  if (isTextPointFile(config.path)) return readTextLayer(config);
  return readOgrLayer(config, progress);
}

}  // namespace tinsmith::ingest
