#include "ingest/readers/point_sources.hpp"

#include <filesystem>

#include "core/base/error.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "ingest/readers/text_points.hpp"

namespace tinsmith::ingest {

std::vector<Point3> readNonTextPoints(const std::string& file) {
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
    } else {
      sources.push_back({file, [file](const auto& sink) { sink(readNonTextPoints(file)); }});
    }
  }
  return sources;
}

}  // namespace tinsmith::ingest
