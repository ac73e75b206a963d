#include "core/fit/multilevel_steps.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::fit::multilevel {

namespace {

/// Runs f(begin, end, part) for the kParts parts of [0, n), on up to `threads`
/// threads (small inputs on the calling thread).
template <class F>
void forEachPart(std::size_t n, unsigned threads, F&& f) {
  parallelParts(n, kParts, threads, std::forward<F>(f), 16384);
}

constexpr std::size_t kNoPoint = std::numeric_limits<std::size_t>::max();

bool insideSquare(Point2 g, double side) { return g.x >= 0.0 && g.y >= 0.0 && g.x <= side && g.y <= side; }

}  // namespace

void checkOptions(std::size_t pointCount, const MultilevelOptions& options) {
  const auto& crit = options.criteria;
  if (!crit.errorAbsolute && !crit.errorPercent && !crit.countAbove && !crit.curvatureAbove) {
    throw usageError("no refinement criterion given", "give an error tolerance, a count, a curvature threshold or a combination");
  }
  if (pointCount < 3) throw inputError("the fit needs at least 3 data points (got " + std::to_string(pointCount) + ")");
  if (options.maxLevel < 1 || options.maxLevel > BinaryTriangulation::kMaxGridLevels - 1) {
    throw usageError("the maximum level must be within 1.." + std::to_string(BinaryTriangulation::kMaxGridLevels - 1) +
                     " (got " + std::to_string(options.maxLevel) + ")");
  }
  if (!options.weights.empty() && options.weights.size() != pointCount) {
    throw inputError("there are " + std::to_string(options.weights.size()) + " weights for " +
                     std::to_string(pointCount) + " points", {}, "give one weight per point or none");
  }
}

DataExtent measureData(std::span<const Point3> input, std::span<const double> weights, unsigned threads) {
  // Per part; workers never throw: the first bad point is reported after
  // they are done.
  struct Extent {
    double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, zmin = xmin;
    double xmax = -xmin, ymax = -xmin, zmax = -xmin;
    std::size_t badPoint = kNoPoint, badWeight = kNoPoint;
  };
  std::vector<Extent> extents(kParts);
  forEachPart(input.size(), threads, [&](std::size_t b, std::size_t e, unsigned part) {
    Extent ex;
    for (std::size_t i = b; i < e; ++i) {
      const auto& p = input[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        ex.badPoint = std::min(ex.badPoint, i);
        continue;
      }
      if (!weights.empty() && !(weights[i] > 0.0 && std::isfinite(weights[i]))) {
        ex.badWeight = std::min(ex.badWeight, i);
      }
      ex.xmin = std::min(ex.xmin, p.x), ex.xmax = std::max(ex.xmax, p.x);
      ex.ymin = std::min(ex.ymin, p.y), ex.ymax = std::max(ex.ymax, p.y);
      ex.zmin = std::min(ex.zmin, p.z), ex.zmax = std::max(ex.zmax, p.z);
    }
    extents[part] = ex;
  });
  Extent all;
  for (const auto& ex : extents) {
    all.xmin = std::min(all.xmin, ex.xmin), all.xmax = std::max(all.xmax, ex.xmax);
    all.ymin = std::min(all.ymin, ex.ymin), all.ymax = std::max(all.ymax, ex.ymax);
    all.zmin = std::min(all.zmin, ex.zmin), all.zmax = std::max(all.zmax, ex.zmax);
    all.badPoint = std::min(all.badPoint, ex.badPoint);
    all.badWeight = std::min(all.badWeight, ex.badWeight);
  }
  if (all.badPoint <= all.badWeight && all.badPoint != kNoPoint) {
    throw inputError("data point " + std::to_string(all.badPoint) + " has a non-finite coordinate", {},
                     "remove NaN or infinite values from the input");
  }
  if (all.badWeight != kNoPoint) {
    throw inputError("data point " + std::to_string(all.badWeight) + " has a weight that is not positive and finite");
  }
  return {all.xmin, all.ymin, all.zmin, all.xmax, all.ymax, all.zmax};
}

