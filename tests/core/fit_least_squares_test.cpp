// Penalized, weighted and constrained least squares over a general
// triangulation (core/fit/least_squares.hpp; Hjelle & Dæhlen 8.2–8.9).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "core/base/error.hpp"
#include "core/fit/least_squares.hpp"
#include "tests/core/fit_test_data.hpp"

namespace tinsmith::fit {
namespace {

using testing::jitteredMesh;
using testing::locateBruteForce;
using testing::Rng;
using testing::SmallMesh;

constexpr Smoothing kAllSmoothing[] = {Smoothing::Membrane, Smoothing::Umbrella, Smoothing::UmbrellaWeighted,
                                       Smoothing::ThinPlate};

std::vector<Sample> samplesOf(const SmallMesh& m, std::size_t count, std::uint64_t seed, double (*f)(double, double),
                              double xmax = 1.0, double ymax = 1.0) {
  Rng rng(seed);
  std::vector<Sample> s;
  for (std::size_t k = 0; k < count; ++k) {
    const double x = rng.uniform() * xmax, y = rng.uniform() * ymax;
    s.push_back(locateBruteForce(m, {x, y, f(x, y)}));
    EXPECT_NE(s.back().triangle, 0xffffffffu);
  }
  return s;
}

double linearFunction(double x, double y) { return 2.0 + 3.0 * x - 5.0 * y; }
double constantFunction(double, double) { return 7.25; }
double wavyFunction(double x, double y) { return std::sin(4 * x) * std::cos(3 * y) + x * x; }

Eigen::MatrixXd dense(const SparseMatrix& m) { return Eigen::MatrixXd(m); }

double minEigenvalue(const Eigen::MatrixXd& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
  return es.eigenvalues().minCoeff();
}

TEST(FitLeastSquares, ThinPlateBetasSumToZeroAndKillLinearFunctions) {
  const Point2 s{0, 0}, t{1, 0.2}, l{0.3, 0.9}, r{0.6, -0.7};
  const auto b = thinPlateBetas(s, t, l, r);
  EXPECT_NEAR(b[0] + b[1] + b[2] + b[3], 0.0, 1e-12);
  auto lin = [](const Point2& p) { return 1.5 - 2.0 * p.x + 0.7 * p.y; };
  EXPECT_NEAR(b[0] * lin(s) + b[1] * lin(t) + b[2] * lin(l) + b[3] * lin(r), 0.0, 1e-12);
  // A crease along s–t: z = max(0, distance to the right of the edge line) has
  // a normal-derivative jump of 1 (in absolute value).
  auto crease = [&](const Point2& p) {
    const double ex = t.x - s.x, ey = t.y - s.y, len = std::hypot(ex, ey);
    const double right = ((p.x - s.x) * ey - (p.y - s.y) * ex) / len;
    return std::max(0.0, right);
  };
  EXPECT_NEAR(std::abs(b[0] * crease(s) + b[1] * crease(t) + b[2] * crease(l) + b[3] * crease(r)), 1.0, 1e-12);
}

TEST(FitLeastSquares, SmoothingMatricesAreSymmetricPsdAndAnnihilateWhatTheyMust) {
  const SmallMesh m = jitteredMesh(5, 11);
  const auto n = static_cast<Eigen::Index>(m.vertices.size());
  Eigen::VectorXd ones = Eigen::VectorXd::Ones(n), xs(n), ys(n);
  for (Eigen::Index i = 0; i < n; ++i) xs[i] = m.vertices[static_cast<std::size_t>(i)].x, ys[i] = m.vertices[static_cast<std::size_t>(i)].y;
  for (Smoothing kind : kAllSmoothing) {
    SCOPED_TRACE(static_cast<int>(kind));
    const Eigen::MatrixXd e = dense(smoothingMatrix(kind, m.vertices, m.triangles));
    const double scale = e.norm();
    ASSERT_GT(scale, 0.0);
    EXPECT_LE((e - e.transpose()).norm(), 1e-12 * scale);
    EXPECT_GE(minEigenvalue(e), -1e-10 * scale);
    EXPECT_LE((e * ones).norm(), 1e-12 * scale);  // constants
    if (kind == Smoothing::ThinPlate) {
      EXPECT_LE((e * xs).norm(), 1e-12 * scale);  // linear functions
      EXPECT_LE((e * ys).norm(), 1e-12 * scale);
    } else {
      // Membrane and umbrella penalize slope: linear functions are not in their null space.
      EXPECT_GT(xs.dot(e * xs), 1e-6 * scale);
    }
  }
}

TEST(FitLeastSquares, ThinPlateNullSpaceIsExactlyTheLinearFunctions) {
  const SmallMesh m = jitteredMesh(4, 5);
  const Eigen::MatrixXd e = dense(thinPlateEnergy(m.vertices, m.triangles));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(e);
  int zero = 0;
  for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i) zero += es.eigenvalues()[i] < 1e-9 * e.norm() ? 1 : 0;
  EXPECT_EQ(zero, 3);
}

TEST(FitLeastSquares, ThinPlateEnergyIsDTransposeDOfTheEdgeStencils) {
  // D has a row √L_e β_e per interior edge on its stencil {s, t, l, r};
  // E must be DᵀD, entry for entry, with an entry exactly where two vertices
  // share a stencil (a jittered mesh with a hole: boundary edges inside).
  SmallMesh m = jitteredMesh(7, 9);
  std::erase_if(m.triangles, [&](const Triangle& t) {
    const Point2& a = m.vertices[t[0]];
    return std::abs(a.x - 0.5) < 0.2 && std::abs(a.y - 0.5) < 0.2;
  });
  ASSERT_LT(m.triangles.size(), jitteredMesh(7, 9).triangles.size());
  const auto edges = meshEdges(m.vertices.size(), m.triangles);
  const auto n = static_cast<Eigen::Index>(m.vertices.size());
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(edges.size()), n);
  Eigen::MatrixXi shared = Eigen::MatrixXi::Zero(n, n);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const MeshEdge& e = edges[k];
    if (e.right == MeshEdge::kNone) continue;
    const auto beta =
        thinPlateBetas(m.vertices[e.s], m.vertices[e.t], m.vertices[e.left], m.vertices[e.right]);
    const double w = std::sqrt(
        std::hypot(m.vertices[e.t].x - m.vertices[e.s].x, m.vertices[e.t].y - m.vertices[e.s].y));
    const std::array<std::uint32_t, 4> v{e.s, e.t, e.left, e.right};
    for (int a = 0; a < 4; ++a) {
      d(static_cast<Eigen::Index>(k), v[a]) = w * beta[a];
      for (int b = 0; b < 4; ++b) shared(v[a], v[b]) = 1;
    }
  }
  const SparseMatrix e = thinPlateEnergy(m.vertices, m.triangles);
  const Eigen::MatrixXd expected = d.transpose() * d;
  EXPECT_LE((dense(e) - expected).norm(), 1e-12 * expected.norm());
  EXPECT_EQ(e.nonZeros(), shared.sum());
  for (Eigen::Index c = 0; c < e.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(e, c); it; ++it) EXPECT_EQ(shared(it.row(), it.col()), 1);
  EXPECT_TRUE(e.isCompressed());
}

