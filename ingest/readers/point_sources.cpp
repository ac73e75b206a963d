#include "ingest/readers/point_sources.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/base/error.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "ingest/readers/raster_reader.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "ingest/readers/text_points.hpp"

namespace tinsmith::ingest {

bool isRasterPointFile(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* raster :
       {".tif", ".tiff", ".vrt", ".img", ".asc", ".hgt", ".dem", ".bil", ".exr"})
    if (ext == raster) return true;
  return false;
}

std::vector<Point3> readNonTextPoints(const std::string& file) {
  if (isRasterPointFile(file)) return gridToPoints(readHeightGrid(file));
  if (isSyntheticSpec(file))
    return readSyntheticLayer(commandLineLayer(file, file, LayerKind::Points)).points;
  const auto name = std::filesystem::path(file).filename().string();
  auto read = readOgrLayer(commandLineLayer(name, file, LayerKind::Points));
  if (!read.hasZ)
    throw inputError("the points have no z", fileLocation(file),
                     "give 3D points, or use a config with a 'z' attribute");
  return std::move(read.points);
}

std::vector<PointSource> pointSources(const std::vector<std::string>& files, unsigned threads) {
  std::vector<PointSource> sources;
  for (const auto& file : files) {
    if (isTextPointFile(file)) {
      sources.push_back({file, [file, threads](const auto& sink) {
                           TextPointOptions text;
                           text.threads = threads;
                           readTextPointsInChunks(file, text, std::size_t{8} << 20, sink);
                         }});
    } else if (isRasterPointFile(file)) {
      sources.push_back(
          {file, [file](const auto& sink) {
             std::function<void(const HeightGrid&, int, std::span<const float>)> strip =
                 [&sink](const HeightGrid& frame, int first, std::span<const float> z) {
                   sink(stripToPoints(frame, first, z));
                 };
             readHeightGridInStrips(file, {}, std::size_t{4} << 20, strip);
           }});
    } else {
      sources.push_back({file, [file](const auto& sink) { sink(readNonTextPoints(file)); }});
    }
  }
  return sources;
}

}  // namespace tinsmith::ingest