namespace {
/// The column and row of the finest-grid cell holding grid point g (clamped
/// into the grid).
std::array<std::uint64_t, 2> fineCell(const BinaryTriangulation& mesh, Point2 g) {
  const double lim = static_cast<double>(mesh.side() - 1);
  return {static_cast<std::uint64_t>(std::clamp(std::floor(g.x), 0.0, lim)),
          static_cast<std::uint64_t>(std::clamp(std::floor(g.y), 0.0, lim))};
}
std::uint64_t mortonCode(std::uint64_t column, std::uint64_t row) {
  return geometry::spreadBits(column) | (geometry::spreadBits(row) << 1);
}
}  // namespace

std::uint64_t fineCellCode(const BinaryTriangulation& mesh, Point2 g) {
  const auto [ci, cj] = fineCell(mesh, g);
  return mortonCode(ci, cj);
}

SortedData sortAlongMortonCurve(std::span<const Point3> input, std::span<const double> weights,
                                const BinaryTriangulation& mesh, double zShift, unsigned threads) {
  const std::size_t n = input.size();
  SortedData sorted;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(n);
  const double sideD = static_cast<double>(mesh.side());
  std::vector<std::size_t> outside(kParts, kNoPoint);
  forEachPart(n, threads, [&](std::size_t b, std::size_t e, unsigned part) {
    for (std::size_t i = b; i < e; ++i) {
      const Point2 g = mesh.toGrid(input[i].xy());
      if (!insideSquare(g, sideD)) outside[part] = std::min(outside[part], i);
      order[i] = {fineCellCode(mesh, g), static_cast<std::uint32_t>(i)};
    }
  });
  const std::size_t firstOutside = *std::min_element(outside.begin(), outside.end());
  if (firstOutside != kNoPoint) {
    throw inputError("data point " + std::to_string(firstOutside) + " is outside the square domain", {},
                     "choose a domain that covers every data point");
  }
  geometry::radixSortByCode(order, 2 * mesh.gridLevels());
  // Split the pairs before permuting the points (lower peak memory).
  std::vector<std::uint32_t> permutation(n);
  for (std::size_t i = 0; i < n; ++i) permutation[i] = order[i].second;
  std::vector<std::pair<std::uint64_t, std::uint32_t>>().swap(order);  // frees (assigning {} keeps the capacity)
  sorted.points.resize(n);
  forEachPart(n, threads, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) {
      sorted.points[i] = input[permutation[i]];
      sorted.points[i].z -= zShift;
    }
  });
  if (!weights.empty()) {
    sorted.weights.resize(n);
    for (std::size_t i = 0; i < n; ++i) sorted.weights[i] = weights[permutation[i]];
  }
  return sorted;
}

std::vector<FixedVertex> activateFixedPoints(BinaryTriangulation& mesh, std::span<const Point3> fixedPoints,
                                             double zShift) {
  std::vector<std::pair<std::uint64_t, double>> fixedKeys;
  const double sideD = static_cast<double>(mesh.side());
  for (std::size_t index = 0; index < fixedPoints.size(); ++index) {
    const Point3& f = fixedPoints[index];
    const Point2 g = mesh.toGrid(f.xy());
    if (!insideSquare(g, sideD) || !std::isfinite(f.z)) {
      throw inputError("fixed point " + std::to_string(index) + " (" + std::to_string(f.x) + ", " + std::to_string(f.y) +
                           ", " + std::to_string(f.z) + ") is outside the square domain or not finite",
                       {}, "fixed points must lie inside the data's bounding square (or the given domain)");
    }
    const std::uint64_t k = mesh.key(static_cast<std::uint64_t>(std::llround(g.x)), static_cast<std::uint64_t>(std::llround(g.y)));
    mesh.activate(k);
    fixedKeys.emplace_back(k, f.z - zShift);
  }
  std::vector<FixedVertex> fixed;
  for (const auto& [k, z] : fixedKeys) {
    const std::uint32_t id = mesh.vertexId(k);
    auto it = std::find_if(fixed.begin(), fixed.end(), [&](const FixedVertex& f) { return f.vertex == id; });
    if (it != fixed.end()) it->z = z;
    else fixed.push_back({id, z});
  }
  return fixed;
}