TEST(FitLeastSquares, ConstantDataIsReproducedForEverySmoothingAndLambda) {
  const SmallMesh m = jitteredMesh(6, 3);
  const auto samples = samplesOf(m, 60, 8, constantFunction, 0.5, 0.5);  // data in one corner only
  for (Smoothing kind : kAllSmoothing) {
    for (double factor : {1e-6, 1.0, 1e3, 1e7}) {
      LeastSquaresOptions opt;
      opt.smoothing = kind;
      opt.lambdaFactor = factor;
      const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
      // Rounding grows with the condition number, which grows with λ.
      EXPECT_LE((res.coefficients.array() - 7.25).abs().maxCoeff(), 1e-11 * std::max(1.0, factor))
          << static_cast<int>(kind) << " " << factor;
    }
  }
}

TEST(FitLeastSquares, LinearDataIsReproducedByThinPlateForAnyLambda) {
  const SmallMesh m = jitteredMesh(6, 4);
  const auto samples = samplesOf(m, 80, 9, linearFunction, 0.6, 0.8);  // empty cells elsewhere
  for (double factor : {1e-6, 1.0, 600.0, 1e6}) {
    LeastSquaresOptions opt;
    opt.smoothing = Smoothing::ThinPlate;
    opt.lambdaFactor = factor;
    const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      EXPECT_NEAR(res.coefficients[static_cast<Eigen::Index>(i)], linearFunction(m.vertices[i].x, m.vertices[i].y), 1e-9)
          << factor;
    }
  }
  // Absolute λ as well.
  LeastSquaresOptions opt;
  opt.lambdaAbsolute = 123.0;
  const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  EXPECT_EQ(res.lambda, 123.0);
  EXPECT_NEAR(res.coefficients[0], linearFunction(0, 0), 1e-9);
}

