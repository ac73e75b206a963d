// readers.*: one [[layer]] of the config → an IngestedLayer in the layer's own
// CRS (filters.reproject moves it into the project CRS afterwards).
//
//   readers.text   .csv .txt .xyz .tsv .pts  → points (kind = points only)
//   readers.raster kind = dem: any GDAL raster or .exr → points at cell centres
//   readers.ogr    anything else OGR opens (GeoJSON, Shapefile, GeoPackage, …)
//   readers.synthetic  a path "synthetic:PATTERN?…" → generated points, lines
//                  or rings, no file (synthetic_reader.hpp)
//
// z, in order: `z_value` (every vertex), `z` (an attribute / CSV column, must be
// numeric and finite on every feature), else the geometry's own z when it is
// 3D. Kinds contours and points need z; the others may be 2D (z = NaN).
//
// Geometry per kind: points ← Point/MultiPoint; contours, road, river ←
// LineString/MultiLineString (polygon rings accepted as closed lines);
// boundary, hole, lake ← Polygon/MultiPolygon or closed LineStrings.
// GeometryCollections are flattened; features without geometry are skipped
// and counted.
//
// Throws tinsmith::Error (Input) naming file, layer, feature and what to do:
// missing or unreadable file, no such layer (with the list), a dataset with
// several layers and none named, a missing z attribute (with the numeric
// fields there are), a non-numeric / empty / NaN z, NaN coordinates, a
// geometry type the kind cannot take, an empty layer.
#pragma once

#include "ingest/base/progress.hpp"
#include "ingest/readers/ingested_layer.hpp"

namespace tinsmith::ingest {

/// Reads one layer with the reader its file and kind call for.
IngestedLayer readLayer(const LayerConfig& config, const Progress* progress = nullptr);

/// readers.ogr — any OGR vector dataset.
IngestedLayer readOgrLayer(const LayerConfig& config, const Progress* progress = nullptr);

/// readers.text — CSV/XYZ points (see text_points.hpp). The CRS comes only
/// from the layer's `crs` key.
IngestedLayer readTextLayer(const LayerConfig& config);

/// readers.raster — a DEM turned into points, nodata cells left out.
IngestedLayer readRasterLayer(const LayerConfig& config);

/// True for the extensions readers.text takes.
bool isTextPointFile(const std::filesystem::path& path);

}  // namespace tinsmith::ingest
