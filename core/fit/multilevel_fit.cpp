// Algorithm 8.1 over binary triangulations (Hjelle & Dæhlen 8.10).
//
// The data are sorted once along the Morton (Z-order) curve of the finest grid,
// so that the points of any grid cell of any level form one contiguous run:
// the per-cell criteria are a linear scan, and nearby points are near in memory.
// Every point keeps the bisection-tree path of its triangle; as the
// triangulations are nested, locating it at the next level continues downward
// from there.
#include "core/fit/multilevel_fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <thread>
#include <utility>

#include "core/base/error.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::fit {

namespace {

std::uint64_t spreadBits(std::uint64_t v) {
  v &= 0xffffffffULL;
  v = (v | (v << 16)) & 0x0000ffff0000ffffULL;
  v = (v | (v << 8)) & 0x00ff00ff00ff00ffULL;
  v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0fULL;
  v = (v | (v << 2)) & 0x3333333333333333ULL;
  v = (v | (v << 1)) & 0x5555555555555555ULL;
  return v;
}

std::uint64_t compactBits(std::uint64_t v) {
  v &= 0x5555555555555555ULL;
  v = (v | (v >> 1)) & 0x3333333333333333ULL;
  v = (v | (v >> 2)) & 0x0f0f0f0f0f0f0f0fULL;
  v = (v | (v >> 4)) & 0x00ff00ff00ff00ffULL;
  v = (v | (v >> 8)) & 0x0000ffff0000ffffULL;
  v = (v | (v >> 16)) & 0x00000000ffffffffULL;
  return v;
}

/// The points are split into this many fixed parts, whatever the number of
/// threads, and per-part sums are combined in part order: the result does not
/// depend on the thread count (same input and options, same bytes).
constexpr int kParts = 2;

/// Runs f(begin, end, part) for the kParts parts of [0, n), on up to `threads`
/// threads.
template <class F>
void forEachPart(std::size_t n, int threads, F&& f) {
  const std::size_t chunk = (n + kParts - 1) / kParts;
  auto range = [&](int part) {
    const std::size_t b = std::min(n, chunk * static_cast<std::size_t>(part));
    return std::pair{b, std::min(n, b + chunk)};
  };
  if (threads <= 1 || n < 16384) {
    for (int part = 0; part < kParts; ++part) f(range(part).first, range(part).second, part);
    return;
  }
  std::vector<std::thread> pool;
  for (int part = 1; part < kParts; ++part) {
    pool.emplace_back([&f, r = range(part), part] { f(r.first, r.second, part); });
  }
  f(range(0).first, range(0).second, 0);
  for (auto& th : pool) th.join();
}

/// Sorts (code, index) pairs by code with a stable LSD radix sort over the
/// low `bits` bits of the codes (11 bits a pass): linear in the points.
void radixSortByCode(std::vector<std::pair<std::uint64_t, std::uint32_t>>& v, int bits) {
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> tmp(v.size());
  std::vector<std::size_t> offset(kBuckets);
  for (int sh = 0; sh < bits; sh += kDigit) {
    std::fill(offset.begin(), offset.end(), 0);
    for (const auto& e : v) ++offset[(e.first >> sh) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (auto& o : offset) {
      const std::size_t c = o;
      o = sum;
      sum += c;
    }
    for (const auto& e : v) tmp[offset[(e.first >> sh) & (kBuckets - 1)]++] = e;
    v.swap(tmp);
  }
}

/// Point location below the triangles of the previous level (the
/// triangulations are nested, 8.10). The bisection subtree of Δ_k under each
/// split triangle of Δ_{k−1} is laid out once as nodes holding the splitting
/// line; a point walks it with one orientation test a step and no hash
/// lookups, taking the decisions of BinaryTriangulation::descend.
struct LocatorNode {
  Point2 a, j;             ///< the splitting line a–j, grid coordinates
  double lSide = 0.0;      ///< geometry::orient2dInexact(a, j, l): the side of the l child
  std::int32_t child[2]{};  ///< l child, r child: ≥ 0 a node, < 0 the leaf −1 − triangle index
};

std::int32_t buildLocator(const BinaryTriangulation& mesh, const KeyIndexMap& triIndex, const BinaryTriangle& t,
                          std::vector<LocatorNode>& nodes) {
  if (!mesh.isSplit(t)) {
    const std::uint32_t id = triIndex.find(t.path);
    if (id == KeyIndexMap::kNone) throw internalError("multilevel fit: a leaf triangle is not in the triangulation");
    return -1 - static_cast<std::int32_t>(id);
  }
  const std::uint64_t j = (t.l + t.r) / 2;
  const Point2 pl = mesh.gridPosition(t.l), pa = mesh.gridPosition(t.a), pr = mesh.gridPosition(t.r);
  const Point2 pj{0.5 * (pl.x + pr.x), 0.5 * (pl.y + pr.y)};
  const auto index = static_cast<std::int32_t>(nodes.size());
  nodes.push_back({pa, pj, geometry::orient2dInexact(pa, pj, pl), {0, 0}});
  const std::int32_t first = buildLocator(mesh, triIndex, BinaryTriangle{t.a, j, t.l, t.path << 1, t.depth + 1}, nodes);
  const std::int32_t second =
      buildLocator(mesh, triIndex, BinaryTriangle{t.r, j, t.a, (t.path << 1) | 1, t.depth + 1}, nodes);
  nodes[static_cast<std::size_t>(index)].child[0] = first;
  nodes[static_cast<std::size_t>(index)].child[1] = second;
  return index;
}

struct CellRecord {
  std::uint64_t cell = 0;  ///< Morton code of the cell at the current level
  std::size_t count = 0;
  double maxError = 0.0;
};

const char* solverName(SolverKind s) {
  switch (s) {
    case SolverKind::Direct: return "direct";
    case SolverKind::GaussSeidel: return "gauss-seidel";
    case SolverKind::ConjugateGradient: return "cg";
  }
  return "?";
}

}  // namespace

MultilevelFit::MultilevelFit(BinaryTriangulation mesh, std::vector<double> z, std::vector<LevelStats> levels)
    : mesh_(std::move(mesh)), z_(std::move(z)), levels_(std::move(levels)) {}

double MultilevelFit::evaluate(Point2 p) const {
  const BinaryLocation loc = mesh_.locate(p);
  const auto& t = loc.triangle;
  return loc.barycentric[0] * z_[mesh_.vertexId(t.l)] + loc.barycentric[1] * z_[mesh_.vertexId(t.r)] +
         loc.barycentric[2] * z_[mesh_.vertexId(t.a)];
}

std::vector<double> MultilevelFit::evaluateGrid(Point2 origin, double dx, double dy, std::size_t nx,
                                                std::size_t ny) const {
  std::vector<double> out(nx * ny, std::numeric_limits<double>::quiet_NaN());
  const Point2 lo = mesh_.origin();
  const double hi = mesh_.size();
  for (std::size_t j = 0; j < ny; ++j) {
    for (std::size_t i = 0; i < nx; ++i) {
      const Point2 p{origin.x + static_cast<double>(i) * dx, origin.y + static_cast<double>(j) * dy};
      if (p.x < lo.x || p.y < lo.y || p.x > lo.x + hi || p.y > lo.y + hi) continue;
      out[j * nx + i] = evaluate(p);
    }
  }
  return out;
}

TinData MultilevelFit::toTinData(const std::string& crs) const {
  TinData tin;
  tin.crs = crs;
  const auto keys = mesh_.activeKeys();
  tin.vertices.reserve(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const Point2 p = mesh_.position(keys[i]);
    tin.vertices.push_back({p.x, p.y, z_[i]});
  }
  const auto tris = mesh_.triangles();
  tin.triangles.reserve(tris.size());
  for (const auto& t : tris) {
    tin.triangles.push_back({mesh_.vertexId(t.l), mesh_.vertexId(t.r), mesh_.vertexId(t.a)});
  }
  return tin;
}

MultilevelFit fitMultilevel(std::span<const Point3> input, const MultilevelOptions& options) {
  using Clock = std::chrono::steady_clock;
  const auto& crit = options.criteria;
  if (!crit.errorAbsolute && !crit.errorPercent && !crit.countAbove && !crit.curvatureAbove) {
    throw usageError("no refinement criterion given", "give an error tolerance, a count, a curvature threshold or a combination");
  }
  if (input.size() < 3) throw inputError("the fit needs at least 3 data points (got " + std::to_string(input.size()) + ")");
  if (options.maxLevel < 1 || options.maxLevel > BinaryTriangulation::kMaxGridLevels - 1) {
    throw usageError("the maximum level must be within 1.." + std::to_string(BinaryTriangulation::kMaxGridLevels - 1) +
                     " (got " + std::to_string(options.maxLevel) + ")");
  }
  if (!options.weights.empty() && options.weights.size() != input.size()) {
    throw inputError("there are " + std::to_string(options.weights.size()) + " weights for " +
                     std::to_string(input.size()) + " points", {}, "give one weight per point or none");
  }
  const int threads = options.threads > 0 ? options.threads
                                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  // Extent and validity, per part (workers never throw: the first bad point
  // is reported after they are done).
  struct Extent {
    double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, zmin = xmin;
    double xmax = -xmin, ymax = -xmin, zmax = -xmin;
    std::size_t badPoint = std::numeric_limits<std::size_t>::max(), badWeight = badPoint;
  };
  std::vector<Extent> extents(kParts);
  forEachPart(input.size(), threads, [&](std::size_t b, std::size_t e, int worker) {
    Extent ex;
    for (std::size_t i = b; i < e; ++i) {
      const auto& p = input[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        ex.badPoint = std::min(ex.badPoint, i);
        continue;
      }
      if (!options.weights.empty() && !(options.weights[i] > 0.0 && std::isfinite(options.weights[i]))) {
        ex.badWeight = std::min(ex.badWeight, i);
      }
      ex.xmin = std::min(ex.xmin, p.x), ex.xmax = std::max(ex.xmax, p.x);
      ex.ymin = std::min(ex.ymin, p.y), ex.ymax = std::max(ex.ymax, p.y);
      ex.zmin = std::min(ex.zmin, p.z), ex.zmax = std::max(ex.zmax, p.z);
    }
    extents[static_cast<std::size_t>(worker)] = ex;
  });
  Extent all;
  for (const auto& ex : extents) {
    all.xmin = std::min(all.xmin, ex.xmin), all.xmax = std::max(all.xmax, ex.xmax);
    all.ymin = std::min(all.ymin, ex.ymin), all.ymax = std::max(all.ymax, ex.ymax);
    all.zmin = std::min(all.zmin, ex.zmin), all.zmax = std::max(all.zmax, ex.zmax);
    all.badPoint = std::min(all.badPoint, ex.badPoint);
    all.badWeight = std::min(all.badWeight, ex.badWeight);
  }
  if (all.badPoint <= all.badWeight && all.badPoint != std::numeric_limits<std::size_t>::max()) {
    throw inputError("data point " + std::to_string(all.badPoint) + " has a non-finite coordinate", {},
                     "remove NaN or infinite values from the input");
  }
  if (all.badWeight != std::numeric_limits<std::size_t>::max()) {
    throw inputError("data point " + std::to_string(all.badWeight) + " has a weight that is not positive and finite");
  }
  const double xmin = all.xmin, ymin = all.ymin, zmin = all.zmin, xmax = all.xmax, ymax = all.ymax, zmax = all.zmax;
  Point2 origin{xmin, ymin};
  double size = std::max(xmax - xmin, ymax - ymin);
  if (options.domainOrigin) origin = *options.domainOrigin;
  if (options.domainSize) size = *options.domainSize;
  if (!(size > 0.0)) {
    throw inputError("the data points have no extent in x and y", {}, "give points that span an area");
  }
  // The fit runs on z − zShift and adds zShift back at the end. The result is
  // the same in exact arithmetic (the hat functions sum to one and every
  // smoothing term annihilates constants), but the solvers' relative stopping
  // tests (‖Δc‖/‖c‖, ‖r‖/‖b‖) no longer depend on how high the terrain lies:
  // at 1 000 m they would accept a surface metres away from the solution.
  const double zShift = 0.5 * (zmin + zmax);
  const int gridLevels = options.maxLevel + 1;
  BinaryTriangulation mesh(origin, size, gridLevels);
  const std::uint64_t side = mesh.side();

  // Sort the data along the Morton curve of the finest grid.
  auto fineCell = [&](const Point2& g) {
    const double lim = static_cast<double>(side - 1);
    const auto ci = static_cast<std::uint64_t>(std::clamp(std::floor(g.x), 0.0, lim));
    const auto cj = static_cast<std::uint64_t>(std::clamp(std::floor(g.y), 0.0, lim));
    return spreadBits(ci) | (spreadBits(cj) << 1);
  };
  const std::size_t n = input.size();
  std::vector<Point3> pts;
  std::vector<double> weights;
  // Morton code of each point's cell of the finest grid, in sorted order: the
  // cell of Ψ_k holding point i is codes[i] >> 2(K − k).
  std::vector<std::uint64_t> codes;
  {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order(n);
    const double sideD = static_cast<double>(side);
    std::vector<std::size_t> outside(kParts, std::numeric_limits<std::size_t>::max());
    forEachPart(n, threads, [&](std::size_t b, std::size_t e, int worker) {
      for (std::size_t i = b; i < e; ++i) {
        const Point2 g = mesh.toGrid(input[i].xy());
        if (!(g.x >= 0.0 && g.y >= 0.0 && g.x <= sideD && g.y <= sideD)) {
          outside[static_cast<std::size_t>(worker)] = std::min(outside[static_cast<std::size_t>(worker)], i);
        }
        order[i] = {fineCell(g), static_cast<std::uint32_t>(i)};
      }
    });
    const std::size_t firstOutside = *std::min_element(outside.begin(), outside.end());
    if (firstOutside != std::numeric_limits<std::size_t>::max()) {
      throw inputError("data point " + std::to_string(firstOutside) + " is outside the square domain", {},
                       "choose a domain that covers every data point");
    }
    radixSortByCode(order, 2 * gridLevels);
    // Split the pairs before permuting the points (lower peak memory).
    std::vector<std::uint32_t> permutation(n);
    codes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      codes[i] = order[i].first;
      permutation[i] = order[i].second;
    }
    std::vector<std::pair<std::uint64_t, std::uint32_t>>().swap(order);  // frees (assigning {} keeps the capacity)
    pts.resize(n);
    forEachPart(n, threads, [&](std::size_t b, std::size_t e, int) {
      for (std::size_t i = b; i < e; ++i) {
        pts[i] = input[permutation[i]];
        pts[i].z -= zShift;
      }
    });
    if (!options.weights.empty()) {
      weights.resize(n);
      for (std::size_t i = 0; i < n; ++i) weights[i] = options.weights[permutation[i]];
    }
  }