const std::vector<TriangleMoments>& levelMoments(
    const BinaryTriangulation& mesh, int level, const SortedData& data,
    std::vector<BinaryTriangle>&& tris, const KeyIndexMap& triIndex,
    std::span<const Triangle> triVerts, std::span<const Point2> positions,
    std::vector<std::uint32_t>& triOf, std::vector<BinaryTriangle>& previousTris,
    std::vector<TriangleMoments>& previousMoments, unsigned threads) {
  // Triangles of Δ_{k−1} that were not split keep their path, their points
  // and so their moments: only the points of split triangles are located
  // again (continuing downward from their old triangle) and accumulated.
  // Per-triangle sums over a fixed split of the points into parts, merged
  // in part order, are the same whichever level computed them.
  const auto& pts = data.points;
  const auto& weights = data.weights;
  // Δ_{k−1}'s triangles and then its moments are let go as soon as they
  // are read (at the finest levels each is tens of MB).
  const std::size_t previousCount = previousTris.size();
  std::vector<std::uint32_t> remap(previousCount);
  NestedLocator locator;
  std::vector<std::int32_t> locatorRoot(previousCount, 0);
  for (std::size_t t = 0; t < previousCount; ++t) {
    remap[t] = level == 1 ? KeyIndexMap::kNone : triIndex.find(previousTris[t].path);
    if (remap[t] == KeyIndexMap::kNone)
      locatorRoot[t] = locator.add(mesh, triIndex, previousTris[t]);
  }
  std::vector<BinaryTriangle>().swap(previousTris);
  std::vector<TriangleMoments> moments(tris.size());
  std::vector<char> fresh(tris.size(), 1);
  for (std::size_t t = 0; t < previousCount; ++t) {
    if (remap[t] == KeyIndexMap::kNone) continue;
    moments[remap[t]] = previousMoments[t];
    fresh[remap[t]] = 0;
  }
  std::vector<TriangleMoments>().swap(previousMoments);
  // Every point's triangle first (a point in a triangle kept from Δ_{k−1}
  // is only renumbered).
  forEachPart(pts.size(), threads, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) {
      const std::uint32_t old =
          level == 1 ? static_cast<std::uint32_t>(mesh.rootIndex(pts[i].xy())) : triOf[i];
      triOf[i] = remap[old] != KeyIndexMap::kNone
                     ? remap[old]
                     : locator.locate(locatorRoot[old], mesh.toGrid(pts[i].xy()));
    }
  });
  locator = NestedLocator();
  std::vector<std::uint32_t>().swap(remap);
  std::vector<std::int32_t>().swap(locatorRoot);
  // Then the sums. A new triangle's points are summed into `moments` by the
  // first part that holds one of them; a later part that holds some too
  // (a triangle across the parts' boundary: few) sums them aside, merged in
  // part order after. The same sums in the same order as a whole array of
  // sums per part merged in part order, without holding an array per part.
  const std::size_t chunk = (pts.size() + kParts - 1) / kParts;  // parallelParts' split
  static_assert(kParts < 255);
  std::vector<std::uint8_t> firstPart(tris.size(), kParts);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::uint32_t t = triOf[i];
    if (fresh[t] && firstPart[t] == kParts) firstPart[t] = static_cast<std::uint8_t>(i / chunk);
  }
  // Barycentric coordinates in triangle (v0, v1, v2) as an affine map of
  // p − v0: b1 = m[0]·dx + m[1]·dy, b2 = m[2]·dx + m[3]·dy, b0 = 1 − b1 − b2.
  // Made as the points come (in Morton order a triangle's points are mostly
  // one run), not held for every triangle.
  struct Affine {
    double x0, y0;
    std::array<double, 4> m;
  };
  const auto affineOf = [&](std::uint32_t t) {
    const Triangle& tv = triVerts[t];
    const Point2 &p0 = positions[tv[0]], &p1 = positions[tv[1]], &p2 = positions[tv[2]];
    const double ax = p1.x - p0.x, ay = p1.y - p0.y, bx = p2.x - p0.x, by = p2.y - p0.y;
    const double det = ax * by - bx * ay;
    return Affine{p0.x, p0.y, {by / det, -bx / det, -ay / det, ax / det}};
  };
  std::vector<std::unordered_map<std::uint32_t, TriangleMoments>> aside(kParts);
  forEachPart(pts.size(), threads, [&](std::size_t b, std::size_t e, unsigned part) {
    std::uint32_t affineTriangle = std::numeric_limits<std::uint32_t>::max();
    Affine af{};
    for (std::size_t i = b; i < e; ++i) {
      const std::uint32_t t = triOf[i];
      if (!fresh[t]) continue;
      if (t != affineTriangle) af = affineOf(affineTriangle = t);
      const double dx = pts[i].x - af.x0, dy = pts[i].y - af.y0;
      const double b1 = af.m[0] * dx + af.m[1] * dy, b2 = af.m[2] * dx + af.m[3] * dy;
      const std::array<double, 3> bc{1.0 - b1 - b2, b1, b2};
      TriangleMoments& sums = firstPart[t] == part ? moments[t] : aside[part][t];
      sums.add(bc, pts[i].z, weights.empty() ? 1.0 : weights[i]);
    }
  });
  for (const auto& sums : aside) {
    for (const auto& [t, m] : sums) moments[t].merge(m);
  }
  previousTris = std::move(tris);
  previousMoments = std::move(moments);
  return previousMoments;
}

