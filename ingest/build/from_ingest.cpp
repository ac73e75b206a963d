#include "ingest/build/from_ingest.hpp"

#include <cmath>

namespace tinsmith::ingest {

std::vector<BuildLayer> toBuildLayers(std::vector<IngestedLayer> layers) {
  std::vector<BuildLayer> out;
  out.reserve(layers.size() + 1);
  BuildLayer innerBoundaryRings;
  for (auto& layer : layers) {
    BuildLayer b;
    b.name = layer.config.name;
    b.kindName = std::string(toString(layer.config.kind));
    b.kind = layer.kind;
    b.source = layerLocation(layer.config).str();
    b.points = std::move(layer.points);
    layer.points.shrink_to_fit();
    for (auto& f : layer.features) {
      BuildLine line;
      line.vertices = std::move(f.vertices);
      line.closed = f.closed;
      line.hasZ = f.hasZ;
      line.source = layerLocation(layer.config, f.fid).str();
      if (f.part > 0) line.source += ", part " + std::to_string(f.part);
      if (f.ring > 0) line.source += ", ring " + std::to_string(f.ring);
      if (layer.kind == FeatureKind::Boundary && f.ring > 0) {
        innerBoundaryRings.lines.push_back(std::move(line));
        continue;
      }
      b.lines.push_back(std::move(line));
    }
    layer.features.clear();
    layer.features.shrink_to_fit();
    out.push_back(std::move(b));
  }
  if (!innerBoundaryRings.lines.empty()) {
    innerBoundaryRings.name = "boundary holes";
    innerBoundaryRings.kindName = "hole";
    innerBoundaryRings.kind = FeatureKind::Hole;
    innerBoundaryRings.source = "interior rings of the boundary";
    out.push_back(std::move(innerBoundaryRings));
  }
  return out;
}

void addIngestReport(BuildReport& report, const IngestResult& ingest) {
  const CleaningReport& c = ingest.cleaning;
  report.cleaning.insert(report.cleaning.begin(),
                         {{"vertices snapped", c.verticesSnapped},
                          {"repeated vertices dropped", c.repeatedVerticesDropped},
                          {"degenerate features dropped", c.degenerateFeaturesDropped},
                          {"points on break-line vertices dropped", c.pointsOnBreakLineVertices},
                          {"duplicate points merged", c.duplicatePointsMerged},
                          {"duplicate points with conflicting z", c.duplicatePointZConflicts},
                          {"contour self-crossings", c.contourSelfCrossings},
                          {"contour crossings", c.contourCrossings},
                          {"segments cut out", c.segmentsCutOut}});
  std::vector<std::string> errors;
  for (const auto& x : c.crossings) errors.push_back(describe(x));
  report.dataErrors.insert(report.dataErrors.begin(), errors.begin(), errors.end());
  // The layer table: counts as read (the builder's own entries count what it got).
  for (std::size_t i = 0; i < ingest.summaries.size() && i < report.layers.size(); ++i) {
    const auto& s = ingest.summaries[i];
    auto& l = report.layers[i];
    l.readFeatures = s.featuresRead;
    l.readVertices = s.verticesRead + s.pointsRead;
    l.sourceCrs = s.sourceCrs;
  }
  std::vector<BuildReport::StageTime> times;
  for (const auto& t : ingest.timings) times.push_back({t.stage, t.seconds});
  report.times.insert(report.times.begin(), times.begin(), times.end());
  double ingestSeconds = 0;
  for (const auto& t : ingest.timings) ingestSeconds += t.seconds;
  report.totalSeconds += ingestSeconds;
}

BuildOptions buildOptionsFrom(const ProjectConfig& config) {
  BuildOptions o;
  o.crs = config.crs;
  o.snapTolerance = config.tin.snapTolerance;
  o.flatTriangleRepair = config.tin.flatTriangleRepair;
  o.riverDescent = config.tin.riverDescent;
  o.strict = config.tin.strict;
  return o;
}

BuildReport buildTinFromConfig(const ProjectConfig& config, const BuildOptions& options,
                               const std::function<void(const Mesh&)>& consume,
                               const Progress* progress) {
  IngestResult ingested = loadLayers(config, progress);
  BuildReport report =
      buildTinInto(toBuildLayers(std::move(ingested.layers)), options, consume, progress);
  addIngestReport(report, ingested);
  return report;
}

}  // namespace tinsmith::ingest
