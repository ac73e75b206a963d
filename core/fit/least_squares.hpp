// Penalized, weighted and constrained least squares over a triangulation
// (Hjelle & Dæhlen ch. 8). The surface is f = Σ c_i N_i with the piecewise
// linear hat functions N_i of the triangulation (8.1); the coefficients c solve
//   (BᵀWB + λE) c = BᵀWz                                        (8.13, 8.18, 8.8)
// with vertices of prescribed z moved to the right-hand side (8.9).
//
// Works on any triangulation: the caller gives vertex positions (x, y in any
// consistent unit), CCW triangles and, per data point, the triangle it lies in
// with its barycentric coordinates. Nothing here locates points.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Sparse>

#include "core/base/point.hpp"

namespace tinsmith::fit {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using Vector = Eigen::VectorXd;
using Triangle = std::array<std::uint32_t, 3>;

/// The smoothing (roughness) term E of (8.18), section 8.6.
enum class Smoothing {
  None,              ///< plain least squares: unique only when every vertex carries data
  Membrane,          ///< membrane energy, E_ij = Σ_t (η_i η_j + μ_i μ_j) / 4A_t
  Umbrella,          ///< umbrella operator M, E = MᵀM
  UmbrellaWeighted,  ///< umbrella operator with weights 1/|v_l − v_k|
  ThinPlate,         ///< discrete thin-plate energy over interior edges (8.27)
};

/// One data point as seen by a triangulation: the triangle containing it,
/// its barycentric coordinates with respect to that triangle's vertices (in
/// the triangle's vertex order), the data value and its weight w_k (8.8).
struct Sample {
  std::uint32_t triangle = 0;
  std::array<double, 3> barycentric{};
  double z = 0.0;
  double weight = 1.0;
};

/// Per-triangle sums from which BᵀWB and BᵀWz are scattered: the 3×3 moment
/// matrix Σ w b bᵀ (upper triangle: 00, 01, 02, 11, 12, 22) and Σ w z b.
/// Accumulating per triangle first keeps assembly linear in the points with
/// no per-point sparse-matrix access, and lets threads work on separate copies.
struct TriangleMoments {
  std::array<double, 6> bb{};
  std::array<double, 3> bz{};
  void add(const std::array<double, 3>& b, double z, double w) {
    const double w0 = w * b[0], w1 = w * b[1], w2 = w * b[2];
    bb[0] += w0 * b[0];
    bb[1] += w0 * b[1];
    bb[2] += w0 * b[2];
    bb[3] += w1 * b[1];
    bb[4] += w1 * b[2];
    bb[5] += w2 * b[2];
    bz[0] += w0 * z;
    bz[1] += w1 * z;
    bz[2] += w2 * z;
  }
  void merge(const TriangleMoments& other);
};

/// The unpenalized normal equations (8.13) / weighted (8.8).
struct NormalEquations {
  SparseMatrix btb;  ///< BᵀWB, n × n, symmetric
  Vector btz;        ///< BᵀWz
};

/// Edges of a triangulation with their left and right opposite vertices.
/// For an interior edge (s, t): triangle (s, t, left) is CCW and (t, s, right)
/// is CCW. Boundary edges have right = kNone (their one triangle is on the left).
struct MeshEdge {
  static constexpr std::uint32_t kNone = 0xffffffffu;
  std::uint32_t s = 0;
  std::uint32_t t = 0;
  std::uint32_t left = kNone;
  std::uint32_t right = kNone;
};

/// Every edge once, from CCW triangles. Throws geometryError when an edge has
/// more than two triangles or two triangles with the same orientation.
std::vector<MeshEdge> meshEdges(std::size_t vertexCount, std::span<const Triangle> triangles);

/// Each triangle's moments (its 3×3 block of BᵀWB and 3 entries of BᵀWz)
/// from the samples inside it. Throws inputError for a sample whose triangle
/// index is out of range.
std::vector<TriangleMoments> triangleMoments(std::size_t vertexCount, std::span<const Triangle> triangles,
                                             std::span<const Sample> samples);

/// Assembles BᵀWB and BᵀWz from samples (8.13, 8.8). Throws inputError for a
/// sample whose triangle index is out of range.
NormalEquations assembleNormalEquations(std::size_t vertexCount, std::span<const Triangle> triangles,
                                        std::span<const Sample> samples);

/// Scatters per-triangle moments (one per triangle) into the normal equations.
NormalEquations scatterMoments(std::size_t vertexCount, std::span<const Triangle> triangles,
                               std::span<const TriangleMoments> moments);

/// BᵀWB + λE assembled straight into E's sparsity pattern (which holds every
/// vertex pair of a triangle for the membrane, umbrella and thin-plate terms
/// on meshes with an interior edge), without the triplet list of
/// scatterMoments. λ = lambdaAbsolute if given, else lambdaFactor · λ_d.
struct PenalizedSystem {
  SparseMatrix a;
  Vector b;
  double lambda = 0.0;
  double lambdaDefault = 0.0;
};
PenalizedSystem assemblePenalized(std::span<const Triangle> triangles, std::span<const TriangleMoments> moments,
                                  const SparseMatrix& energy, double lambdaFactor,
                                  std::optional<double> lambdaAbsolute);
/// The system a fit solves: assemblePenalized with `energy` (freed on
/// return, before the solve), or without smoothing (no energy) the moments
/// alone, scatterMoments, with λ 0. Eigen 3.4's SparseMatrix has no move
/// constructor or assignment (std::move copies): `energy` is taken by
/// reference and reset here, and the matrices are handed on by swap, so
/// that no matrix of the system is held twice.
PenalizedSystem assembleSystem(std::size_t vertexCount, std::span<const Triangle> triangles,
                               std::span<const TriangleMoments> moments,
                               std::optional<SparseMatrix>&& energy, double lambdaFactor,
                               std::optional<double> lambdaAbsolute);

/// Membrane energy matrix (section 8.6): symmetric PSD, annihilates constants.
SparseMatrix membraneEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles);

