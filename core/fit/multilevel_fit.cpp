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
#include <utility>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "core/fit/multilevel_steps.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::fit {

namespace {

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
  using namespace multilevel;
  checkOptions(input.size(), options);
  const unsigned threads = resolveThreads(options.threads);
  const DataExtent extent = measureData(input, options.weights, threads);
  Point2 origin{extent.xmin, extent.ymin};
  double size = std::max(extent.xmax - extent.xmin, extent.ymax - extent.ymin);
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
  const double zShift = 0.5 * (extent.zmin + extent.zmax);
  const int gridLevels = options.maxLevel + 1;
  BinaryTriangulation mesh(origin, size, gridLevels);
  const SortedData data = sortAlongMortonCurve(input, options.weights, mesh, zShift, threads);
  const std::vector<FixedVertex> fixed = activateFixedPoints(mesh, options.fixed, zShift);

  const auto& crit = options.criteria;
  const double epsilon = crit.errorAbsolute ? *crit.errorAbsolute
                         : crit.errorPercent ? *crit.errorPercent / 100.0 * (extent.zmax - extent.zmin)
                                             : 0.0;

  // Per point: the index of its triangle in the current triangulation. Per
  // triangle of the previous level (previousTris): its merged moments. Level
  // 1 locates every point below the four triangles around the centre.
  std::vector<std::uint32_t> triOf(data.points.size(), 0);
  std::vector<BinaryTriangle> previousTris;
  {
    const auto roots = mesh.rootTriangles();
    previousTris.assign(roots.begin(), roots.end());
  }
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

    auto tris = mesh.triangles();
    st.triangles = tris.size();
    std::vector<Triangle> triVerts(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
      triVerts[t] = {mesh.vertexId(tris[t].l), mesh.vertexId(tris[t].r), mesh.vertexId(tris[t].a)};
    std::vector<Point2> positions(nv);
    for (std::size_t i = 0; i < nv; ++i) positions[i] = mesh.position(keys[i]);

    KeyIndexMap triIndex;
    triIndex.reserve(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
      triIndex.insert(tris[t].path, static_cast<std::uint32_t>(t));
    const std::vector<TriangleMoments>& moments =
        levelMoments(mesh, level, data, std::move(tris), triIndex, triVerts, positions, triOf,
                     previousTris, previousMoments, threads);
    triIndex = KeyIndexMap();  // served the moments alone: let go before the solve
    // The smoothing matrix after the moments: its construction then meets
    // neither the triangles' index nor the previous level's moments, which
    // are let go by now (lower peak memory; it depends on neither).
    std::optional<SparseMatrix> energy;
    if (options.smoothing != Smoothing::None) {
      SparseMatrix built = smoothingMatrix(options.smoothing, positions, triVerts);
      energy.emplace().swap(built);  // swapped, not copied (see assembleSystem)
    }
    PenalizedSystem sys = assembleSystem(nv, triVerts, moments, std::move(energy),
                                         options.lambdaFactor, options.lambdaAbsolute);
    st.lambda = sys.lambda;
    SparseMatrix& a = sys.a;
    Vector& rhs = sys.b;
    applyFixedVertices(a, rhs, fixed);
    st.solver = level <= options.directLevels ? SolverKind::Direct : options.solver;
    const SolveReport report = solveSystem(a, rhs, coefficients, st.solver, options.control);
    st.iterations = report.iterations;
    st.relativeResidual = report.relativeResidual;
    SparseMatrix().swap(a);  // solved: let go before the errors are measured
    Vector().swap(rhs);

    const LevelErrors errors = levelErrors(mesh, data, triOf, triVerts, positions, coefficients,
                                           level, gridLevels, threads);
    st.maxError = errors.maxError;
    st.rmsError = errors.rmsError;
    const std::vector<std::uint64_t> refine =
        cellsToRefine(crit, epsilon, errors, mesh, triVerts, positions, coefficients, level, gridLevels);
    st.cellsFailing = refine.size();
    const bool last = refine.empty() || level >= options.maxLevel;
    if (!last) {
      for (std::uint64_t c : refine) {
        mesh.activate(mesh.cellCentre(level, geometry::compactBits(c), geometry::compactBits(c >> 1)));
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
