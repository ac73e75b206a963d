// The multilevel fitter (core/fit/multilevel_fit.hpp; Algorithm 8.1, 8.10–8.11),
// including the book's Franke example, whose numbers are written next to ours
// in fit_book_table.txt (the test's working directory) and printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "core/base/error.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "core/mesh/validate.hpp"
#include "tests/core/fit_test_data.hpp"

namespace tinsmith::fit {
namespace {

using testing::conformingSquareMesh;
using testing::frankePoints;

std::string meshProblem(const MultilevelFit& fit) {
  const TinData tin = fit.toTinData();
  ValidationOptions vo;
  vo.checkDelaunay = false;  // binary triangulations need not be Delaunay
  const ValidationReport report = validate(tin, vo);
  if (!report.ok || report.boundaryLoops != 1) return "core validator: " + report.summary();
  std::vector<Point2> v;
  for (const auto& p : tin.vertices) v.push_back(p.xy());
  std::vector<Triangle> t(tin.triangles.begin(), tin.triangles.end());
  return conformingSquareMesh(v, t, fit.mesh().origin(), fit.mesh().size());
}

std::string levelTable(const MultilevelFit& fit) {
  std::ostringstream out;
  out << "  level  vertices  triangles  solver        iterations  lambda      max error    rms error    refined cells\n";
  for (const auto& s : fit.levels()) {
    char line[200];
    std::snprintf(line, sizeof line, "  %5d  %8zu  %9zu  %-12s  %10d  %.4e  %.4e  %.4e  %zu\n", s.level, s.vertices,
                  s.triangles, s.solver == SolverKind::Direct ? "direct" : "gauss-seidel", s.iterations, s.lambda,
                  s.maxError, s.rmsError, s.cellsRefined);
    out << line;
  }
  return out.str();
}

void appendToBookTable(const std::string& text) {
  static bool first = true;
  std::ofstream file("fit_book_table.txt", first ? std::ios::trunc : std::ios::app);
  first = false;
  file << text;
  std::printf("%s", text.c_str());
}

MultilevelOptions bookOptions() {
  MultilevelOptions opt;
  opt.smoothing = Smoothing::ThinPlate;
  opt.lambdaFactor = 1.0;
  opt.domainOrigin = Point2{0.0, 0.0};
  opt.domainSize = 1.0;
  opt.threads = 1;
  return opt;
}

TEST(FitMultilevel, FrankeBookExample) {
  // 8.11: 3000 unevenly spread points, count > 2 and error > 0.25 % of the z
  // range, λ = λ_d, thin-plate: the book stops after subdividing Ψ7 (Δ8) with
  // 1476 vertices and 2866 triangles, 9–12 Gauss–Seidel iterations a level.
  const auto pts = frankePoints(3000, 2006);
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorPercent = 0.25;
  opt.criteria.countAbove = 2;
  const MultilevelFit fit = fitMultilevel(pts, opt);
  const auto& last = fit.levels().back();
  // The same run with exact solves at every level: the refinement does not
  // depend on how far Gauss-Seidel is taken.
  MultilevelOptions exact = opt;
  exact.directLevels = 100;
  const MultilevelFit direct = fitMultilevel(pts, exact);
  std::ostringstream out;
  out << "Franke, 3000 points (seed 2006), error 0.25 % of z range and count > 2, lambda = "
         "lambda_d, thin-plate\n"
      << levelTable(fit)
      << "  book: stops after subdividing Psi7 (Delta8): 1476 vertices, 2866 triangles, 9-12 GS "
         "iterations a level\n"
      << "  ours: stops at Delta" << last.level << ": " << last.vertices << " vertices ("
      << std::lround(100.0 * static_cast<double>(last.vertices) / 1476.0) << " % of the book's), "
      << last.triangles << " triangles; direct solves at every level: Delta"
      << direct.levels().back().level << ", " << direct.levels().back().vertices << " vertices\n";
  appendToBookTable(out.str());
  EXPECT_EQ(direct.levels().back().level, last.level);
  EXPECT_NEAR(static_cast<double>(direct.levels().back().vertices), static_cast<double>(last.vertices),
              0.05 * static_cast<double>(last.vertices));

  EXPECT_EQ(meshProblem(fit), "");
  // What the book specifies, not what we get today. The vertex count is
  // reported above (and in the README), not asserted: the book's 1476 comes
  // from its own point set, which is not published, and on ours the same
  // criteria keep about half as many (README, "Multilevel fitting: the book's
  // Franke example").
  // The last triangulation within one level of the book's Δ8, reached because
  // no cell fails any more, not because of the maximum level.
  constexpr int kBookLastLevel = 8;
  EXPECT_GE(last.level, kBookLastLevel - 1);
  EXPECT_LE(last.level, kBookLastLevel + 1);
  EXPECT_FALSE(fit.stoppedAtMaxLevel());
  EXPECT_EQ(last.cellsFailing, 0u);
  // Gauss–Seidel sweeps a level: the book reports 9–12 but not its stopping
  // thresholds (relative improvement, residual), so half its least to twice
  // its most.
  constexpr int kBookFewestSweeps = 9, kBookMostSweeps = 12;
  int gaussSeidelLevels = 0;
  for (const auto& s : fit.levels()) {
    if (s.solver != SolverKind::GaussSeidel) continue;
    ++gaussSeidelLevels;
    EXPECT_GE(s.iterations, kBookFewestSweeps / 2) << "level " << s.level;
    EXPECT_LE(s.iterations, 2 * kBookMostSweeps) << "level " << s.level;
  }
  EXPECT_GT(gaussSeidelLevels, 0);
  // Stopping by the criterion means every cell of the last Ψ_k that holds
  // more than two points has the error within ε at each of them (cells with
  // two or fewer fail the count part and may keep larger errors). Checked
  // with the fit's own evaluation, to rounding.
  double zmin = pts.front().z, zmax = zmin;
  for (const auto& p : pts) zmin = std::min(zmin, p.z), zmax = std::max(zmax, p.z);
  const double epsilon = 0.25 / 100.0 * (zmax - zmin);
  const auto cellsASide = std::size_t{1} << last.level;
  auto cellIndex = [&](double t) {
    return std::min(static_cast<std::size_t>(std::floor(t * static_cast<double>(cellsASide))),
                    cellsASide - 1);
  };
  std::map<std::size_t, std::vector<double>> errorsByCell;
  for (const auto& p : pts) {
    errorsByCell[cellIndex(p.y) * cellsASide + cellIndex(p.x)].push_back(
        std::abs(fit.evaluate(p.xy()) - p.z));
  }
  std::size_t checkedPoints = 0;
  for (const auto& [cell, errors] : errorsByCell) {
    if (errors.size() <= 2) continue;
    for (double e : errors) EXPECT_LE(e, epsilon + 1e-12) << "cell " << cell;
    checkedPoints += errors.size();
  }
  EXPECT_GT(checkedPoints, 0u);
  // The error criterion alone (Algorithm 8.1 as written) stops only when
  // |f(p_i) − z_i| ≤ ε at every data point.
  MultilevelOptions errorOnly = opt;
  errorOnly.criteria.countAbove.reset();
  const MultilevelFit exactAtData = fitMultilevel(pts, errorOnly);
  EXPECT_FALSE(exactAtData.stoppedAtMaxLevel());
  EXPECT_LE(exactAtData.levels().back().maxError, epsilon);
  double worst = 0.0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(exactAtData.evaluate(p.xy()) - p.z));
  EXPECT_LE(worst, epsilon + 1e-12);
  std::ostringstream more;
  more << "  " << checkedPoints << " points lie in cells of Psi" << last.level
       << " with more than two points; all within the tolerance " << epsilon << "\n"
       << "  error criterion alone: stops at Delta" << exactAtData.levels().back().level << ": "
       << exactAtData.levels().back().vertices << " vertices, max error at the data " << worst
       << "\n\n";
  appendToBookTable(more.str());
}

TEST(FitMultilevel, FrankeNoisyExample) {
  // 8.11: normal noise, count criterion only, λ = 600 λ_d: a smooth surface
  // (the book: 73–207 Gauss–Seidel iterations a level, same final level).
  const double sigma = 0.02;
  const auto pts = frankePoints(3000, 2006, sigma);
  MultilevelOptions opt = bookOptions();
  opt.criteria.countAbove = 2;
  opt.lambdaFactor = 600.0;
#if defined(__SANITIZE_ADDRESS__)
  // Hundreds of Gauss-Seidel sweeps a level are slow in a sanitizer build;
  // the direct solver gives the same surface to within the stopping tolerance.
  opt.directLevels = 100;
#endif
  const MultilevelFit fit = fitMultilevel(pts, opt);
  double sumSq = 0.0, sumSqData = 0.0;
  for (const auto& p : pts) {
    const double e = fit.evaluate(p.xy()) - frankeFunction(p.x, p.y);
    sumSq += e * e;
    const double noise = p.z - frankeFunction(p.x, p.y);
    sumSqData += noise * noise;
  }
  const double rmsTrue = std::sqrt(sumSq / static_cast<double>(pts.size()));
  const double rmsNoise = std::sqrt(sumSqData / static_cast<double>(pts.size()));
  const auto& last = fit.levels().back();
  std::ostringstream out;
  out << "Franke with normal noise (sigma " << sigma << "), count > 2 only, lambda = 600 lambda_d, thin-plate\n"
      << levelTable(fit) << "  book: 73-207 GS iterations a level, stops at the same level as the noise-free run (Delta8)\n"
      << "  ours: stops at Delta" << last.level << " with " << last.vertices << " vertices; RMS error against the noise-free"
      << " function " << rmsTrue << " vs noise RMS " << rmsNoise << "\n\n";
  appendToBookTable(out.str());
  EXPECT_EQ(meshProblem(fit), "");
  EXPECT_LT(rmsTrue, rmsNoise);
  EXPECT_LT(rmsTrue, 0.75 * sigma);
  EXPECT_GE(last.level, 7);
  EXPECT_LE(last.level, 9);
}

TEST(FitMultilevel, LinearDataIsFitExactlyAtTheFirstLevel) {
  std::vector<Point3> pts;
  testing::Rng rng(4);
  for (int i = 0; i < 500; ++i) {
    const double x = 10 + 90 * rng.uniform(), y = -5 + 60 * rng.uniform();
    pts.push_back({x, y, 3.0 + 0.5 * x - 0.25 * y});
  }
  MultilevelOptions opt;
  opt.criteria.errorAbsolute = 1e-6;
  for (SolverKind s : {SolverKind::GaussSeidel, SolverKind::ConjugateGradient}) {
    opt.solver = s;
    const MultilevelFit fit = fitMultilevel(pts, opt);
    EXPECT_EQ(fit.levels().size(), 1u);
    EXPECT_LT(fit.levels().back().maxError, 1e-9);
    EXPECT_NEAR(fit.evaluate({50, 20}), 3.0 + 25.0 - 5.0, 1e-9);
  }
}

TEST(FitMultilevel, SolversGiveTheSameSurface) {
  const auto pts = frankePoints(3000, 7);
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorPercent = 0.5;
  opt.criteria.countAbove = 2;
  opt.solver = SolverKind::GaussSeidel;
  const MultilevelFit gs = fitMultilevel(pts, opt);
  opt.solver = SolverKind::ConjugateGradient;
  const MultilevelFit cg = fitMultilevel(pts, opt);
  opt.directLevels = 100;
  const MultilevelFit direct = fitMultilevel(pts, opt);
  // Iterative stopping tolerances allow small differences, which can change
  // a few refinement decisions; the vertex counts stay close.
  const double nd = static_cast<double>(direct.levels().back().vertices);
  EXPECT_NEAR(static_cast<double>(gs.levels().back().vertices), nd, 0.1 * nd);
  EXPECT_NEAR(static_cast<double>(cg.levels().back().vertices), nd, 0.1 * nd);
  EXPECT_LT(gs.levels().back().rmsError, 2 * direct.levels().back().rmsError);
}

TEST(FitMultilevel, HowHighTheTerrainLiesChangesNothing) {
  // The same relief 1 500 m up: every solver must give the same refinement
  // and surface. The solvers' relative stopping tests used to see the height
  // too: conjugate gradients stopped before its first step on the fine levels
  // and refined to the last level, and Gauss-Seidel stopped early.
  const auto base = frankePoints(3000, 7);
  std::vector<Point3> low, high;
  for (const auto& p : base) {
    low.push_back({p.x, p.y, 20.0 * p.z});
    high.push_back({p.x, p.y, 1500.0 + 20.0 * p.z});
  }
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorAbsolute = 0.05;
  opt.criteria.countAbove = 2;
  opt.maxLevel = 12;
  for (SolverKind s : {SolverKind::GaussSeidel, SolverKind::ConjugateGradient}) {
    opt.solver = s;
    const MultilevelFit a = fitMultilevel(low, opt);
    const MultilevelFit b = fitMultilevel(high, opt);
    SCOPED_TRACE(s == SolverKind::GaussSeidel ? "gauss-seidel" : "cg");
    ASSERT_EQ(a.levels().size(), b.levels().size());
    EXPECT_LT(b.levels().back().level, opt.maxLevel);
    for (std::size_t k = 0; k < a.levels().size(); ++k) {
      EXPECT_EQ(a.levels()[k].vertices, b.levels()[k].vertices) << "level " << k + 1;
      EXPECT_NEAR(a.levels()[k].maxError, b.levels()[k].maxError, 1e-6) << "level " << k + 1;
    }
    for (const auto& p : base) EXPECT_NEAR(a.evaluate(p.xy()) + 1500.0, b.evaluate(p.xy()), 1e-6);
  }
}

TEST(FitMultilevel, ThreadsGiveTheSameResult) {
#if defined(__SANITIZE_ADDRESS__)
  const auto pts = frankePoints(20000, 9);  // still above the threading threshold
#else
  const auto pts = frankePoints(40000, 9);
#endif
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorPercent = 0.5;
  opt.criteria.countAbove = 2;
  opt.threads = 1;
  const MultilevelFit one = fitMultilevel(pts, opt);
  opt.threads = 2;
  const MultilevelFit two = fitMultilevel(pts, opt);
  // Bit for bit: the work is split into fixed parts whatever the thread count.
  ASSERT_EQ(one.vertexZ().size(), two.vertexZ().size());
  for (std::size_t i = 0; i < one.vertexZ().size(); ++i) EXPECT_EQ(one.vertexZ()[i], two.vertexZ()[i]);
  opt.threads = 3;
  const MultilevelFit three = fitMultilevel(pts, opt);
  ASSERT_EQ(one.vertexZ().size(), three.vertexZ().size());
  for (std::size_t i = 0; i < one.vertexZ().size(); ++i) EXPECT_EQ(one.vertexZ()[i], three.vertexZ()[i]);
}

TEST(FitMultilevel, FixedVerticesAndWeightsCarryThroughAllLevels) {
  const auto pts = frankePoints(3000, 11);
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorPercent = 0.5;
  opt.criteria.countAbove = 2;
  opt.maxLevel = 7;
  opt.fixed = {{0.5, 0.5, 2.0}, {0.25, 0.75, -1.0}};
  const MultilevelFit fit = fitMultilevel(pts, opt);
  EXPECT_NEAR(fit.evaluate({0.5, 0.5}), 2.0, 1e-12);
  EXPECT_NEAR(fit.evaluate({0.25, 0.75}), -1.0, 1e-12);
  EXPECT_EQ(meshProblem(fit), "");
  EXPECT_LE(fit.levels().back().level, 7);

  // A heavy weight pulls the surface through one point.
  MultilevelOptions w = bookOptions();
  w.criteria.countAbove = 4;
  w.maxLevel = 3;
  std::vector<Point3> data = pts;
  data.push_back({0.3, 0.3, 5.0});
  w.weights.assign(data.size(), 1.0);
  w.weights.back() = 1e9;
  const MultilevelFit weighted = fitMultilevel(data, w);
  EXPECT_NEAR(weighted.evaluate({0.3, 0.3}), 5.0, 1e-3);
}

TEST(FitMultilevel, LastLevelEqualsAFitFromScratchOverTheFinalMesh) {
  // The multilevel fitter keeps the moments of unsplit triangles and locates
  // only the points of split ones; the last level's system must still be the
  // one assembled from scratch over the final triangulation (brute-force
  // location), with and without weights and fixed vertices.
  auto pts = frankePoints(3000, 23);
  pts.push_back({0.0, 0.0, frankeFunction(0, 0)});  // domain exactly [0, 1]²
  pts.push_back({1.0, 1.0, frankeFunction(1, 1)});
  for (int variant = 0; variant < 2; ++variant) {
    MultilevelOptions opt = bookOptions();
    opt.criteria.errorPercent = 0.5;
    opt.criteria.countAbove = 2;
    opt.directLevels = 100;
    opt.maxLevel = 6;
    if (variant == 1) {
      opt.weights.resize(pts.size());
      for (std::size_t i = 0; i < pts.size(); ++i) opt.weights[i] = 0.5 + static_cast<double>(i % 7) * 0.25;
      opt.fixed = {{0.5, 0.5, 1.5}, {0.75, 0.25, 0.1}};
    }
    const MultilevelFit fit = fitMultilevel(pts, opt);
    const TinData tin = fit.toTinData();
    testing::SmallMesh mesh;
    for (const auto& v : tin.vertices) mesh.vertices.push_back(v.xy());
    mesh.triangles.assign(tin.triangles.begin(), tin.triangles.end());
    std::vector<Sample> samples;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      samples.push_back(testing::locateBruteForce(mesh, pts[i], opt.weights.empty() ? 1.0 : opt.weights[i]));
      ASSERT_NE(samples.back().triangle, 0xffffffffu) << "point " << i;
    }
    LeastSquaresOptions ls;
    ls.smoothing = Smoothing::ThinPlate;
    ls.lambdaAbsolute = fit.levels().back().lambda;
    ls.solver = SolverKind::Direct;
    for (const auto& f : opt.fixed) {
      for (std::size_t v = 0; v < tin.vertices.size(); ++v) {
        if (tin.vertices[v].x == f.x && tin.vertices[v].y == f.y) ls.fixed.push_back({static_cast<std::uint32_t>(v), f.z});
      }
    }
    ASSERT_EQ(ls.fixed.size(), opt.fixed.size());
    const LeastSquaresResult scratch = fitLeastSquares(mesh.vertices, mesh.triangles, samples, ls);
    ASSERT_EQ(static_cast<std::size_t>(scratch.coefficients.size()), fit.vertexZ().size());
    for (std::size_t v = 0; v < fit.vertexZ().size(); ++v) {
      EXPECT_NEAR(fit.vertexZ()[v], scratch.coefficients[static_cast<Eigen::Index>(v)], 1e-9) << "vertex " << v;
    }
  }
}

