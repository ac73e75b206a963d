#include "ingest/build/build_report.hpp"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

namespace tinsmith::ingest {

namespace {

nlohmann::ordered_json eventJson(const BuildReport::Event& e) {
  return {{"x", e.at.x}, {"y", e.at.y}, {"what", e.what}, {"z_kept", e.zKept}, {"z_other", e.zOther}};
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

std::string BuildReport::toJson() const {
  using J = nlohmann::ordered_json;
  J j;
  j["crs"] = crs;
  j["layers"] = J::array();
  for (const auto& l : layers)
    j["layers"].push_back({{"name", l.name},
                           {"kind", l.kind},
                           {"source", l.source},
                           {"features", l.features},
                           {"points", l.points},
                           {"vertices", l.vertices},
                           {"features_read", l.readFeatures},
                           {"vertices_read", l.readVertices},
                           {"source_crs", l.sourceCrs}});
  J cleanJ = J::object();
  for (const auto& [name, count] : cleaning) cleanJ[name] = count;
  j["cleaning"] = cleanJ;
  j["data_errors"] = dataErrors;
  J tri;
  tri["input_points"] = inputPoints;
  tri["input_line_vertices"] = inputLineVertices;
  tri["merged_points"] = mergedPoints;
  tri["crossings_split"] = crossings;
  tri["zero_length_segments_dropped"] = droppedSegments;
  tri["dropped_outside_boundary"] = droppedOutside;
  tri["bridge_candidates"] = J::array();
  for (const auto& e : bridgeCandidates) tri["bridge_candidates"].push_back(eventJson(e));
  tri["merge_samples"] = J::array();
  for (const auto& e : mergeSamples) tri["merge_samples"].push_back(eventJson(e));
  j["triangulation"] = tri;
  j["rivers"] = {{"draped", riversDraped},
                 {"checked", riversChecked},
                 {"reversed", riversReversed},
                 {"vertices_adjusted", riverVerticesAdjusted},
                 {"max_adjustment_m", riverMaxAdjustment},
                 {"largest_changes", J::array()}};
  for (const auto& e : riverLargestChanges) j["rivers"]["largest_changes"].push_back(eventJson(e));
  j["roads"] = {{"draped", roadsDraped},
                {"spikes_removed", roadSpikesRemoved},
                {"max_change_m", roadMaxChange}};
  j["lakes"] = J::array();
  for (const auto& l : lakes)
    j["lakes"].push_back({{"source", l.source}, {"level_m", l.level}, {"vertices", l.vertices}});
  j["draped_vertices_off_surface"] = drapedOutside;
  j["flat_triangles"] = {{"repair", flatRepair},
                         {"before", flatBefore},
                         {"after", flatAfter},
                         {"vertices_added", flatVerticesAdded},
                         {"iterations", flatIterations},
                         {"regions", flatRegions},
                         {"closed_regions", flatClosedRegions}};
  j["result"] = {{"vertices", vertices},
                 {"triangles", triangles},
                 {"constrained_edges", constrainedEdges},
                 {"features", features},
                 {"extent", {minX, minY, maxX, maxY}},
                 {"z_range", {minZ, maxZ}},
                 {"valid", valid},
                 {"validation", validation},
                 {"validation_problems", validationProblems}};
  J timesJ = J::array();
  for (const auto& t : times) timesJ.push_back({{"stage", t.stage}, {"seconds", t.seconds}});
  j["times"] = timesJ;
  j["total_seconds"] = totalSeconds;
  return j.dump(2) + "\n";
}

std::string BuildReport::summary() const {
  std::ostringstream s;
  s << "TIN build summary" << (crs.empty() ? "" : " (" + crs + ")") << "\n";
  if (!layers.empty()) {
    s << "  layers:\n";
    for (const auto& l : layers) {
      s << "    " << l.name << " [" << l.kind << "]: " << l.features << " features";
      if (l.points) s << ", " << l.points << " points";
      if (l.vertices) s << ", " << l.vertices << " line vertices";
      if (l.readVertices) s << " (read " << l.readFeatures << " features, " << l.readVertices << " vertices)";
      s << "\n";
    }
  }
  if (!cleaning.empty()) {
    s << "  cleaning:";
    for (const auto& [name, count] : cleaning) s << " " << name << " " << count << ";";
    s << "\n";
  }
  if (!dataErrors.empty()) {
    s << "  data errors: " << dataErrors.size() << " (all in the JSON report)\n";
    for (std::size_t i = 0; i < dataErrors.size() && i < 5; ++i) s << "    " << dataErrors[i] << "\n";
    if (dataErrors.size() > 5) s << "    … " << dataErrors.size() - 5 << " more\n";
  }
  s << "  input: " << inputPoints << " points, " << inputLineVertices << " break-line vertices\n";
  s << "  merged points: " << mergedPoints << ", crossings split: " << crossings
    << ", zero-length segments dropped: " << droppedSegments;
  if (droppedOutside) s << ", dropped outside the boundary: " << droppedOutside;
  s << "\n";
  if (!bridgeCandidates.empty()) {
    s << "  bridge candidates (road × river): " << bridgeCandidates.size() << "\n";
    for (std::size_t i = 0; i < bridgeCandidates.size() && i < 5; ++i)
      s << "    at " << fixed(bridgeCandidates[i].at.x, 2) << ", " << fixed(bridgeCandidates[i].at.y, 2)
        << ": " << bridgeCandidates[i].what << " (TIN z " << fixed(bridgeCandidates[i].zKept, 2)
        << " m from the river; the road there was " << fixed(bridgeCandidates[i].zOther, 2) << " m)\n";
  }
  if (riversDraped || riversChecked)
    s << "  rivers (pieces outside lakes): " << riversDraped << " draped, " << riversChecked << " 3D checked, "
      << riversReversed << " digitised upstream, " << riverVerticesAdjusted
      << " vertices lowered/raised to descend (max " << fixed(riverMaxAdjustment, 2) << " m)\n";
  for (std::size_t i = 0; i < riverLargestChanges.size() && i < 5; ++i) {
    const Event& e = riverLargestChanges[i];
    s << "    at " << fixed(e.at.x, 2) << ", " << fixed(e.at.y, 2) << ": " << e.what << " "
      << (e.zKept < e.zOther ? "lowered" : "raised") << " from " << fixed(e.zOther, 2) << " to "
      << fixed(e.zKept, 2) << " m";
    if (e.zOther - e.zKept >= 3.0)
      s << " — its banks keep their height, so the TIN has a pit there; a reservoir, weir or "
           "culvert the layers do not hold? (add it as a lake or check the river's direction)";
    s << "\n";
  }
  if (roadsDraped)
    s << "  roads: " << roadsDraped << " draped and smoothed, " << roadSpikesRemoved
      << " spikes removed (max change " << fixed(roadMaxChange, 2) << " m)\n";
  for (const auto& l : lakes)
    s << "  lake " << l.source << ": flat at " << fixed(l.level, 2) << " m (" << l.vertices
      << " shore vertices)\n";
  if (drapedOutside) s << "  draped vertices off the surface (z interpolated along the line): " << drapedOutside << "\n";
  if (flatRepair)
    s << "  flat triangles: " << flatBefore << " before, " << flatAfter << " after ("
      << flatVerticesAdded << " vertices added in " << flatIterations << " passes, "
      << flatRegions << " regions, " << flatClosedRegions << " summits/pits)\n";
  else
    s << "  flat triangles: " << flatBefore << " (repair off)\n";
  s << "  result: " << vertices << " vertices, " << triangles << " triangles, " << constrainedEdges
    << " constrained edges, " << features << " features\n";
  s << "  extent: x " << fixed(minX, 3) << " .. " << fixed(maxX, 3) << ", y " << fixed(minY, 3)
    << " .. " << fixed(maxY, 3) << "; z " << fixed(minZ, 3) << " .. " << fixed(maxZ, 3) << " m\n";
  if (validation == "off" || validation.empty())
    s << "  validation: off\n";
  else
    s << "  validation: " << (valid ? "ok" : "FAILED") << " (" << validation
      << (validation == "structural" ? "; --validate runs the full check" : "") << ")\n";
  for (const auto& p : validationProblems) s << "    " << p << "\n";
  s << "  time:";
  for (const auto& t : times) s << " " << t.stage << " " << fixed(t.seconds, 3) << " s;";
  s << " total " << fixed(totalSeconds, 3) << " s\n";
  return s.str();
}

}  // namespace tinsmith::ingest
