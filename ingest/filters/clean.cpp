#include "ingest/filters/clean.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "core/base/error.hpp"
#include "ingest/filters/grid_hash.hpp"

namespace tinsmith::ingest {
namespace {

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

// Hash cell for merging within `tolerance`: at least the tolerance (so the
// 3 x 3 block holds every neighbour), and coarse enough that cell indices fit
// in 32 bits.
double mergeCell(double tolerance, const Extent& extent) {
  return std::max({tolerance, extent.size() / 1.0e9, 1.0e-6});
}

// Features (layer, index) of line and area layers, highest constraintPriority
// first, then config order.
std::vector<std::pair<std::uint32_t, std::uint32_t>> featureOrder(const std::vector<IngestedLayer>& layers) {
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

// Rule 1.
void snapVertices(std::vector<IngestedLayer>& layers, double tolerance, const Extent& extent, std::size_t vertexCount,
                  CleaningReport& report) {
  if (tolerance <= 0.0) return;  // exact duplicates are already identical
  const auto order = featureOrder(layers);
  GridHash hash(extent.minX, extent.minY, mergeCell(tolerance, extent), vertexCount);
  std::vector<Point2> kept;
  std::vector<std::uint32_t> owner;
  kept.reserve(vertexCount);
  owner.reserve(vertexCount);
  const double tol2 = tolerance * tolerance;
  std::uint32_t ordinal = 0;
  for (const auto& [l, fi] : order) {
    for (auto& v : layers[l].features[fi].vertices) {
      double best = std::numeric_limits<double>::infinity();
      std::uint32_t bestIndex = GridHash::kNone;
      hash.forEachNear(v.x, v.y, [&](std::uint32_t i) {
        if (owner[i] == ordinal) return;
        const double dx = kept[i].x - v.x;
        const double dy = kept[i].y - v.y;
        const double d = dx * dx + dy * dy;
        if (d <= tol2 && (d < best || (d == best && i < bestIndex))) {
          best = d;
          bestIndex = i;
        }
      });
      if (bestIndex != GridHash::kNone) {
        if (kept[bestIndex].x != v.x || kept[bestIndex].y != v.y) {
          v.x = kept[bestIndex].x;
          v.y = kept[bestIndex].y;
          ++report.verticesSnapped;
        }
        continue;  // the position is in the hash already
      }
      hash.insert(v.x, v.y);
      kept.push_back({v.x, v.y});
      owner.push_back(ordinal);
    }
    ++ordinal;
  }
}

// Rules 2 and 3.
void dropRepeatedVertices(std::vector<IngestedLayer>& layers, double tolerance, CleaningReport& report) {
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

// Rule 4.
void mergePoints(std::vector<IngestedLayer>& layers, double tolerance, double zConflict, const Extent& extent,
                 std::size_t vertexCount, CleaningReport& report) {
  std::size_t pointCount = 0;
  for (const auto& l : layers) pointCount += l.points.size();
  if (pointCount == 0) return;
  GridHash hash(extent.minX, extent.minY, mergeCell(tolerance, extent), vertexCount);
  std::vector<Point3> kept;
  std::vector<char> isLineVertex;
  kept.reserve(vertexCount);
  isLineVertex.reserve(vertexCount);
  for (const auto& layer : layers) {
    for (const auto& f : layer.features) {
      for (const auto& v : f.vertices) {
        hash.insert(v.x, v.y);
        kept.push_back(v);
        isLineVertex.push_back(1);
      }
    }
  }
  std::vector<std::uint32_t> layerOrder(layers.size());
  std::iota(layerOrder.begin(), layerOrder.end(), 0u);
  std::stable_sort(layerOrder.begin(), layerOrder.end(), [&](std::uint32_t a, std::uint32_t b) {
    return constraintPriority(layers[a].kind) > constraintPriority(layers[b].kind);
  });
  const double tol2 = tolerance * tolerance;
  for (const auto l : layerOrder) {
    auto& layer = layers[l];
    std::size_t w = 0;
    for (std::size_t r = 0; r < layer.points.size(); ++r) {
      const Point3 p = layer.points[r];
      std::uint32_t match = GridHash::kNone;
      bool onLine = false;
      hash.forEachNear(p.x, p.y, [&](std::uint32_t i) {
        if (dist2(kept[i], p) > tol2) return;
        if (isLineVertex[i]) onLine = true;
        if (match == GridHash::kNone || i < match) match = i;
      });
      if (onLine) {
        ++report.pointsOnBreakLineVertices;
        continue;
      }
      if (match != GridHash::kNone) {
        ++report.duplicatePointsMerged;
        if (std::abs(kept[match].z - p.z) > zConflict) ++report.duplicatePointZConflicts;
        continue;
      }
      hash.insert(p.x, p.y);
      kept.push_back(p);
      isLineVertex.push_back(0);
      layer.points[w] = p;
      layer.pointIds[w] = layer.pointIds[r];
      ++w;
    }
    layer.points.resize(w);
    layer.pointIds.resize(w);
  }
}

// ---- Rule 5: contour crossings -------------------------------------------

double orient(const Point3& a, const Point3& b, const Point3& c) {
  // Relative to a, which keeps UTM-sized coordinates from cancelling.
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

bool onSegment(const Point3& a, const Point3& b, const Point3& p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

// Whether segments ab and cd meet (cross or touch); `at` gets a meeting point.
bool segmentsMeet(const Point3& a, const Point3& b, const Point3& c, const Point3& d, Point2& at) {
  if (std::max(a.x, b.x) < std::min(c.x, d.x) || std::max(c.x, d.x) < std::min(a.x, b.x) ||
      std::max(a.y, b.y) < std::min(c.y, d.y) || std::max(c.y, d.y) < std::min(a.y, b.y)) {
    return false;
  }
  const double o1 = orient(a, b, c);
  const double o2 = orient(a, b, d);
  const double o3 = orient(c, d, a);
  const double o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) {
    const double t = o3 / (o3 - o4);
    at = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
    return true;
  }
  if (o1 == 0 && onSegment(a, b, c)) return at = c.xy(), true;
  if (o2 == 0 && onSegment(a, b, d)) return at = d.xy(), true;
  if (o3 == 0 && onSegment(c, d, a)) return at = a.xy(), true;
  if (o4 == 0 && onSegment(c, d, b)) return at = b.xy(), true;
  return false;
}

struct ContourRef {
  std::uint32_t layer;
  std::uint32_t feature;
};

struct Segment {
  std::uint32_t contour;  // index into the ContourRef list
  std::uint32_t index;    // segment i joins vertices i and i+1 (mod n when closed)
};

struct Hit {
  Segment a, b;
  Point2 at;
};

void findCrossings(std::vector<IngestedLayer>& layers, const CleanOptions& options, const Extent& extent,
                   const Progress* progress, CleaningReport& report) {
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
        segments.push_back({static_cast<std::uint32_t>(contours.size()), i});
        totalLength += std::sqrt(dist2(v[i], v[(i + 1) % v.size()]));
      }
      contours.push_back({l, f});
    }
  }
  if (segments.empty()) return;
  auto vertex = [&](const Segment& s, std::uint32_t k) -> const Point3& {
    const auto& ref = contours[s.contour];
    const auto& v = layers[ref.layer].features[ref.feature].vertices;
    return v[(s.index + k) % v.size()];
  };

  // A segment grid: each segment goes into every cell it passes through,
  // row by row; the cell is about twice the mean segment length.
  const double cell = std::max({2.0 * totalLength / static_cast<double>(segments.size()), extent.size() / 1.0e6, 1.0e-6});
  GridHash grid(extent.minX, extent.minY, cell, segments.size() * 3);
  std::vector<std::uint32_t> entrySegment;
  entrySegment.reserve(segments.size() * 3);
  const std::string stage = "filters.clean";
  ProgressTicker ticker(progress, stage, "contour crossings", segments.size() * 2);
  for (std::uint32_t s = 0; s < segments.size(); ++s) {
    ticker.step(s);
    const Point3& a = vertex(segments[s], 0);
    const Point3& b = vertex(segments[s], 1);
    const auto cy0 = grid.cellY(std::min(a.y, b.y));
    const auto cy1 = grid.cellY(std::max(a.y, b.y));
    for (auto cy = cy0; cy <= cy1; ++cy) {
      double xLo = std::min(a.x, b.x);
      double xHi = std::max(a.x, b.x);
      if (cy0 != cy1) {
        // Clip the segment to this row's y band.
        const double y0 = std::max(std::min(a.y, b.y), extent.minY + static_cast<double>(cy) * cell);
        const double y1 = std::min(std::max(a.y, b.y), extent.minY + static_cast<double>(cy + 1) * cell);
        const double x0 = a.x + (b.x - a.x) * (y0 - a.y) / (b.y - a.y);
        const double x1 = a.x + (b.x - a.x) * (y1 - a.y) / (b.y - a.y);
        xLo = std::max(xLo, std::min(x0, x1) - 1e-6 * cell);
        xHi = std::min(xHi, std::max(x0, x1) + 1e-6 * cell);
      }
      for (auto cx = grid.cellX(xLo); cx <= grid.cellX(xHi); ++cx) {
        grid.insertInCell(cx, cy);
        entrySegment.push_back(s);
      }
    }
  }

  std::vector<Hit> hits;
  std::vector<std::uint32_t> inCell;
  std::uint64_t visited = 0;
  grid.forEachCell([&](std::uint32_t head, const std::vector<std::uint32_t>& next) {
    inCell.clear();
    for (auto e = head; e != GridHash::kNone; e = next[e]) inCell.push_back(entrySegment[e]);
    visited += inCell.size();
    ticker.step(segments.size() + visited / 3);
    for (std::size_t i = 0; i < inCell.size(); ++i) {
      for (std::size_t j = i + 1; j < inCell.size(); ++j) {
        Segment sa = segments[inCell[i]];
        Segment sb = segments[inCell[j]];
        if (sa.contour == sb.contour) {
          const auto& ref = contours[sa.contour];
          const auto& feature = layers[ref.layer].features[ref.feature];
          const auto n = static_cast<std::uint32_t>(feature.vertices.size());
          const auto lo = std::min(sa.index, sb.index);
          const auto hi = std::max(sa.index, sb.index);
          if (hi == lo + 1) continue;                                // neighbours share a vertex
          if (feature.closed && lo == 0 && hi == n - 1) continue;  // across the ring's seam
        } else {
          const double za = vertex(sa, 0).z;
          const double zb = vertex(sb, 0).z;
          if (std::abs(za - zb) <= 1e-9) continue;  // same height: may meet
        }
        Point2 at;
        if (!segmentsMeet(vertex(sa, 0), vertex(sa, 1), vertex(sb, 0), vertex(sb, 1), at)) continue;
        auto key = [](const Segment& s) { return (std::uint64_t{s.contour} << 32) | s.index; };
        if (key(sb) < key(sa)) std::swap(sa, sb);
        hits.push_back({sa, sb, at});
      }
    }
  });
  ticker.finish();
  if (hits.empty()) return;

  auto hitKey = [](const Hit& h) {
    return std::tuple(h.a.contour, h.a.index, h.b.contour, h.b.index);
  };
  std::sort(hits.begin(), hits.end(), [&](const Hit& x, const Hit& y) { return hitKey(x) < hitKey(y); });
  hits.erase(std::unique(hits.begin(), hits.end(), [&](const Hit& x, const Hit& y) { return hitKey(x) == hitKey(y); }),
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
    c.zA = vertex(h.a, 0).z;
    c.zB = vertex(h.b, 0).z;
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
    throw inputError(std::to_string(report.crossings.size()) + " contour crossing(s); the first: " + describe(first),
                     where, "fix the contours (a contour may not cross itself or another height), or leave strict mode off to cut the crossing segments out");
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
    return "contour '" + c.layerA + "' feature " + std::to_string(c.fidA) + " (z " + za + ") crosses itself at " + at;
  }
  return "contour '" + c.layerA + "' feature " + std::to_string(c.fidA) + " (z " + za + ") crosses '" + c.layerB +
         "' feature " + std::to_string(c.fidB) + " (z " + zb + ") at " + at;
}

CleaningReport cleanLayers(std::vector<IngestedLayer>& layers, const CleanOptions& options, const Progress* progress) {
  if (!(options.tolerance >= 0.0)) throw usageError("the cleaning tolerance must be 0 or more metres");
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
  mergePoints(layers, options.tolerance, options.zConflict, extent, vertexCount, report);
  reportProgress(progress, stage, "contour crossings", 3, 4);
  findCrossings(layers, options, extent, progress, report);
  reportProgress(progress, stage, "", 4, 4);
  return report;
}

}  // namespace tinsmith::ingest