TEST(FitMultilevel, CurvatureCriterionRefinesWhereTheSurfaceBends) {
  const auto pts = frankePoints(3000, 13);
  MultilevelOptions opt = bookOptions();
  opt.criteria.curvatureAbove = 0.02;
  opt.maxLevel = 6;
  const MultilevelFit fit = fitMultilevel(pts, opt);
  EXPECT_GT(fit.levels().size(), 2u);
  EXPECT_EQ(meshProblem(fit), "");
  opt.criteria.countAbove = 2;  // combined
  const MultilevelFit both = fitMultilevel(pts, opt);
  EXPECT_LE(both.levels().back().vertices, fit.levels().back().vertices);
}

TEST(FitMultilevel, EvaluationAndExport) {
  const auto pts = frankePoints(3000, 17);
  MultilevelOptions opt = bookOptions();
  opt.criteria.errorPercent = 1.0;
  const MultilevelFit fit = fitMultilevel(pts, opt);
  const TinData tin = fit.toTinData("EPSG:32619");
  EXPECT_EQ(tin.crs, "EPSG:32619");
  EXPECT_EQ(tin.vertices.size(), fit.levels().back().vertices);
  EXPECT_EQ(tin.triangles.size(), fit.levels().back().triangles);
  for (const auto& v : tin.vertices) EXPECT_NEAR(fit.evaluate(v.xy()), v.z, 1e-12);
  const auto grid = fit.evaluateGrid({0.0, 0.0}, 0.25, 0.25, 6, 5);
  ASSERT_EQ(grid.size(), 30u);
  EXPECT_NEAR(grid[1 * 6 + 2], fit.evaluate({0.5, 0.25}), 1e-15);
  EXPECT_TRUE(std::isnan(grid[5]));  // x = 1.25 is outside the domain
  EXPECT_THROW((void)fit.evaluate({2.0, 0.5}), Error);
}

