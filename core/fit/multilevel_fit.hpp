// The multilevel least-squares fitter (Hjelle & Dæhlen, Algorithm 8.1 over
// binary triangulations, 8.10): for k = 1, 2, …, fit f_k over the binary
// triangulation Δ_k by penalized least squares; for every grid cell of Ψ_k that
// fails the refinement criterion activate the cell's centre (a vertex of
// Ψ_{k+1}) with its ancestors, giving Δ_{k+1}; start the next solve from f_k
// (nested iteration). Stops when no cell fails or at the maximum level.
//
// Units: x, y in any projected unit (metres), z in metres; the square domain
// covers the data (or is given). Output z values are the coefficients c_i =
// f(v_i) at the active vertices.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "core/fit/binary_triangulation.hpp"
#include "core/fit/least_squares.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::fit {

/// When a grid cell is refined. Every criterion that is set must hold (the
/// book's Franke example: "more than two points inside the cell and the error
/// for at least one of them greater than the tolerance"). At least one must be set.
struct RefinementCriteria {
  std::optional<double> errorAbsolute;  ///< ε in z units: some point of the cell has |f − z| > ε
  std::optional<double> errorPercent;   ///< ε as a percentage of z_max − z_min of the data
  std::optional<std::size_t> countAbove;  ///< more than n data points in the cell
  std::optional<double> curvatureAbove;   ///< some interior edge with midpoint in the cell has |T_e f| > τ
};

struct MultilevelOptions {
  Smoothing smoothing = Smoothing::ThinPlate;
  double lambdaFactor = 1.0;             ///< λ = lambdaFactor · λ_d at every level ...
  std::optional<double> lambdaAbsolute;  ///< ... unless an absolute λ is given
  RefinementCriteria criteria;
  int maxLevel = 20;          ///< the last Ψ_k whose cells may be refined (1..29)
  int directLevels = 3;       ///< levels 1..directLevels are solved by the direct solver
  SolverKind solver = SolverKind::GaussSeidel;  ///< on the finer levels
  IterationControl control;
  /// The square domain; by default the bounding square of the data (lower-left
  /// corner at (x_min, y_min), side max(x range, y range)).
  std::optional<Point2> domainOrigin;
  std::optional<double> domainSize;
  /// Vertices with prescribed z (8.9): each is snapped to the nearest vertex of
  /// the finest grid Ψ_{maxLevel+1}, which is active from the first level on and
  /// keeps its z at every level. Two constraints on one vertex: the later wins.
  std::vector<Point3> fixed;
  /// Per-point weights w_k (8.8); empty means all 1. Must be > 0.
  std::vector<double> weights;
  /// Worker threads (0: std::thread::hardware_concurrency()). The points are
  /// split into two fixed parts, so at most two are used and the result is the
  /// same bit for bit for any thread count.
  int threads = 0;
  /// Called after each level with a one-line summary (optional).
  std::function<void(const std::string&)> progress;
};

struct LevelStats {
  int level = 0;                  ///< k of Δ_k
  std::size_t vertices = 0;       ///< active vertices
  std::size_t triangles = 0;
  SolverKind solver = SolverKind::Direct;
  int iterations = 0;             ///< iterative solver sweeps (0 when direct)
  double relativeResidual = 0.0;
  double lambda = 0.0;
  double maxError = 0.0;          ///< max |f_k(p_i) − z_i| over the data
  double rmsError = 0.0;
  std::size_t cellsFailing = 0;   ///< cells of Ψ_k that fail the refinement criterion
  std::size_t cellsRefined = 0;   ///< cells of Ψ_k whose centre was activated (0 on the last level)
  double seconds = 0.0;
};

class MultilevelFit {
 public:
  MultilevelFit(BinaryTriangulation mesh, std::vector<double> z, std::vector<LevelStats> levels);

  [[nodiscard]] const BinaryTriangulation& mesh() const { return mesh_; }
  /// z at the active vertices, by dense vertex id.
  [[nodiscard]] std::span<const double> vertexZ() const { return z_; }
  [[nodiscard]] std::span<const LevelStats> levels() const { return levels_; }
  /// Whether the fit stopped at MultilevelOptions::maxLevel with cells that
  /// still fail the criterion (otherwise it stopped because none did). False
  /// for a fit without levels (made from its parts): it stopped nowhere.
  [[nodiscard]] bool stoppedAtMaxLevel() const {
    return !levels_.empty() && levels_.back().cellsFailing > 0;
  }

  /// f(p); throws inputError when p is outside the domain.
  [[nodiscard]] double evaluate(Point2 p) const;
  /// f on a grid of nx × ny points origin + (i·dx, j·dy), row-major (j outer).
  /// Points outside the domain get NaN.
  [[nodiscard]] std::vector<double> evaluateGrid(Point2 origin, double dx, double dy, std::size_t nx,
                                                 std::size_t ny) const;
  /// The final binary triangulation as a TIN (vertex order = dense ids,
  /// triangles CCW, no constrained edges).
  [[nodiscard]] TinData toTinData(const std::string& crs = {}) const;

 private:
  BinaryTriangulation mesh_;
  std::vector<double> z_;
  std::vector<LevelStats> levels_;
};

/// Runs Algorithm 8.1 on the points. Throws inputError for fewer than 3
/// points, non-finite coordinates, a degenerate extent, points outside a given
/// domain, bad weights or missing criteria.
MultilevelFit fitMultilevel(std::span<const Point3> points, const MultilevelOptions& options);

}  // namespace tinsmith::fit
