#include "ingest/build/tin_builder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/mesh/validate.hpp"
#include "core/surface/surface.hpp"
#include "ingest/base/memory.hpp"
#include "ingest/build/flat_triangles.hpp"
#include "ingest/build/line_profile.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"

namespace tinsmith::ingest {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A lake shore ring for point-in-polygon tests (even-odd, in x, y; floating
// point is enough here: this only decides which input is dropped, it never
// feeds the triangulation's predicates).
struct Ring {
  std::vector<Point2> pts;
  double minX = 0, minY = 0, maxX = 0, maxY = 0;
  explicit Ring(const std::vector<Point3>& v) {
    for (const auto& p : v) pts.push_back(p.xy());
    if (pts.size() > 1 && pts.front() == pts.back()) pts.pop_back();
    if (pts.empty()) return;
    minX = maxX = pts[0].x;
    minY = maxY = pts[0].y;
    for (const auto& p : pts) {
      minX = std::min(minX, p.x);
      maxX = std::max(maxX, p.x);
      minY = std::min(minY, p.y);
      maxY = std::max(maxY, p.y);
    }
  }
  [[nodiscard]] bool contains(double x, double y) const {
    if (pts.size() < 3 || x < minX || x > maxX || y < minY || y > maxY) return false;
    bool in = false;
    for (std::size_t i = 0, j = pts.size() - 1; i < pts.size(); j = i++) {
      const Point2& a = pts[i];
      const Point2& b = pts[j];
      if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) in = !in;
    }
    return in;
  }
};

bool insideAny(const std::vector<Ring>& rings, const Point3& p) {
  for (const auto& r : rings)
    if (r.contains(p.x, p.y)) return true;
  return false;
}

// The parts of a line outside every lake: cut at the last vertex outside.
std::vector<std::vector<Point3>> clipOutside(const std::vector<Point3>& line, bool closed,
                                             const std::vector<Ring>& lakes, std::size_t& dropped) {
  std::vector<char> in(line.size());
  bool any = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    in[i] = insideAny(lakes, line[i]) ? 1 : 0;
    if (in[i]) {
      any = true;
      ++dropped;
    }
  }
  if (!any) return {line};
  std::vector<std::vector<Point3>> pieces;
  std::size_t start = 0;
  if (closed) {  // start the walk at an inside vertex so no piece wraps around
    while (!in[start]) ++start;
  }
  std::vector<Point3> piece;
  for (std::size_t k = 0; k < line.size(); ++k) {
    const std::size_t i = (start + k) % line.size();
    if (in[i]) {
      if (!piece.empty()) pieces.push_back(std::move(piece));
      piece.clear();
    } else {
      piece.push_back(line[i]);
    }
  }
  if (!piece.empty()) pieces.push_back(std::move(piece));
  return pieces;
}

struct PendingLine {
  FeatureId feature;
  FeatureKind kind;
  std::vector<Point3> vertices;
  bool closed;
  bool drape;  ///< 2D: z comes from the base surface
};

}  // namespace

BuildValidation defaultBuildValidation() {
#ifdef NDEBUG
  return BuildValidation::Structural;
#else
  return BuildValidation::Full;
#endif
}

bool takesLines(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::Contour:
    case FeatureKind::Road:
    case FeatureKind::River:
    case FeatureKind::Lake:
    case FeatureKind::Boundary:
    case FeatureKind::Hole:
    case FeatureKind::BreakLine:
      return true;
    default:
      return false;
  }
}