TEST(FitLeastSquares, LinearDataIsReproducedByEverySmoothingWhenEveryVertexCarriesData) {
  // Membrane and umbrella terms do not vanish on linear functions, so they
  // reproduce linear data only in the limit λ → 0; with data at every vertex
  // and small λ they do, to within O(λ).
  const SmallMesh m = jitteredMesh(5, 6);
  std::vector<Sample> samples = samplesOf(m, 100, 10, linearFunction);
  for (const auto& v : m.vertices) samples.push_back(locateBruteForce(m, {v.x, v.y, linearFunction(v.x, v.y)}));
  for (Smoothing kind : kAllSmoothing) {
    LeastSquaresOptions opt;
    opt.smoothing = kind;
    opt.lambdaFactor = 1e-9;
    const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      EXPECT_NEAR(res.coefficients[static_cast<Eigen::Index>(i)], linearFunction(m.vertices[i].x, m.vertices[i].y), 1e-7);
    }
  }
}

TEST(FitLeastSquares, PlainLeastSquaresReproducesLinearDataExactly) {
  const SmallMesh m = jitteredMesh(4, 7);
  std::vector<Sample> samples = samplesOf(m, 200, 12, linearFunction);
  for (const auto& v : m.vertices) samples.push_back(locateBruteForce(m, {v.x, v.y, linearFunction(v.x, v.y)}));
  LeastSquaresOptions opt;
  opt.smoothing = Smoothing::None;
  const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    EXPECT_NEAR(res.coefficients[static_cast<Eigen::Index>(i)], linearFunction(m.vertices[i].x, m.vertices[i].y), 1e-10);
  }
}

TEST(FitLeastSquares, LambdaToZeroWithDataAtEveryVertexInterpolates) {
  const SmallMesh m = jitteredMesh(6, 13);
  std::vector<Sample> samples;
  for (const auto& v : m.vertices) samples.push_back(locateBruteForce(m, {v.x, v.y, wavyFunction(v.x, v.y)}));
  for (Smoothing kind : kAllSmoothing) {
    LeastSquaresOptions opt;
    opt.smoothing = kind;
    opt.lambdaFactor = 1e-10;
    const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      EXPECT_NEAR(res.coefficients[static_cast<Eigen::Index>(i)], wavyFunction(m.vertices[i].x, m.vertices[i].y), 1e-7);
    }
  }
}

TEST(FitLeastSquares, PenalizedSystemIsPositiveDefiniteWithEmptyCells) {
  const SmallMesh m = jitteredMesh(6, 14);
  const auto samples = samplesOf(m, 30, 15, wavyFunction, 0.3, 0.3);  // most triangles empty
  const NormalEquations eq = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  EXPECT_LE(minEigenvalue(dense(eq.btb)), 1e-12);  // B^T B alone is singular here
  for (Smoothing kind : kAllSmoothing) {
    const SparseMatrix e = smoothingMatrix(kind, m.vertices, m.triangles);
    const double lambda = defaultLambda(eq.btb, e);
    ASSERT_GT(lambda, 0.0);
    const Eigen::MatrixXd a = dense(eq.btb) + lambda * dense(e);
    EXPECT_GT(minEigenvalue(a), 1e-12 * a.norm()) << static_cast<int>(kind);
  }
  LeastSquaresOptions opt;
  opt.smoothing = Smoothing::None;
  EXPECT_THROW(fitLeastSquares(m.vertices, m.triangles, samples, opt), Error);
}

TEST(FitLeastSquares, DefaultLambdaIsTheFrobeniusRatio) {
  const SmallMesh m = jitteredMesh(3, 1);
  const auto samples = samplesOf(m, 50, 2, wavyFunction);
  const NormalEquations eq = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  const SparseMatrix e = thinPlateEnergy(m.vertices, m.triangles);
  EXPECT_NEAR(defaultLambda(eq.btb, e), dense(eq.btb).norm() / dense(e).norm(), 1e-12);
  LeastSquaresOptions opt;
  opt.lambdaFactor = 3.0;
  const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  EXPECT_NEAR(res.lambda, 3.0 * res.lambdaDefault, 1e-15);
}