  // Level 1 locates every point below the four triangles around the centre.
  std::vector<BinaryTriangle> previousTris;
  {
    const auto roots = mesh.rootTriangles();
    previousTris.assign(roots.begin(), roots.end());
  }

  // Constraints (8.9): snapped to the finest grid, active from the start.
  std::vector<std::pair<std::uint64_t, double>> fixedKeys;
  for (std::size_t index = 0; index < options.fixed.size(); ++index) {
    const Point3& f = options.fixed[index];
    const Point2 g = mesh.toGrid(f.xy());
    const double sideD = static_cast<double>(side);
    if (!(g.x >= 0.0 && g.y >= 0.0 && g.x <= sideD && g.y <= sideD) || !std::isfinite(f.z)) {
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

  const double epsilon = crit.errorAbsolute ? *crit.errorAbsolute
                         : crit.errorPercent ? *crit.errorPercent / 100.0 * (zmax - zmin)
                                             : 0.0;
  const bool useError = crit.errorAbsolute.has_value() || crit.errorPercent.has_value();

  // Per point: the index of its triangle in the current triangulation. Per
  // triangle of the previous level (previousTris): its merged moments.
  std::vector<std::uint32_t> triOf(n, 0);
  std::vector<TriangleMoments> previousMoments;
  Vector coefficients;
  std::vector<LevelStats> stats;

  for (int level = 1;; ++level) {
    const auto start = Clock::now();
    LevelStats st;
    st.level = level;
    const std::size_t nv = mesh.activeCount();
    st.vertices = nv;

    // Nested iteration (8.10): old coefficients carry over (dense ids are
    // stable); a new vertex gets f_{k−1} at its position = the mean of its
    // split edge's ends (the edge lies inside one triangle of Δ_{k−1}).
    const auto oldCount = static_cast<std::size_t>(coefficients.size());
    coefficients.conservativeResize(static_cast<Eigen::Index>(nv));
    const auto keys = mesh.activeKeys();
    for (std::size_t id = oldCount; id < nv; ++id) {
      if (oldCount == 0) {
        coefficients[static_cast<Eigen::Index>(id)] = 0.0;
        continue;
      }
      const auto ends = mesh.splitEdge(keys[id]);
      coefficients[static_cast<Eigen::Index>(id)] =
          0.5 * (coefficients[mesh.vertexId(ends[0])] + coefficients[mesh.vertexId(ends[1])]);
    }
    for (const auto& f : fixed) coefficients[f.vertex] = f.z;

    const auto tris = mesh.triangles();
    st.triangles = tris.size();
    KeyIndexMap triIndex;
    triIndex.reserve(tris.size());
    std::vector<Triangle> triVerts(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      triIndex.insert(tris[t].path, static_cast<std::uint32_t>(t));
      triVerts[t] = {mesh.vertexId(tris[t].l), mesh.vertexId(tris[t].r), mesh.vertexId(tris[t].a)};
    }
    std::vector<Point2> positions(nv);
    for (std::size_t i = 0; i < nv; ++i) positions[i] = mesh.position(keys[i]);

    // The smoothing matrix first: its temporaries are gone before the
    // per-part moments are allocated (lower peak memory).
    SparseMatrix energy;
    if (options.smoothing != Smoothing::None) energy = smoothingMatrix(options.smoothing, positions, triVerts);

    // Triangles of Δ_{k−1} that were not split keep their path, their points
    // and so their moments: only the points of split triangles are located
    // again (continuing downward from their old triangle) and accumulated.
    // Per-triangle sums over a fixed split of the points into parts, merged
    // in part order, are the same whichever level computed them.
    std::vector<std::uint32_t> remap(previousTris.size());
    for (std::size_t t = 0; t < previousTris.size(); ++t) {
      remap[t] = level == 1 ? KeyIndexMap::kNone : triIndex.find(previousTris[t].path);
    }
    std::vector<TriangleMoments> moments(tris.size());
    std::vector<char> fresh(tris.size(), 1);
    std::vector<LocatorNode> nodes;
    std::vector<std::int32_t> locatorRoot(previousTris.size(), 0);
    for (std::size_t t = 0; t < previousTris.size(); ++t) {
      if (remap[t] == KeyIndexMap::kNone) {
        locatorRoot[t] = buildLocator(mesh, triIndex, previousTris[t], nodes);
      } else {
        moments[remap[t]] = previousMoments[t];
        fresh[remap[t]] = 0;
      }
    }
    // Barycentric coordinates in triangle (v0, v1, v2) as an affine map of
    // p − v0: b1 = m[0]·dx + m[1]·dy, b2 = m[2]·dx + m[3]·dy, b0 = 1 − b1 − b2.
    struct Affine {
      double x0, y0;
      std::array<double, 4> m;
    };
    std::vector<Affine> affine(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const Triangle& tv = triVerts[t];
      const Point2 &p0 = positions[tv[0]], &p1 = positions[tv[1]], &p2 = positions[tv[2]];
      const double ax = p1.x - p0.x, ay = p1.y - p0.y, bx = p2.x - p0.x, by = p2.y - p0.y;
      const double det = ax * by - bx * ay;
      affine[t] = {p0.x, p0.y, {by / det, -bx / det, -ay / det, ax / det}};
    }
    {
      std::vector<std::vector<TriangleMoments>> partMoments(kParts);
      forEachPart(n, threads, [&](std::size_t b, std::size_t e, int worker) {
        auto& mine = partMoments[static_cast<std::size_t>(worker)];
        for (std::size_t i = b; i < e; ++i) {
          const std::uint32_t old = level == 1 ? static_cast<std::uint32_t>(mesh.rootIndex(pts[i].xy())) : triOf[i];
          if (remap[old] != KeyIndexMap::kNone) {
            triOf[i] = remap[old];
            continue;
          }
          std::int32_t node = locatorRoot[old];
          const Point2 g = mesh.toGrid(pts[i].xy());
          while (node >= 0) {
            const LocatorNode& nd = nodes[static_cast<std::size_t>(node)];
            node = nd.child[geometry::orient2dInexact(nd.a, nd.j, g) * nd.lSide >= 0.0 ? 0 : 1];
          }
          const auto t = static_cast<std::uint32_t>(-1 - node);
          triOf[i] = t;
          const Affine& af = affine[t];
          const double dx = pts[i].x - af.x0, dy = pts[i].y - af.y0;
          const double b1 = af.m[0] * dx + af.m[1] * dy, b2 = af.m[2] * dx + af.m[3] * dy;
          const std::array<double, 3> bc{1.0 - b1 - b2, b1, b2};
          if (mine.empty()) mine.assign(tris.size(), TriangleMoments{});
          mine[t].add(bc, pts[i].z, weights.empty() ? 1.0 : weights[i]);
        }
      });
      for (std::size_t t = 0; t < tris.size(); ++t) {
        if (!fresh[t]) continue;
        bool first = true;
        for (const auto& part : partMoments) {
          if (part.empty()) continue;
          if (first) moments[t] = part[t];
          else moments[t].merge(part[t]);
          first = false;
        }
      }
    }
    previousTris = tris;
    previousMoments = moments;
    SparseMatrix a;
    Vector rhs;
    if (options.smoothing != Smoothing::None) {
      PenalizedSystem sys = assemblePenalized(triVerts, moments, energy, options.lambdaFactor, options.lambdaAbsolute);
      st.lambda = sys.lambda;
      energy = SparseMatrix();
      a = std::move(sys.a);
      rhs = std::move(sys.b);
    } else {
      NormalEquations eq = scatterMoments(nv, triVerts, moments);
      a = std::move(eq.btb);
      rhs = std::move(eq.btz);
    }
    std::vector<TriangleMoments>().swap(moments);
    applyFixedVertices(a, rhs, fixed);
    st.solver = level <= options.directLevels ? SolverKind::Direct : options.solver;
    const SolveReport report = solveSystem(a, rhs, coefficients, st.solver, options.control);
    st.iterations = report.iterations;
    st.relativeResidual = report.relativeResidual;

    // Errors at the data and per-cell records of Ψ_level (contiguous runs).
    // f on each triangle as a plane through its vertex l:
    // f(p) = c_l + g_x (x − x_l) + g_y (y − y_l) with the gradient of 8.1.
    struct Plane {
      double x0, y0, z0, gx, gy;
    };
    std::vector<Plane> planes(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const Triangle& tv = triVerts[t];
      const Point2 &pa = positions[tv[0]], &pb = positions[tv[1]], &pc = positions[tv[2]];
      const double ca = coefficients[tv[0]], cb = coefficients[tv[1]], cc = coefficients[tv[2]];
      const double area2 = geometry::orient2dInexact(pa, pb, pc);
      const double gx = ((pb.y - pc.y) * ca + (pc.y - pa.y) * cb + (pa.y - pb.y) * cc) / area2;
      const double gy = ((pc.x - pb.x) * ca + (pa.x - pc.x) * cb + (pb.x - pa.x) * cc) / area2;
      planes[t] = {pa.x, pa.y, ca, gx, gy};
    }
    const int shift = 2 * (gridLevels - level);
    std::vector<std::vector<CellRecord>> records(kParts);
    std::vector<double> maxErr(kParts, 0.0), sumSq(kParts, 0.0);
    forEachPart(n, threads, [&](std::size_t b, std::size_t e, int worker) {
      auto& rec = records[static_cast<std::size_t>(worker)];
      double mx = 0.0, ss = 0.0;
      for (std::size_t i = b; i < e; ++i) {
        const Plane& pl = planes[triOf[i]];
        const double f = pl.z0 + pl.gx * (pts[i].x - pl.x0) + pl.gy * (pts[i].y - pl.y0);
        const double err = std::abs(f - pts[i].z);
        mx = std::max(mx, err);
        ss += err * err;
        const std::uint64_t cell = codes[i] >> shift;
        if (rec.empty() || rec.back().cell != cell) rec.push_back({cell, 0, 0.0});
        rec.back().count += 1;
        rec.back().maxError = std::max(rec.back().maxError, err);
      }
      maxErr[static_cast<std::size_t>(worker)] = mx;
      sumSq[static_cast<std::size_t>(worker)] = ss;
    });
    std::vector<CellRecord> cells;
    for (auto& rec : records) {
      for (const auto& r : rec) {
        if (!cells.empty() && cells.back().cell == r.cell) {
          cells.back().count += r.count;
          cells.back().maxError = std::max(cells.back().maxError, r.maxError);
        } else {
          cells.push_back(r);
        }
      }
    }
    records.clear();
    st.maxError = *std::max_element(maxErr.begin(), maxErr.end());
    st.rmsError = std::sqrt(std::accumulate(sumSq.begin(), sumSq.end(), 0.0) / static_cast<double>(n));

    // Curvature: cells holding the midpoint of an edge with |T_e f| > τ.
    std::vector<std::uint64_t> curved;
    if (crit.curvatureAbove) {
      for (const auto& e : meshEdges(nv, triVerts)) {
        if (e.right == MeshEdge::kNone) continue;
        const auto beta = thinPlateBetas(positions[e.s], positions[e.t], positions[e.left], positions[e.right]);
        const double te = beta[0] * coefficients[e.s] + beta[1] * coefficients[e.t] + beta[2] * coefficients[e.left] +
                          beta[3] * coefficients[e.right];
        if (std::abs(te) > *crit.curvatureAbove) {
          const Point2 mid{0.5 * (positions[e.s].x + positions[e.t].x), 0.5 * (positions[e.s].y + positions[e.t].y)};
          curved.push_back(fineCell(mesh.toGrid(mid)) >> shift);
        }
      }
      std::sort(curved.begin(), curved.end());
      curved.erase(std::unique(curved.begin(), curved.end()), curved.end());
    }

    // Cells to refine: every criterion that is set must hold.
    std::vector<std::uint64_t> refine;
    {
      auto isCurved = [&](std::uint64_t c) { return std::binary_search(curved.begin(), curved.end(), c); };
      for (const auto& c : cells) {
        bool ok = true;
        if (crit.countAbove) ok = ok && c.count > *crit.countAbove;
        if (useError) ok = ok && c.maxError > epsilon;
        if (crit.curvatureAbove) ok = ok && isCurved(c.cell);
        if (ok) refine.push_back(c.cell);
      }
      if (crit.curvatureAbove && !crit.countAbove && !useError) {
        refine = curved;  // cells without data may be curved too
      }
    }
    st.cellsFailing = refine.size();
    const bool last = refine.empty() || level >= options.maxLevel;
    if (!last) {
      for (std::uint64_t c : refine) {
        mesh.activate(mesh.cellCentre(level, compactBits(c), compactBits(c >> 1)));
      }
      st.cellsRefined = refine.size();
    }
    st.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.push_back(st);
    if (options.progress) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "level %d: %zu vertices, %zu triangles, %s %d it, max error %.6g, rms %.6g, %zu cells refined, %.3f s",
                    st.level, st.vertices, st.triangles, solverName(st.solver), st.iterations, st.maxError, st.rmsError,
                    st.cellsRefined, st.seconds);
      options.progress(line);
    }
    if (last) break;
  }

  std::vector<double> z(coefficients.data(), coefficients.data() + coefficients.size());
  for (double& v : z) v += zShift;
  return MultilevelFit(std::move(mesh), std::move(z), std::move(stats));
}

}  // namespace tinsmith::fit