namespace {

// The whole build. The result goes to `consume` (the CDT's mesh) when given,
// else into `out` (a TinData copy).
BuildReport build(std::vector<BuildLayer> layers, const BuildOptions& options,
                  const Progress* progress, const std::function<void(const Mesh&)>* consume,
                  TinData* out) {
  const auto start = Clock::now();
  BuildReport report;
  report.crs = options.crs;
  report.flatRepair = options.flatTriangleRepair;
  auto stageStart = Clock::now();
  auto endStage = [&](const char* name) {
    report.times.push_back({name, secondsSince(stageStart)});
    stageStart = Clock::now();
  };
  auto tick = [&](std::string_view detail, std::uint64_t done, std::uint64_t total) {
    reportProgress(progress, "builders.tin", detail, done, total);
  };
  constexpr std::uint64_t kSteps = 7;
  tick("preparing", 0, kSteps);

  // Lakes first: their shores decide which input is dropped.
  std::vector<Ring> lakeRings;
  for (const auto& layer : layers) {
    BuildReport::Layer& entry = report.layers.emplace_back();
    entry.name = layer.name;
    entry.kind = layer.kindName;
    entry.source = layer.source;
    entry.points = layer.points.size();
    entry.features = layer.lines.size() + (layer.points.empty() ? 0 : 1);
    for (const auto& l : layer.lines) entry.vertices += l.vertices.size();
    if (layer.kind == FeatureKind::Lake)
      for (const auto& l : layer.lines) lakeRings.emplace_back(l.vertices);
  }

  Cdt cdt({.snapTolerance = options.snapTolerance, .crs = options.crs, .threads = options.threads});
  std::vector<PendingLine> later;  // 2D lines to drape, or everything after the base
  std::size_t droppedInLakes = 0;

  for (auto& layer : layers) {
    if (!layer.points.empty()) {
      const FeatureKind pk = takesLines(layer.kind) ? FeatureKind::Other : layer.kind;
      const FeatureId f = cdt.addFeature(pk, layer.source);
      if (lakeRings.empty()) {
        cdt.insertPoints(layer.points, f);
        report.inputPoints += layer.points.size();
      } else {
        std::vector<Point3> kept;
        kept.reserve(layer.points.size());
        for (const auto& p : layer.points) {
          if (insideAny(lakeRings, p))
            ++droppedInLakes;
          else
            kept.push_back(p);
        }
        cdt.insertPoints(kept, f);
        report.inputPoints += kept.size();
      }
    }
    if (!takesLines(layer.kind) && !layer.lines.empty()) {
      // Lines of no particular role (plain break lines): 3D constraints as given.
      for (const auto& line : layer.lines) {
        const FeatureId f = cdt.addFeature(layer.kind, line.source);
        cdt.insertConstraint(line.vertices, f, line.closed);
        report.inputLineVertices += line.vertices.size();
      }
      continue;
    }
    for (auto& line : layer.lines) {
      if (layer.kind == FeatureKind::Contour && !line.hasZ)
        throw inputError("a contour has no z", {line.source, {}, {}, {}},
                         "give the contour layer a 'z' attribute or 'z_value'");
      const FeatureId f = cdt.addFeature(layer.kind, line.source);
      if (layer.kind == FeatureKind::Contour && lakeRings.empty()) {
        report.inputLineVertices += line.vertices.size();
        cdt.insertConstraint(line.vertices, f, line.closed);
        continue;
      }
      if (layer.kind == FeatureKind::Contour) {
        for (auto& piece : clipOutside(line.vertices, line.closed, lakeRings, droppedInLakes)) {
          const bool closed = line.closed && piece.size() == line.vertices.size();
          report.inputLineVertices += piece.size();
          cdt.insertConstraint(piece, f, closed);
        }
        continue;
      }
      if (layer.kind == FeatureKind::River && !lakeRings.empty()) {
        auto pieces = clipOutside(line.vertices, line.closed, lakeRings, droppedInLakes);
        const bool whole = pieces.size() == 1 && pieces[0].size() == line.vertices.size();
        for (auto& piece : pieces)
          later.push_back({f, layer.kind, std::move(piece), whole && line.closed, !line.hasZ});
      } else {
        later.push_back({f, layer.kind, std::move(line.vertices), line.closed, !line.hasZ});
      }
    }
  }
  if (droppedInLakes) report.cleaning.push_back({"input vertices inside lakes dropped", droppedInLakes});
  layers.clear();  // the Cdt and `later` hold everything from here on
  layers.shrink_to_fit();
  releaseFreeMemory();  // the layers' and the cleaning's heap, before the CDT grows
  endStage("prepare");

  // 1. The base surface, when anything must be draped on it.
  std::optional<Surface> surface;
  if (std::any_of(later.begin(), later.end(), [](const PendingLine& l) { return l.drape; })) {
    tick("base surface", 1, kSteps);

    if (report.inputPoints + report.inputLineVertices < 3)
      throw inputError("2D break lines need a surface to drape on, but there are fewer than 3 points and contour vertices",
                       {}, "add points or contours, or give the break lines z");
    cdt.finalize();
    surface.emplace(cdt.mesh());
    endStage("triangulate.base");
  }
  ZLookup lookup = [&surface](double x, double y) -> std::optional<double> {
    return surface ? surface->z({x, y}) : std::nullopt;
  };

  // 2–4. Lakes, rivers, roads, domain rings.
  tick("break lines", 2, kSteps);
  std::vector<std::vector<Point3>*> rivers;  // made to descend, for their confluences
  std::vector<bool> riverReversed;
  for (std::size_t i = 0; i < later.size(); ++i) {
    PendingLine& line = later[i];
    const std::string& source = cdt.features()[line.feature].source;
    const bool drapeIt = line.drape;
    switch (line.kind) {
      case FeatureKind::Lake: {
        std::vector<Point3> shore = line.vertices;
        if (drapeIt) {
          densify(shore, options.drapeSpacing);
          report.drapedOutside += drape(shore, lookup, source).outside;
        }
        if (shore.empty()) break;
        double level = std::numeric_limits<double>::infinity();
        for (const auto& p : shore) level = std::min(level, p.z);
        for (auto& p : line.vertices) p.z = level;
        line.closed = true;
        report.lakes.push_back({source, level, line.vertices.size()});
        break;
      }
      case FeatureKind::River: {
        if (drapeIt) {
          densify(line.vertices, options.drapeSpacing);
          report.drapedOutside += drape(line.vertices, lookup, source).outside;
          ++report.riversDraped;
        } else {
          ++report.riversChecked;
        }
        if (options.riverDescent) {
          const auto d = enforceDescent(line.vertices);
          rivers.push_back(&line.vertices);
          riverReversed.push_back(d.reversed);
          report.riversReversed += d.reversed ? 1 : 0;
          report.riverVerticesAdjusted += d.adjusted;
          report.riverMaxAdjustment = std::max(report.riverMaxAdjustment, d.maxAdjustment);
          if (d.maxAdjustment >= BuildReport::kRiverChangeToReport)
            report.riverLargestChanges.push_back({d.maxAt, source, d.maxTo, d.maxFrom});
        }
        break;
      }
      case FeatureKind::Road: {
        if (drapeIt) {
          densify(line.vertices, options.drapeSpacing);
          report.drapedOutside += drape(line.vertices, lookup, source).outside;
          const auto s = smoothAlongLength(line.vertices, options.roadWindow, options.roadSpikeThreshold);
          ++report.roadsDraped;
          report.roadSpikesRemoved += s.spikesRemoved;
          report.roadMaxChange = std::max(report.roadMaxChange, s.maxChange);
        }
        break;
      }
      default:  // boundary, hole: take z from the surface
        if (drapeIt) report.drapedOutside += drape(line.vertices, lookup, source).outside;
        break;
    }
  }
  // Where rivers meet end to end, one vertex: every river keeps descending
  // through it.
  report.riverVerticesAdjusted += reconcileConfluences(rivers, riverReversed);
  std::stable_sort(report.riverLargestChanges.begin(), report.riverLargestChanges.end(),
                   [](const auto& a, const auto& b) {
                     return std::abs(a.zOther - a.zKept) > std::abs(b.zOther - b.zKept);
                   });
  surface.reset();  // free the copy before the big triangulation
  for (auto& line : later) {
    report.inputLineVertices += line.vertices.size();
    if (line.kind == FeatureKind::Boundary)
      cdt.addBoundary(line.vertices, line.feature);
    else if (line.kind == FeatureKind::Hole)
      cdt.addHole(line.vertices, line.feature);
    else
      cdt.insertConstraint(line.vertices, line.feature, line.closed);
  }
  later.clear();
  later.shrink_to_fit();
  endStage("break lines");

  // 5. The triangulation.
  tick("triangulation", 3, kSteps);
  cdt.finalize();
  (void)cdt.mesh();  // the output mesh is built on first use: part of the triangulation's time
  endStage("triangulate");

  const auto& features = cdt.features();
  auto kindOf = [&](FeatureId f) {
    return f < features.size() ? features[f].kind : FeatureKind::Other;
  };
  auto nameOf = [&](FeatureId f) {
    return f < features.size() ? features[f].source : std::string("(no feature)");
  };
  {
    const CdtReport& cr = cdt.report();
    report.mergedPoints = cr.merges.size();
    for (const auto& m : cr.merges)
      if (m.keptZ != m.droppedZ && report.mergeSamples.size() < 10)
        report.mergeSamples.push_back(
            {m.at, nameOf(m.keptFeature) + " kept over " + nameOf(m.droppedFeature), m.keptZ, m.droppedZ});
    report.crossings = cr.intersections.size();
    for (const auto& x : cr.intersections) {
      const FeatureKind a = kindOf(x.existing), b = kindOf(x.inserted);
      if ((a == FeatureKind::Road && b == FeatureKind::River) ||
          (a == FeatureKind::River && b == FeatureKind::Road)) {
        const bool riverFirst = a == FeatureKind::River;
        report.bridgeCandidates.push_back(
            {x.at.xy(), nameOf(riverFirst ? x.inserted : x.existing) + " × " +
                            nameOf(riverFirst ? x.existing : x.inserted),
             x.at.z, riverFirst ? x.zInserted : x.zExisting});
      }
      if (a == FeatureKind::Contour && b == FeatureKind::Contour &&
          (x.existing == x.inserted || x.zExisting != x.zInserted)) {
        std::ostringstream msg;
        msg.precision(10);
        if (x.existing == x.inserted)
          msg << nameOf(x.existing) << " crosses itself";
        else
          msg << nameOf(x.existing) << " (z " << x.zExisting << ") crosses " << nameOf(x.inserted)
              << " (z " << x.zInserted << ")";
        msg << " at " << x.at.x << ", " << x.at.y;
        report.dataErrors.push_back(msg.str());
      }
    }
    for (const auto& d : cr.dropped) {
      if (d.what == CdtReport::Dropped::What::ZeroLengthSegment)
        ++report.droppedSegments;
      else
        ++report.droppedOutside;
    }
  }
  if (options.strict && !report.dataErrors.empty()) {
    std::string list;
    for (std::size_t i = 0; i < report.dataErrors.size() && i < 5; ++i) list += "\n  " + report.dataErrors[i];
    throw inputError(std::to_string(report.dataErrors.size()) + " contour crossing(s):" + list, {},
                     "fix the contours, or run without --strict to keep going and have them reported");
  }

  // 6. Flat triangles, found and repaired on the CDT's own mesh (no TinData
  // copy of the whole TIN until the end).
  tick("flat triangles", 4, kSteps);
  if (!options.flatTriangleRepair || options.flatPasses <= 0) {
    report.flatBefore = countFlatTriangles(cdt.mesh());
    report.flatAfter = report.flatBefore;
  } else {
    // Each analysis also counts: the one after a pass is the next pass's.
    const double minSpacing = std::max(10 * options.snapTolerance, 1e-9);
    FlatTriangleAnalysis a = analyseFlatTriangles(cdt.mesh(), minSpacing);
    report.flatBefore = a.flatTriangles.size();
    report.flatAfter = report.flatBefore;
    report.flatRegions = a.regions;
    report.flatClosedRegions = a.closedRegions;
    for (int pass = 0; pass < options.flatPasses && !a.proposals.empty(); ++pass) {
      cdt.insertPoints(a.proposals);
      report.flatVerticesAdded += a.proposals.size();
      a = FlatTriangleAnalysis{};  // release it before the triangulation grows
      cdt.finalize();
      ++report.flatIterations;
      std::size_t now = 0;
      if (pass + 1 < options.flatPasses) {
        a = analyseFlatTriangles(cdt.mesh(), minSpacing);
        now = a.flatTriangles.size();
      } else {
        now = countFlatTriangles(cdt.mesh());
      }
      const bool progressMade = now < report.flatAfter;
      report.flatAfter = now;
      if (now == 0 || !progressMade) break;
    }
  }
  endStage("flat-repair");

  // 7. Validation.
  tick("validation", 5, kSteps);
  {
    ValidationReport v;
    switch (options.validation) {
      case BuildValidation::Off:
        report.validation = "off";
        break;
      case BuildValidation::Structural:
        report.validation = "structural";
        v = validate(cdt.mesh(), {.checkDelaunay = false, .threads = options.threads});
        break;
      case BuildValidation::Full:
        report.validation = "full";
        v = cdt.validate({.threads = options.threads});
        break;
    }
    report.valid = v.ok && options.validation != BuildValidation::Off;
    report.validationProblems = v.problems;
    if (!v.ok)
      throw internalError("the TIN built from this input fails validation: " + v.summary());
  }
  endStage("validate");

  // The result, made once: either the mesh goes to the consumer (timed as
  // the stage "write": it writes the .tin), or a TinData copy of it — the
  // last big allocation while the Cdt lives (the Cdt is freed on return).
  releaseFreeMemory();
  static_cast<TinCounts&>(report) = countTin(cdt.mesh());
  if (out) *out = cdt.toTinData();
  if (consume) {
    tick("writing", 6, kSteps);
    (*consume)(cdt.mesh());
    endStage("write");
  }
  report.totalSeconds = secondsSince(start);
  tick("done", kSteps, kSteps);
  return report;
}

}  // namespace

BuildResult buildTin(std::vector<BuildLayer> layers, const BuildOptions& options,
                     const Progress* progress) {
  BuildResult result;
  result.report = build(std::move(layers), options, progress, nullptr, &result.tin);
  return result;
}

BuildReport buildTinInto(std::vector<BuildLayer> layers, const BuildOptions& options,
                         const std::function<void(const Mesh&)>& consume,
                         const Progress* progress) {
  return build(std::move(layers), options, progress, &consume, nullptr);
}

}  // namespace tinsmith::ingest