LevelErrors levelErrors(const BinaryTriangulation& mesh, const SortedData& data,
                        std::span<const std::uint32_t> triOf, std::span<const Triangle> triVerts,
                        std::span<const Point2> positions, const Vector& coefficients, int level,
                        int gridLevels, unsigned threads) {
  // f on each triangle as a plane through its vertex l:
  // f(p) = c_l + g_x (x − x_l) + g_y (y − y_l) with the gradient of 8.1.
  // Made as the points come (in Morton order a triangle's points are mostly
  // one run), not held for every triangle: at the finest levels that was
  // 40 bytes a triangle, more than the points themselves.
  struct Plane {
    double x0, y0, z0, gx, gy;
  };
  const auto planeOf = [&](std::uint32_t t) {
    const Triangle& tv = triVerts[t];
    const Point2 &pa = positions[tv[0]], &pb = positions[tv[1]], &pc = positions[tv[2]];
    const double ca = coefficients[tv[0]], cb = coefficients[tv[1]], cc = coefficients[tv[2]];
    const double area2 = geometry::orient2dInexact(pa, pb, pc);
    const double gx = ((pb.y - pc.y) * ca + (pc.y - pa.y) * cb + (pa.y - pb.y) * cc) / area2;
    const double gy = ((pc.x - pb.x) * ca + (pa.x - pc.x) * cb + (pb.x - pa.x) * cc) / area2;
    return Plane{pa.x, pa.y, ca, gx, gy};
  };
  // The points of a cell are one contiguous run (Morton order): per part a
  // list of runs, joined across the part boundaries.
  const auto& pts = data.points;
  const int coarser = gridLevels - level;  // a fine cell's column and row >> this: Ψ_level's
  // A part has at most one record a point. The first part's room holds
  // every part's records, which are then appended to it in place: no record
  // is copied twice or held in a vector grown by doubling (at the finest
  // levels a cell holds about one point, and the records are the data's
  // size). Room not written to is address space only.
  std::vector<std::vector<CellRecord>> records(kParts);
  std::vector<double> maxErr(kParts, 0.0), sumSq(kParts, 0.0);
  forEachPart(pts.size(), threads, [&](std::size_t b, std::size_t e, unsigned part) {
    auto& rec = records[part];
    rec.reserve(part == 0 ? pts.size() : e - b);
    double mx = 0.0, ss = 0.0;
    std::uint32_t planeTriangle = std::numeric_limits<std::uint32_t>::max();
    Plane pl{};
    std::uint64_t runColumn = 0, runRow = 0;  // of the cell of rec.back()
    for (std::size_t i = b; i < e; ++i) {
      if (triOf[i] != planeTriangle) pl = planeOf(planeTriangle = triOf[i]);
      const double f = pl.z0 + pl.gx * (pts[i].x - pl.x0) + pl.gy * (pts[i].y - pl.y0);
      const double err = std::abs(f - pts[i].z);
      mx = std::max(mx, err);
      ss += err * err;
      // The cell of Ψ_level (its Morton code, fineCellCode >> 2·coarser,
      // made only when a run of points in one cell begins).
      const auto [ci, cj] = fineCell(mesh, mesh.toGrid(pts[i].xy()));
      const std::uint64_t column = ci >> coarser, row = cj >> coarser;
      if (rec.empty() || column != runColumn || row != runRow) {
        rec.push_back({mortonCode(column, row), 0, 0.0});
        runColumn = column;
        runRow = row;
      }
      rec.back().count += 1;
      rec.back().maxError = std::max(rec.back().maxError, err);
    }
    maxErr[part] = mx;
    sumSq[part] = ss;
  });
  LevelErrors out;
  out.cells = std::move(records[0]);
  for (unsigned part = 1; part < kParts; ++part) {
    auto& rec = records[part];
    auto from = rec.begin();
    if (from != rec.end() && !out.cells.empty() && out.cells.back().cell == from->cell) {
      out.cells.back().count += from->count;  // a cell across the parts' boundary
      out.cells.back().maxError = std::max(out.cells.back().maxError, from->maxError);
      ++from;
    }
    out.cells.insert(out.cells.end(), from, rec.end());
    std::vector<CellRecord>().swap(rec);
  }
  out.maxError = *std::max_element(maxErr.begin(), maxErr.end());
  out.rmsError = std::sqrt(std::accumulate(sumSq.begin(), sumSq.end(), 0.0) / static_cast<double>(pts.size()));
  return out;
}