TEST(FitMultilevel, StoppedAtMaxLevelOfAFitWithoutLevelsIsFalse) {
  // Regression: stoppedAtMaxLevel() read levels().back() of an empty vector.
  // A fit made from its parts with no levels did not stop anywhere.
  const MultilevelFit empty(BinaryTriangulation({0.0, 0.0}, 1.0, 1), std::vector<double>(5, 0.0),
                            {});
  EXPECT_TRUE(empty.levels().empty());
  EXPECT_FALSE(empty.stoppedAtMaxLevel());
  LevelStats failing;
  failing.level = 1;
  failing.cellsFailing = 3;
  EXPECT_TRUE(
      MultilevelFit(BinaryTriangulation({0.0, 0.0}, 1.0, 1), std::vector<double>(5, 0.0), {failing})
          .stoppedAtMaxLevel());
}

TEST(FitMultilevel, BadInputIsReported) {
  MultilevelOptions opt;
  std::vector<Point3> few{{0, 0, 0}, {1, 1, 1}};
  opt.criteria.countAbove = 1;
  EXPECT_THROW(fitMultilevel(few, opt), Error);
  std::vector<Point3> line{{0, 0, 0}, {0, 0, 1}, {0, 0, 2}};
  EXPECT_THROW(fitMultilevel(line, opt), Error);
  std::vector<Point3> nan{{0, 0, 0}, {1, 0, 1}, {0, std::nan(""), 2}};
  EXPECT_THROW(fitMultilevel(nan, opt), Error);
  MultilevelOptions none;
  EXPECT_THROW(fitMultilevel(frankePoints(10, 1), none), Error);
  opt.maxLevel = 40;
  EXPECT_THROW(fitMultilevel(frankePoints(10, 1), opt), Error);
}

}  // namespace
}  // namespace tinsmith::fit