TEST(FitLeastSquares, NormalEquationsMatchDenseB) {
  const SmallMesh m = jitteredMesh(3, 2);
  const auto samples = samplesOf(m, 40, 3, wavyFunction);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(samples.size()), static_cast<Eigen::Index>(m.vertices.size()));
  Eigen::VectorXd z(static_cast<Eigen::Index>(samples.size()));
  for (std::size_t k = 0; k < samples.size(); ++k) {
    for (int c = 0; c < 3; ++c) b(static_cast<Eigen::Index>(k), m.triangles[samples[k].triangle][c]) = samples[k].barycentric[c];
    z[static_cast<Eigen::Index>(k)] = samples[k].z;
  }
  const NormalEquations eq = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  EXPECT_LE((dense(eq.btb) - b.transpose() * b).norm(), 1e-12);
  EXPECT_LE((eq.btz - b.transpose() * z).norm(), 1e-12);
  // Sparsity: only vertex pairs sharing a triangle.
  const auto edges = meshEdges(m.vertices.size(), m.triangles);
  EXPECT_LE(static_cast<std::size_t>(eq.btb.nonZeros()), m.vertices.size() + 2 * edges.size());
}

TEST(FitLeastSquares, WeightTwoEqualsThePointTwice) {
  const SmallMesh m = jitteredMesh(3, 4);
  auto samples = samplesOf(m, 30, 5, wavyFunction);
  auto doubled = samples;
  doubled.push_back(samples[7]);
  samples[7].weight = 2.0;
  const auto a = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  const auto b = assembleNormalEquations(m.vertices.size(), m.triangles, doubled);
  EXPECT_LE((dense(a.btb) - dense(b.btb)).norm(), 1e-13);
  EXPECT_LE((a.btz - b.btz).norm(), 1e-13);
  // A heavy weight pulls the surface through its point.
  samples[7].weight = 1e8;
  LeastSquaresOptions opt;
  const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  const auto& tri = m.triangles[samples[7].triangle];
  double f = 0;
  for (int c = 0; c < 3; ++c) f += samples[7].barycentric[c] * res.coefficients[tri[c]];
  EXPECT_NEAR(f, samples[7].z, 1e-5);
}

TEST(FitLeastSquares, FixedVerticesKeepTheirZAndTheRestMinimizes) {
  const SmallMesh m = jitteredMesh(5, 6);
  const auto samples = samplesOf(m, 120, 7, wavyFunction);
  LeastSquaresOptions opt;
  opt.fixed = {{0, 10.0}, {7, -3.0}, {20, 2.5}};
  const auto res = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  EXPECT_EQ(res.coefficients[0], 10.0);
  EXPECT_EQ(res.coefficients[7], -3.0);
  EXPECT_EQ(res.coefficients[20], 2.5);
  // Reference: minimize the full functional over the free coefficients (dense).
  const auto eq = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  const SparseMatrix e = thinPlateEnergy(m.vertices, m.triangles);
  const Eigen::MatrixXd a = dense(eq.btb) + res.lambda * dense(e);
  std::vector<int> freeIdx;
  for (int i = 0; i < static_cast<int>(m.vertices.size()); ++i) {
    if (i != 0 && i != 7 && i != 20) freeIdx.push_back(i);
  }
  const auto nf = static_cast<Eigen::Index>(freeIdx.size());
  Eigen::MatrixXd aff(nf, nf);
  Eigen::VectorXd rhs(nf);
  for (Eigen::Index r = 0; r < nf; ++r) {
    rhs[r] = eq.btz[freeIdx[r]] - a(freeIdx[r], 0) * 10.0 - a(freeIdx[r], 7) * -3.0 - a(freeIdx[r], 20) * 2.5;
    for (Eigen::Index c = 0; c < nf; ++c) aff(r, c) = a(freeIdx[r], freeIdx[c]);
  }
  const Eigen::VectorXd cf = aff.ldlt().solve(rhs);
  for (Eigen::Index r = 0; r < nf; ++r) EXPECT_NEAR(res.coefficients[freeIdx[r]], cf[r], 1e-9);
  SparseMatrix small(2, 2);
  Vector rhs2 = Vector::Zero(2);
  const std::vector<FixedVertex> outside{{5, 1.0}};
  EXPECT_THROW(applyFixedVertices(small, rhs2, outside), Error);
}

