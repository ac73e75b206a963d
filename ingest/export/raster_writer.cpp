#include "ingest/export/raster_writer.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <limits>
#include <memory>
#include <string>

#include "core/base/error.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/base/gdal_runtime.hpp"

namespace tinsmith::ingest {
namespace {

void checkGrid(const HeightGrid& grid, const std::filesystem::path& path) {
  if (grid.width <= 0 || grid.height <= 0 ||
      grid.z.size() !=
          static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height)) {
    throw ioError("height grid is malformed: " + std::to_string(grid.width) + " x " +
                      std::to_string(grid.height) + " with " + std::to_string(grid.z.size()) +
                      " values",
                  fileLocation(path));
  }
}

}  // namespace

void writeGeoTiff(const HeightGrid& grid, const std::filesystem::path& path) {
  checkGrid(grid, path);
  ensureGdalReady();
  auto* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) throw internalError("GDAL has no GTiff driver");
  AtomicPath out(path);
  char** options = nullptr;
  options = CSLSetNameValue(options, "COMPRESS", "DEFLATE");
  options = CSLSetNameValue(options, "PREDICTOR", "3");
  if (grid.width >= 512 && grid.height >= 512) options = CSLSetNameValue(options, "TILED", "YES");
  CPLErrorReset();
  std::unique_ptr<GDALDataset> ds(
      driver->Create(out.temp().c_str(), grid.width, grid.height, 1, GDT_Float32, options));
  CSLDestroy(options);
  if (!ds)
    throw ioError("cannot create the GeoTIFF" + lastGdalError(), fileLocation(path),
                  "check the folder exists and is writable");
  auto fail = [&](const std::string& what) {
    const std::string gdalError = lastGdalError();
    ds.reset();  // closes the temp file; `out` removes it
    throw ioError(what + gdalError, fileLocation(path));
  };
  auto gt = grid.geotransform;
  if (ds->SetGeoTransform(gt.data()) != CE_None) fail("cannot write the geotransform");
  if (!grid.crs.empty()) {
    OGRSpatialReference srs;
    if (srs.SetFromUserInput(grid.crs.c_str()) != OGRERR_NONE)
      fail("unknown CRS '" + grid.crs + "'");
    if (ds->SetSpatialRef(&srs) != CE_None) fail("cannot write the CRS");
  }
  auto* band = ds->GetRasterBand(1);
  band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, const_cast<float*>(grid.z.data()),
                     grid.width, grid.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
    fail("cannot write the cells");
  }
  CPLErrorReset();
  ds->FlushCache(true);
  if (CPLGetLastErrorType() >= CE_Failure) fail("cannot finish the GeoTIFF");
  CPLErrorReset();
  ds.reset();  // closes the file
  if (CPLGetLastErrorType() >= CE_Failure)
    throw ioError("cannot finish the GeoTIFF" + lastGdalError(), fileLocation(path));
  out.commit();
}

void writeExr(const HeightGrid& grid, const std::filesystem::path& path) {
  checkGrid(grid, path);
  AtomicPath out(path);
  try {
    Imf::Header header(grid.width, grid.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    const auto& g = grid.geotransform;
    header.insert("geoTransform",
                  Imf::M33dAttribute(Imath::M33d(g[1], g[2], g[0], g[4], g[5], g[3], 0, 0, 1)));
    if (!grid.crs.empty()) header.insert("crs", Imf::StringAttribute(grid.crs));
    Imf::OutputFile file(out.temp().c_str(), header);
    Imf::FrameBuffer frame;
    frame.insert("Z",
                 Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(grid.z.data())),
                            sizeof(float), sizeof(float) * static_cast<std::size_t>(grid.width)));
    file.setFrameBuffer(frame);
    file.writePixels(grid.height);
  } catch (const std::exception& e) {
    throw ioError(std::string("cannot write the EXR heightmap (OpenEXR: ") + e.what() + ")",
                  fileLocation(path), "check the folder exists and is writable");
  }
  out.commit();
}

}  // namespace tinsmith::ingest