std::vector<std::uint64_t> cellsToRefine(const RefinementCriteria& crit, double epsilon, const LevelErrors& errors,
                                         const BinaryTriangulation& mesh, std::span<const Triangle> triVerts,
                                         std::span<const Point2> positions, const Vector& coefficients, int level,
                                         int gridLevels) {
  const int shift = 2 * (gridLevels - level);
  const bool useError = crit.errorAbsolute.has_value() || crit.errorPercent.has_value();
  // Curvature: cells holding the midpoint of an edge with |T_e f| > τ.
  std::vector<std::uint64_t> curved;
  if (crit.curvatureAbove) {
    for (const auto& e : meshEdges(positions.size(), triVerts)) {
      if (e.right == MeshEdge::kNone) continue;
      const auto beta = thinPlateBetas(positions[e.s], positions[e.t], positions[e.left], positions[e.right]);
      const double te = beta[0] * coefficients[e.s] + beta[1] * coefficients[e.t] + beta[2] * coefficients[e.left] +
                        beta[3] * coefficients[e.right];
      if (std::abs(te) > *crit.curvatureAbove) {
        const Point2 mid{0.5 * (positions[e.s].x + positions[e.t].x), 0.5 * (positions[e.s].y + positions[e.t].y)};
        curved.push_back(fineCellCode(mesh, mesh.toGrid(mid)) >> shift);
      }
    }
    std::sort(curved.begin(), curved.end());
    curved.erase(std::unique(curved.begin(), curved.end()), curved.end());
    if (!crit.countAbove && !useError) return curved;  // cells without data may be curved too
  }
  // Every criterion that is set must hold.
  std::vector<std::uint64_t> refine;
  for (const auto& c : errors.cells) {
    bool ok = true;
    if (crit.countAbove) ok = ok && c.count > *crit.countAbove;
    if (useError) ok = ok && c.maxError > epsilon;
    if (crit.curvatureAbove) ok = ok && std::binary_search(curved.begin(), curved.end(), c.cell);
    if (ok) refine.push_back(c.cell);
  }
  return refine;
}

}  // namespace tinsmith::fit::multilevel
