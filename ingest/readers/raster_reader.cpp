#include "ingest/readers/raster_reader.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfMatrixAttribute.h>
#include <ImfStringAttribute.h>
#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"

namespace tinsmith::ingest {
namespace {

bool isExr(const std::filesystem::path& path) {
  auto ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".exr";
}

}  // namespace

HeightGrid readHeightGrid(const std::filesystem::path& path, const RasterReadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw inputError("raster file not found", fileLocation(path), "check the path");
  if (isExr(path)) {
    auto grid = readExr(path);
    if (options.nodata) {
      const float nd = static_cast<float>(*options.nodata);
      for (auto& v : grid.z) {
        if (v == nd) v = std::numeric_limits<float>::quiet_NaN();
      }
    }
    return grid;
  }
  HeightGrid grid;
  readHeightGridInStrips(path, options, std::numeric_limits<std::size_t>::max(),
                         [&grid](const HeightGrid& frame, int, std::span<const float> z) {
                           grid = frame;
                           grid.z.assign(z.begin(), z.end());
                         });
  return grid;
}

void readHeightGridInStrips(
    const std::filesystem::path& path, const RasterReadOptions& options, std::size_t stripCells,
    const std::function<void(const HeightGrid&, int, std::span<const float>)>& strip) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw inputError("raster file not found", fileLocation(path), "check the path");
  if (isExr(path)) {
    HeightGrid grid = readHeightGrid(path, options);
    std::vector<float> z = std::move(grid.z);
    grid.z.clear();
    strip(grid, 0, z);
    return;
  }
  ensureGdalReady();
  CPLErrorReset();
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(
      path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) {
    throw inputError("cannot open as a raster" + lastGdalError(), fileLocation(path),
                     "give a GeoTIFF (or another GDAL raster) or an OpenEXR heightmap");
  }
  if (options.band < 1 || options.band > ds->GetRasterCount()) {
    throw inputError("has no band " + std::to_string(options.band) + " (it has " +
                         std::to_string(ds->GetRasterCount()) + ")",
                     fileLocation(path), "set 'band' to an existing band");
  }
  HeightGrid grid;
  grid.width = ds->GetRasterXSize();
  grid.height = ds->GetRasterYSize();
  if (ds->GetGeoTransform(grid.geotransform.data()) != CE_None) {
    throw inputError("raster has no georeferencing (no geotransform)", fileLocation(path),
                     "georeference it first, e.g. with gdal_translate -a_ullr … -a_srs …");
  }
  if (const auto* srs = ds->GetSpatialRef()) {
    const char* name = srs->GetAuthorityName(nullptr);
    const char* code = srs->GetAuthorityCode(nullptr);
    if (name && code) {
      grid.crs = std::string(name) + ":" + code;
    } else {
      char* wkt = nullptr;
      srs->exportToWkt(&wkt);
      grid.crs = wkt ? wkt : "";
      CPLFree(wkt);
    }
  }
  auto* band = ds->GetRasterBand(options.band);
  int hasNodata = 0;
  double nodata = band->GetNoDataValue(&hasNodata);
  if (options.nodata) {
    hasNodata = 1;
    nodata = *options.nodata;
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int rows = static_cast<int>(
      std::clamp<std::size_t>(stripCells / static_cast<std::size_t>(std::max(1, grid.width)), 1,
                              static_cast<std::size_t>(std::max(1, grid.height))));
  std::vector<float> z;
  for (int first = 0; first < grid.height; first += rows) {
    const int n = std::min(rows, grid.height - first);
    z.resize(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(n));
    if (band->RasterIO(GF_Read, 0, first, grid.width, n, z.data(), grid.width, n, GDT_Float32, 0, 0,
                       nullptr) != CE_None) {
      throw inputError("cannot read the raster's cells" + lastGdalError(), fileLocation(path),
                       "the file may be damaged");
    }
    if (hasNodata && !std::isnan(nodata)) {
      const float nd = static_cast<float>(nodata);
      for (auto& v : z) {
        if (v == nd) v = nan;
      }
    }
    for (auto& v : z) {
      if (!std::isfinite(v)) v = nan;  // infinities are never heights
    }
    strip(grid, first, z);
  }
}

std::vector<Point3> stripToPoints(const HeightGrid& frame, int firstRow, std::span<const float> z) {
  std::vector<Point3> points;
  const int rows =
      frame.width > 0 ? static_cast<int>(z.size() / static_cast<std::size_t>(frame.width)) : 0;
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      const float v = z[static_cast<std::size_t>(row) * static_cast<std::size_t>(frame.width) +
                        static_cast<std::size_t>(col)];
      if (std::isnan(v)) continue;
      const auto c = frame.cellCentre(col, firstRow + row);
      points.push_back({c.x, c.y, static_cast<double>(v)});
    }
  }
  return points;
}

