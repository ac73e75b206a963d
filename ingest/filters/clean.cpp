#include "ingest/filters/clean.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <tuple>

#include "core/base/error.hpp"
#include "core/geometry/cell_grid.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::ingest {
namespace {

constexpr std::uint32_t kNoItem = 0xffffffffu;

struct Extent {
  double minX = std::numeric_limits<double>::infinity();
  double minY = std::numeric_limits<double>::infinity();
  double maxX = -std::numeric_limits<double>::infinity();
  double maxY = -std::numeric_limits<double>::infinity();
  void add(const Point3& p) {
    minX = std::min(minX, p.x);
    minY = std::min(minY, p.y);
    maxX = std::max(maxX, p.x);
    maxY = std::max(maxY, p.y);
  }
  [[nodiscard]] bool empty() const { return !(minX <= maxX); }
  [[nodiscard]] double size() const { return empty() ? 0.0 : std::max(maxX - minX, maxY - minY); }
};

double dist2(const Point3& a, const Point3& b) {
  const double dx = a.x - b.x;
  const double dy = a.y - b.y;
  return dx * dx + dy * dy;
}

// Features (layer, index) of line and area layers, highest constraintPriority
// first, then config order.
std::vector<std::pair<std::uint32_t, std::uint32_t>> featureOrder(
    const std::vector<IngestedLayer>& layers) {
  std::vector<std::uint32_t> layerOrder(layers.size());
  std::iota(layerOrder.begin(), layerOrder.end(), 0u);
  std::stable_sort(layerOrder.begin(), layerOrder.end(), [&](std::uint32_t a, std::uint32_t b) {
    return constraintPriority(layers[a].kind) > constraintPriority(layers[b].kind);
  });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> order;
  for (const auto l : layerOrder) {
    for (std::uint32_t f = 0; f < layers[l].features.size(); ++f) order.emplace_back(l, f);
  }
  return order;
}

// Rule 1. Vertices are visited in priority order; a vertex snaps onto the
// nearest earlier, unsnapped vertex of another feature within the tolerance.
void snapVertices(std::vector<IngestedLayer>& layers, double tolerance, const Extent& extent,
                  std::size_t vertexCount, CleaningReport& report) {
  if (tolerance <= 0.0 || vertexCount == 0) return;  // exact duplicates are already identical
  const auto order = featureOrder(layers);
  std::vector<Point3*> vertex;
  std::vector<std::uint32_t> owner;
  vertex.reserve(vertexCount);
  owner.reserve(vertexCount);
  for (std::uint32_t k = 0; k < order.size(); ++k) {
    for (auto& v : layers[order[k].first].features[order[k].second].vertices) {
      vertex.push_back(&v);
      owner.push_back(k);
    }
  }
  CellGrid grid(extent.minX, extent.minY, extent.maxX, extent.maxY,
                CellGrid::cellFor(extent.maxX - extent.minX, extent.maxY - extent.minY,
                                  vertex.size(), tolerance));
  grid.build(vertex.size(), [&](std::size_t i, auto&& emit) {
    emit(grid.index(grid.cellX(vertex[i]->x), grid.cellY(vertex[i]->y)));
  });
  std::vector<char> snapped(vertex.size(), 0);
  const double tol2 = tolerance * tolerance;
  for (std::uint32_t p = 0; p < vertex.size(); ++p) {
    Point3& v = *vertex[p];
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t bestIndex = kNoItem;
    grid.forEachNear(v.x, v.y, tolerance, [&](std::uint32_t u) {
      if (u >= p || snapped[u] || owner[u] == owner[p]) return;
      const double d = dist2(*vertex[u], v);
      if (d <= tol2 && (d < best || (d == best && u < bestIndex))) {
        best = d;
        bestIndex = u;
      }
    });
    if (bestIndex == kNoItem) continue;
    snapped[p] = 1;
    const Point3& target = *vertex[bestIndex];
    if (target.x != v.x || target.y != v.y) {
      v.x = target.x;
      v.y = target.y;
      ++report.verticesSnapped;
    }
  }
}

// Rules 2 and 3.
void dropRepeatedVertices(std::vector<IngestedLayer>& layers, double tolerance,
                          CleaningReport& report) {
  const double tol2 = tolerance * tolerance;
  for (auto& layer : layers) {
    auto& features = layer.features;
    std::size_t out = 0;
    for (std::size_t i = 0; i < features.size(); ++i) {
      auto& v = features[i].vertices;
      std::size_t w = 0;
      for (std::size_t r = 0; r < v.size(); ++r) {
        if (w > 0 && dist2(v[w - 1], v[r]) <= tol2) {
          ++report.repeatedVerticesDropped;
          continue;
        }
        v[w++] = v[r];
      }
      v.resize(w);
      if (features[i].closed) {
        while (v.size() >= 2 && dist2(v.back(), v.front()) <= tol2) {
          v.pop_back();
          ++report.repeatedVerticesDropped;
        }
      }
      const std::size_t minimum = features[i].closed ? 3 : 2;
      if (v.size() < minimum) {
        ++report.degenerateFeaturesDropped;
        continue;
      }
      if (out != i) features[out] = std::move(features[i]);
      ++out;
    }
    features.resize(out);
  }
}

// Rule 4. Line vertices come first in the grid's order, then the points by
// layer priority; a point is dropped when an earlier, kept item is within the
// tolerance.
void mergePoints(std::vector<IngestedLayer>& layers, double tolerance, double zConflict,
                 const Extent& extent, CleaningReport& report) {
  std::size_t pointCount = 0;
  std::size_t lineVertices = 0;
  for (const auto& l : layers) {
    pointCount += l.points.size();
    for (const auto& f : l.features) lineVertices += f.vertices.size();
  }
  if (pointCount == 0) return;
  std::vector<std::uint32_t> layerOrder(layers.size());
  std::iota(layerOrder.begin(), layerOrder.end(), 0u);
  std::stable_sort(layerOrder.begin(), layerOrder.end(), [&](std::uint32_t a, std::uint32_t b) {
    return constraintPriority(layers[a].kind) > constraintPriority(layers[b].kind);
  });
  std::vector<Point3> position;
  position.reserve(lineVertices + pointCount);
  for (const auto& layer : layers) {
    for (const auto& f : layer.features)
      position.insert(position.end(), f.vertices.begin(), f.vertices.end());
  }
  for (const auto l : layerOrder)
    position.insert(position.end(), layers[l].points.begin(), layers[l].points.end());

  CellGrid grid(extent.minX, extent.minY, extent.maxX, extent.maxY,
                CellGrid::cellFor(extent.maxX - extent.minX, extent.maxY - extent.minY,
                                  position.size(), tolerance));
  grid.build(position.size(), [&](std::size_t i, auto&& emit) {
    emit(grid.index(grid.cellX(position[i].x), grid.cellY(position[i].y)));
  });
  std::vector<char> dropped(position.size(), 0);
  const double tol2 = tolerance * tolerance;
  auto p = static_cast<std::uint32_t>(lineVertices);
  for (const auto l : layerOrder) {
    auto& layer = layers[l];
    std::size_t w = 0;
    for (std::size_t r = 0; r < layer.points.size(); ++r, ++p) {
      const Point3& point = position[p];
      std::uint32_t match = kNoItem;
      grid.forEachNear(point.x, point.y, tolerance, [&](std::uint32_t u) {
        if (u >= p || dropped[u] || dist2(position[u], point) > tol2) return;
        match = std::min(match, u);
      });
      if (match != kNoItem) {
        dropped[p] = 1;
        if (match < lineVertices) {
          ++report.pointsOnBreakLineVertices;
        } else {
          ++report.duplicatePointsMerged;
          if (std::abs(position[match].z - point.z) > zConflict) ++report.duplicatePointZConflicts;
        }
        continue;
      }
      layer.points[w] = point;
      layer.pointIds[w] = layer.pointIds[r];
      ++w;
    }
    layer.points.resize(w);
    layer.pointIds.resize(w);
  }
}

// ---- Rule 5: contour crossings -------------------------------------------

// Whether segments ab and cd meet (cross or touch), decided with the exact
// predicates; `at` gets a meeting point (rounded where they cross properly).
bool segmentsMeet(const Point3& a, const Point3& b, const Point3& c, const Point3& d, Point2& at) {
  using geometry::SegmentIntersection;
  const auto kind = geometry::segmentIntersection(a.xy(), b.xy(), c.xy(), d.xy());
  if (kind == SegmentIntersection::None) return false;
  if (kind == SegmentIntersection::Proper) {
    at = geometry::intersectionPoint(a.xy(), b.xy(), c.xy(), d.xy());
    return true;
  }
  // Touching or overlapping: some endpoint lies on the other segment.
  for (const auto& [p, q0, q1] :
       {std::tuple{c, a, b}, std::tuple{d, a, b}, std::tuple{a, c, d}, std::tuple{b, c, d}}) {
    if (geometry::onSegment(q0.xy(), q1.xy(), p.xy())) {
      at = p.xy();
      return true;
    }
  }
  at = c.xy();
  return true;
}

struct ContourRef {
  std::uint32_t layer;
  std::uint32_t feature;
  std::uint32_t vertexCount;
  bool closed;
};

struct Segment {
  const Point3* a;  // start and end vertex
  const Point3* b;
  std::uint32_t contour;  // index into the ContourRef list
  std::uint32_t index;    // segment i joins vertices i and i+1 (mod n when closed)
};

struct Hit {
  Segment a, b;
  Point2 at;
};

void findCrossings(std::vector<IngestedLayer>& layers, const CleanOptions& options,
                   const Extent& extent, const Progress* progress, CleaningReport& report) {
  std::vector<ContourRef> contours;
  std::vector<Segment> segments;
  double totalLength = 0.0;
  for (std::uint32_t l = 0; l < layers.size(); ++l) {
    if (layers[l].kind != FeatureKind::Contour) continue;
    for (std::uint32_t f = 0; f < layers[l].features.size(); ++f) {
      const auto& feature = layers[l].features[f];
      const auto& v = feature.vertices;
      const auto n = static_cast<std::uint32_t>(feature.closed ? v.size() : v.size() - 1);
      for (std::uint32_t i = 0; i < n; ++i) {
        const Point3* a = &v[i];
        const Point3* b = &v[(i + 1) % v.size()];
        segments.push_back({a, b, static_cast<std::uint32_t>(contours.size()), i});
        totalLength += std::sqrt(dist2(*a, *b));
      }
      contours.push_back({l, f, static_cast<std::uint32_t>(v.size()), feature.closed});
    }
  }
  if (segments.empty()) return;

  // A segment grid: each segment goes into every cell it passes through, row
  // by row. Cells about the mean segment length keep a few segments per cell.
  const double width = extent.maxX - extent.minX;
  const double height = extent.maxY - extent.minY;
  const double cell = std::max(totalLength / static_cast<double>(segments.size()),
                               CellGrid::cellFor(width, height, segments.size(), 0.0));
  CellGrid grid(extent.minX, extent.minY, extent.maxX, extent.maxY, cell);
  auto cellsOf = [&](std::size_t s, auto&& emit) {
    const Point3& a = *segments[s].a;
    const Point3& b = *segments[s].b;
    const auto cy0 = grid.cellY(std::min(a.y, b.y));
    const auto cy1 = grid.cellY(std::max(a.y, b.y));
    for (auto cy = cy0; cy <= cy1; ++cy) {
      double xLo = std::min(a.x, b.x);
      double xHi = std::max(a.x, b.x);
      if (cy0 != cy1) {
        // Clip the segment to this row's y band (a little wider, for rounding).
        const double y0 =
            std::max(std::min(a.y, b.y), grid.originY() + static_cast<double>(cy) * cell);
        const double y1 =
            std::min(std::max(a.y, b.y), grid.originY() + static_cast<double>(cy + 1) * cell);
        const double x0 = a.x + (b.x - a.x) * (y0 - a.y) / (b.y - a.y);
        const double x1 = a.x + (b.x - a.x) * (y1 - a.y) / (b.y - a.y);
        xLo = std::max(xLo, std::min(x0, x1) - 1e-6 * cell);
        xHi = std::min(xHi, std::max(x0, x1) + 1e-6 * cell);
      }
      for (auto cx = grid.cellX(xLo); cx <= grid.cellX(xHi); ++cx) emit(grid.index(cx, cy));
    }
  };
  const std::string stage = "filters.clean";
  ProgressTicker ticker(progress, stage, "contour crossings", grid.cellCount());
  grid.build(segments.size(), cellsOf);

  std::vector<Hit> hits;
  for (std::size_t c = 0; c < grid.cellCount(); ++c) {
    ticker.step(c);
    const std::uint32_t count = grid.cellSize(c);
    if (count < 2) continue;
    const std::uint32_t* items = grid.cellItems(c);
    for (std::uint32_t i = 0; i < count; ++i) {
      const Segment& s1 = segments[items[i]];
      const double loX = std::min(s1.a->x, s1.b->x), hiX = std::max(s1.a->x, s1.b->x);
      const double loY = std::min(s1.a->y, s1.b->y), hiY = std::max(s1.a->y, s1.b->y);
      for (std::uint32_t j = i + 1; j < count; ++j) {
        const Segment& s2 = segments[items[j]];
        if (std::max(s2.a->x, s2.b->x) < loX || std::min(s2.a->x, s2.b->x) > hiX ||
            std::max(s2.a->y, s2.b->y) < loY || std::min(s2.a->y, s2.b->y) > hiY) {
          continue;
        }
        if (s1.contour == s2.contour) {
          const auto& ref = contours[s1.contour];
          const auto lo = std::min(s1.index, s2.index);
          const auto hi = std::max(s1.index, s2.index);
          if (hi == lo + 1) continue;  // neighbours share a vertex
          if (ref.closed && lo == 0 && hi == ref.vertexCount - 1)
            continue;  // across the ring's seam
        } else if (std::abs(s1.a->z - s2.a->z) <= 1e-9) {
          continue;  // same height: may meet
        }
        Point2 at;
        if (!segmentsMeet(*s1.a, *s1.b, *s2.a, *s2.b, at)) continue;
        Segment sa = s1, sb = s2;
        auto key = [](const Segment& s) { return (std::uint64_t{s.contour} << 32) | s.index; };
        if (key(sb) < key(sa)) std::swap(sa, sb);
        hits.push_back({sa, sb, at});
      }
    }
  }
  ticker.finish();
  if (hits.empty()) return;

  auto hitKey = [](const Hit& h) {
    return std::tuple(h.a.contour, h.a.index, h.b.contour, h.b.index);
  };
  std::sort(hits.begin(), hits.end(),
            [&](const Hit& x, const Hit& y) { return hitKey(x) < hitKey(y); });
  hits.erase(std::unique(hits.begin(), hits.end(),
                         [&](const Hit& x, const Hit& y) { return hitKey(x) == hitKey(y); }),
             hits.end());

  std::vector<std::pair<std::uint32_t, std::uint32_t>> bad;  // (contour, segment index)
  for (const auto& h : hits) {
    const auto& ra = contours[h.a.contour];
    const auto& rb = contours[h.b.contour];
    const auto& fa = layers[ra.layer].features[ra.feature];
    const auto& fb = layers[rb.layer].features[rb.feature];
    ContourCrossing c;
    c.layerA = layers[ra.layer].config.name;
    c.layerB = layers[rb.layer].config.name;
    c.fidA = fa.fid;
    c.fidB = fb.fid;
    c.zA = h.a.a->z;
    c.zB = h.b.a->z;
    c.at = h.at;
    c.self = h.a.contour == h.b.contour;
    (c.self ? report.contourSelfCrossings : report.contourCrossings) += 1;
    report.crossings.push_back(c);
    bad.emplace_back(h.a.contour, h.a.index);
    bad.emplace_back(h.b.contour, h.b.index);
  }
  if (options.strict) {
    const auto& first = report.crossings.front();
    SourceLocation where;
    where.layer = first.layerA;
    where.feature = first.fidA;
    throw inputError(std::to_string(report.crossings.size()) +
                         " contour crossing(s); the first: " + describe(first),
                     where,
                     "fix the contours (a contour may not cross itself or another height), or "
                     "leave strict mode off to cut the crossing segments out");
  }

  // Cut the crossing segments out: each affected feature becomes the runs of
  // its remaining segments, as open lines.
  std::sort(bad.begin(), bad.end());
  bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  report.segmentsCutOut += bad.size();
  std::vector<std::vector<IngestedFeature>> replacement(contours.size());
  std::vector<char> affected(contours.size(), 0);
  for (std::size_t k = 0; k < bad.size();) {
    const auto c = bad[k].first;
    affected[c] = 1;
    const auto& feature = layers[contours[c].layer].features[contours[c].feature];
    const auto n = feature.vertices.size();
    const std::size_t segCount = feature.closed ? n : n - 1;
    std::vector<char> cut(segCount, 0);
    for (; k < bad.size() && bad[k].first == c; ++k) cut[bad[k].second] = 1;
    // Start after a cut segment so a ring's runs do not wrap.
    std::size_t start = 0;
    if (feature.closed) {
      while (!cut[start]) ++start;
      start = (start + 1) % segCount;
    }
    IngestedFeature piece;
    auto flush = [&] {
      if (piece.vertices.size() >= 2) replacement[c].push_back(std::move(piece));
      piece = IngestedFeature{};
    };
    for (std::size_t step = 0; step < segCount; ++step) {
      const std::size_t s = (start + step) % segCount;
      if (cut[s]) {
        flush();
        continue;
      }
      if (piece.vertices.empty()) {
        piece.fid = feature.fid;
        piece.part = feature.part;
        piece.ring = feature.ring;
        piece.hasZ = feature.hasZ;
        piece.vertices.push_back(feature.vertices[s]);
      }
      piece.vertices.push_back(feature.vertices[(s + 1) % n]);
    }
    flush();
  }
  for (std::uint32_t l = 0; l < layers.size(); ++l) {
    if (layers[l].kind != FeatureKind::Contour) continue;
    std::vector<IngestedFeature> rebuilt;
    rebuilt.reserve(layers[l].features.size());
    for (std::uint32_t c = 0; c < contours.size(); ++c) {
      if (contours[c].layer != l) continue;
      auto& feature = layers[l].features[contours[c].feature];
      if (!affected[c]) {
        rebuilt.push_back(std::move(feature));
      } else {
        for (auto& piece : replacement[c]) rebuilt.push_back(std::move(piece));
      }
    }
    layers[l].features = std::move(rebuilt);
  }
}

}  // namespace