TEST(FitLeastSquares, IterativeSolversAgreeWithTheDirectOne) {
  const SmallMesh m = jitteredMesh(8, 8);
  const auto samples = samplesOf(m, 400, 9, wavyFunction);
  LeastSquaresOptions opt;
  opt.solver = SolverKind::Direct;
  const auto direct = fitLeastSquares(m.vertices, m.triangles, samples, opt);
  for (SolverKind s : {SolverKind::GaussSeidel, SolverKind::ConjugateGradient}) {
    opt.solver = s;
    opt.control.relativeImprovement = 1e-12;
    opt.control.relativeResidual = 1e-10;
    opt.control.maxIterations = 100000;
    const auto it = fitLeastSquares(m.vertices, m.triangles, samples, opt);
    EXPECT_GT(it.report.iterations, 0);
    EXPECT_LE((it.coefficients - direct.coefficients).cwiseAbs().maxCoeff(), 1e-6) << static_cast<int>(s);
  }
}

TEST(FitLeastSquares, BadInputIsReported) {
  const SmallMesh m = jitteredMesh(2, 1);
  std::vector<Sample> samples{{99, {1, 0, 0}, 1.0, 1.0}};
  EXPECT_THROW(assembleNormalEquations(m.vertices.size(), m.triangles, samples), Error);
  std::vector<Triangle> bad{{0, 1, 100}};
  EXPECT_THROW(meshEdges(m.vertices.size(), bad), Error);
  std::vector<Triangle> same{{0, 1, 3}, {0, 1, 4}};  // edge (0,1) twice in the same direction
  EXPECT_THROW(meshEdges(m.vertices.size(), same), Error);
}

}  // namespace
}  // namespace tinsmith::fit

namespace tinsmith::fit {
namespace {

TEST(FitLeastSquares, PenalizedAssemblyInTheEnergyPatternMatchesTheSum) {
  const SmallMesh m = jitteredMesh(5, 21);
  const auto samples = samplesOf(m, 90, 22, wavyFunction, 0.7, 0.9);
  std::vector<TriangleMoments> moments(m.triangles.size());
  for (const auto& s : samples) moments[s.triangle].add(s.barycentric, s.z, s.weight);
  const NormalEquations eq = assembleNormalEquations(m.vertices.size(), m.triangles, samples);
  for (Smoothing kind : kAllSmoothing) {
    const SparseMatrix e = smoothingMatrix(kind, m.vertices, m.triangles);
    const PenalizedSystem sys = assemblePenalized(m.triangles, moments, e, 2.5, std::nullopt);
    EXPECT_NEAR(sys.lambdaDefault, defaultLambda(eq.btb, e), 1e-12 * sys.lambdaDefault);
    EXPECT_NEAR(sys.lambda, 2.5 * sys.lambdaDefault, 1e-12 * sys.lambda);
    const Eigen::MatrixXd expected = dense(eq.btb) + sys.lambda * dense(e);
    EXPECT_LE((dense(sys.a) - expected).norm(), 1e-12 * expected.norm()) << static_cast<int>(kind);
    EXPECT_LE((sys.b - eq.btz).norm(), 1e-12);
    // assembleSystem gives the same system and lets the energy go (taken by
    // reference: Eigen 3.4's SparseMatrix has no move, std::move copies).
    std::optional<SparseMatrix> energy;
    energy.emplace(e);
    const PenalizedSystem same = assembleSystem(m.vertices.size(), m.triangles, moments,
                                                std::move(energy), 2.5, std::nullopt);
    EXPECT_FALSE(energy.has_value());
    EXPECT_EQ((dense(same.a) - dense(sys.a)).norm(), 0.0);
    EXPECT_EQ(same.lambda, sys.lambda);
  }
  // Without smoothing: the moments alone, λ 0.
  const PenalizedSystem plain =
      assembleSystem(m.vertices.size(), m.triangles, moments, std::nullopt, 2.5, std::nullopt);
  EXPECT_EQ((dense(plain.a) - dense(eq.btb)).norm(), 0.0);
  EXPECT_EQ(plain.lambda, 0.0);
}

}  // namespace
}  // namespace tinsmith::fit
