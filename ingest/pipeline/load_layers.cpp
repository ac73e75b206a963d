#include "ingest/pipeline/load_layers.hpp"

#include <chrono>

#include "ingest/filters/reproject.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "ingest/readers/synthetic_reader.hpp"

namespace tinsmith::ingest {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<IngestedLayer> readLayers(const ProjectConfig& config, const Progress* progress) {
  std::vector<IngestedLayer> layers;
  layers.reserve(config.layers.size());
  for (const auto& layerConfig : config.layers) {
    layers.push_back(readLayer(layerConfig, progress));
    // Generated data has no CRS of its own: without a `crs` key it is made
    // in the project CRS.
    auto& layer = layers.back();
    if (layer.sourceCrs.empty() && isSyntheticSpec(layerConfig.path.string())) {
      layer.sourceCrs = layer.crs = config.crs;
    }
  }
  return layers;
}

void reprojectLayers(std::vector<IngestedLayer>& layers, const std::string& crs,
                     const Progress* progress) {
  for (auto& layer : layers) reprojectLayer(layer, crs, progress);
}

IngestResult loadLayers(const ProjectConfig& config, const Progress* progress) {
  IngestResult result;
  result.crs = config.crs;
  auto start = std::chrono::steady_clock::now();
  result.layers = readLayers(config, progress);
  result.timings.push_back({"readers", secondsSince(start)});
  for (const auto& layer : result.layers) {
    LayerSummary s;
    s.name = layer.config.name;
    s.kind = layer.config.kind;
    s.sourceCrs = layer.sourceCrs;
    s.featuresRead = layer.features.size();
    s.pointsRead = layer.points.size();
    s.verticesRead = layer.vertexCount() - layer.points.size();
    s.nullGeometriesSkipped = layer.nullGeometriesSkipped;
    s.hasZ = layer.hasZ;
    result.summaries.push_back(s);
  }

  start = std::chrono::steady_clock::now();
  reprojectLayers(result.layers, config.crs, progress);
  result.timings.push_back({"filters.reproject", secondsSince(start)});

  start = std::chrono::steady_clock::now();
  CleanOptions options;
  options.tolerance = config.tin.snapTolerance;
  options.strict = config.tin.strict;
  result.cleaning = cleanLayers(result.layers, options, progress);
  result.timings.push_back({"filters.clean", secondsSince(start)});
  for (std::size_t i = 0; i < result.layers.size(); ++i) {
    auto& s = result.summaries[i];
    const auto& layer = result.layers[i];
    s.featuresKept = layer.features.size();
    s.pointsKept = layer.points.size();
    s.verticesKept = layer.vertexCount() - layer.points.size();
  }
  return result;
}

}  // namespace tinsmith::ingest