/// Umbrella-operator energy E = MᵀM; `weighted` uses ω_kl = 1/|v_l − v_k|.
/// Annihilates constants (not linear functions in general).
SparseMatrix umbrellaEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles,
                            bool weighted);

/// Discrete thin-plate energy (8.27): E = Σ_e L_e β βᵀ over interior edges, with
/// the β's of the jump in normal derivative across e. Annihilates linear functions.
SparseMatrix thinPlateEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles);

/// The smoothing matrix for `kind` (empty n × n for Smoothing::None).
SparseMatrix smoothingMatrix(Smoothing kind, std::span<const Point2> vertices,
                             std::span<const Triangle> triangles);

/// T_e f = Σ β_i c_i for an interior edge: the jump of the normal derivative.
/// The β's are in the order (s, t, left, right).
std::array<double, 4> thinPlateBetas(const Point2& s, const Point2& t, const Point2& l, const Point2& r);

/// λ_d = ‖BᵀB‖_F / ‖E‖_F (8.19); 0 when E is zero.
double defaultLambda(const SparseMatrix& btb, const SparseMatrix& energy);

/// A vertex whose z is prescribed (8.9).
struct FixedVertex {
  std::uint32_t vertex = 0;
  double z = 0.0;
};

/// Applies the constraints (8.9) to A c = b in place: the known c_k move to the
/// right side (b_i −= A_ik z_k) and row/column k become the identity with
/// b_k = z_k, so the system stays symmetric and its free part is A_ff.
void applyFixedVertices(SparseMatrix& a, Vector& b, std::span<const FixedVertex> fixed);

enum class SolverKind { Direct, GaussSeidel, ConjugateGradient };

/// Stopping rule of the iterative solvers (section 8.10): stop when the relative
/// improvement ‖c_new − c_old‖₂ / ‖c_new‖₂ falls below `relativeImprovement`
/// and the relative residual ‖b − Ac‖₂ / ‖b‖₂ below `relativeResidual`, or after
/// `maxIterations`.
struct IterationControl {
  double relativeImprovement = 1e-5;
  double relativeResidual = 1e-3;
  int maxIterations = 2000;
};

struct SolveReport {
  int iterations = 0;         ///< 0 for the direct solver
  double relativeResidual = 0.0;
  bool converged = true;
};

/// Solves A c = b for symmetric positive definite A; `c` is the initial guess
/// for the iterative solvers (nested iteration) and the result. Throws
/// geometryError when the direct factorization finds A singular.
SolveReport solveSystem(const SparseMatrix& a, const Vector& b, Vector& c, SolverKind solver,
                        const IterationControl& control = {});

/// Everything for one penalized least-squares fit over a fixed triangulation.
struct LeastSquaresOptions {
  Smoothing smoothing = Smoothing::ThinPlate;
  double lambdaFactor = 1.0;            ///< λ = lambdaFactor · λ_d ...
  std::optional<double> lambdaAbsolute; ///< ... unless an absolute λ is given
  std::vector<FixedVertex> fixed;
  SolverKind solver = SolverKind::Direct;
  IterationControl control;
};

struct LeastSquaresResult {
  Vector coefficients;  ///< c_i = f(v_i)
  double lambda = 0.0;
  double lambdaDefault = 0.0;
  SolveReport report;
};

/// Fits f over the triangulation to the samples. `initial`, if non-empty, is the
/// starting vector of an iterative solver. Throws geometryError when the system
/// is singular (no smoothing and a vertex without data).
LeastSquaresResult fitLeastSquares(std::span<const Point2> vertices, std::span<const Triangle> triangles,
                                   std::span<const Sample> samples, const LeastSquaresOptions& options,
                                   const Vector& initial = {});

/// Barycentric coordinates of p in triangle (a, b, c) (any orientation).
std::array<double, 3> barycentric(const Point2& p, const Point2& a, const Point2& b, const Point2& c);

}  // namespace tinsmith::fit