HeightGrid readExr(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw inputError("EXR file not found", fileLocation(path), "check the path");
  HeightGrid grid;
  try {
    Imf::InputFile file(path.string().c_str());
    const auto& header = file.header();
    const auto dw = header.dataWindow();
    grid.width = dw.max.x - dw.min.x + 1;
    grid.height = dw.max.y - dw.min.y + 1;
    const auto& channels = header.channels();
    std::string channel;
    if (channels.findChannel("Z")) {
      channel = "Z";
    } else if (channels.findChannel("Y")) {
      channel = "Y";
    } else {
      int count = 0;
      for (auto it = channels.begin(); it != channels.end(); ++it) {
        ++count;
        channel = it.name();
      }
      if (count != 1) {
        throw inputError("EXR has no 'Z' channel and " + std::to_string(count) + " others",
                         fileLocation(path), "give a heightmap with one channel named Z");
      }
    }
    if (const auto* gt = header.findTypedAttribute<Imf::M33dAttribute>("geoTransform")) {
      const auto& m = gt->value();
      grid.geotransform = {m[0][2], m[0][0], m[0][1], m[1][2], m[1][0], m[1][1]};
    }
    if (const auto* crs = header.findTypedAttribute<Imf::StringAttribute>("crs"))
      grid.crs = crs->value();
    grid.z.assign(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height),
                  std::numeric_limits<float>::quiet_NaN());
    Imf::FrameBuffer frame;
    frame.insert(channel, Imf::Slice::Make(Imf::FLOAT, grid.z.data(), dw, sizeof(float),
                                           sizeof(float) * static_cast<std::size_t>(grid.width)));
    file.setFrameBuffer(frame);
    file.readPixels(dw.min.y, dw.max.y);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw inputError(std::string("cannot read as an EXR heightmap (OpenEXR: ") + e.what() + ")",
                     fileLocation(path), "the file may be damaged or not an OpenEXR file");
  }
  for (auto& v : grid.z) {
    if (!std::isfinite(v)) v = std::numeric_limits<float>::quiet_NaN();
  }
  return grid;
}

std::vector<Point3> gridToPoints(const HeightGrid& grid, std::vector<std::int64_t>* cellIds) {
  std::vector<Point3> points;
  std::size_t valid = 0;
  for (const float v : grid.z) valid += std::isnan(v) ? 0 : 1;
  points.reserve(valid);
  if (cellIds) {
    cellIds->clear();
    cellIds->reserve(valid);
  }
  for (int row = 0; row < grid.height; ++row) {
    for (int col = 0; col < grid.width; ++col) {
      const float v = grid.at(col, row);
      if (std::isnan(v)) continue;
      const auto c = grid.cellCentre(col, row);
      points.push_back({c.x, c.y, static_cast<double>(v)});
      if (cellIds) cellIds->push_back(static_cast<std::int64_t>(row) * grid.width + col);
    }
  }
  return points;
}

}  // namespace tinsmith::ingest