std::string describe(const ContourCrossing& c) {
  char at[96];
  std::snprintf(at, sizeof at, "%.3f, %.3f", c.at.x, c.at.y);
  char za[32];
  char zb[32];
  std::snprintf(za, sizeof za, "%g", c.zA);
  std::snprintf(zb, sizeof zb, "%g", c.zB);
  if (c.self) {
    return "contour '" + c.layerA + "' feature " + std::to_string(c.fidA) + " (z " + za +
           ") crosses itself at " + at;
  }
  return "contour '" + c.layerA + "' feature " + std::to_string(c.fidA) + " (z " + za +
         ") crosses '" + c.layerB + "' feature " + std::to_string(c.fidB) + " (z " + zb + ") at " +
         at;
}

CleaningReport cleanLayers(std::vector<IngestedLayer>& layers, const CleanOptions& options,
                           const Progress* progress) {
  if (!(options.tolerance >= 0.0))
    throw usageError("the cleaning tolerance must be 0 or more metres");
  CleaningReport report;
  Extent extent;
  std::size_t vertexCount = 0;
  for (const auto& layer : layers) {
    for (const auto& p : layer.points) extent.add(p);
    for (const auto& f : layer.features) {
      for (const auto& v : f.vertices) extent.add(v);
      vertexCount += f.vertices.size();
    }
  }
  if (extent.empty()) return report;
  const std::string stage = "filters.clean";
  reportProgress(progress, stage, "snap", 0, 4);
  snapVertices(layers, options.tolerance, extent, vertexCount, report);
  reportProgress(progress, stage, "repeated vertices", 1, 4);
  dropRepeatedVertices(layers, options.tolerance, report);
  reportProgress(progress, stage, "points", 2, 4);
  mergePoints(layers, options.tolerance, options.zConflict, extent, report);
  reportProgress(progress, stage, "contour crossings", 3, 4);
  findCrossings(layers, options, extent, progress, report);
  reportProgress(progress, stage, "", 4, 4);
  return report;
}

}  // namespace tinsmith::ingest
