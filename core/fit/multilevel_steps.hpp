// The steps of the multilevel fit (Algorithm 8.1 over binary triangulations,
// 8.10), one function each, in the order fitMultilevel() runs them: checking
// and measuring the data, sorting it along the Morton curve of the finest
// grid, the fixed vertices, each level's triangle moments (locating only the
// points whose triangle was split), each level's errors per grid cell, and
// choosing the cells to refine. Internal to core/fit.
//
// Determinism: data-parallel steps split the points into kParts fixed parts
// and combine per-part results in part order, so every result is the same bit
// for bit for any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "core/fit/binary_triangulation.hpp"
#include "core/fit/least_squares.hpp"
#include "core/fit/multilevel_fit.hpp"

namespace tinsmith::fit::multilevel {

/// The fixed number of parts the points are split into, whatever the threads.
inline constexpr unsigned kParts = 2;

/// Throws usageError/inputError for options the fit cannot run with (no
/// criterion, a maximum level out of range, a weight count that does not
/// match, fewer than 3 points).
void checkOptions(std::size_t pointCount, const MultilevelOptions& options);

struct DataExtent {
  double xmin = 0, ymin = 0, zmin = 0, xmax = 0, ymax = 0, zmax = 0;
};
/// The data's bounding box. Throws inputError naming the first point with a
/// non-finite coordinate or a weight that is not positive and finite.
DataExtent measureData(std::span<const Point3> input, std::span<const double> weights, unsigned threads);

/// The Morton code of the finest-grid cell holding grid point g (clamped into
/// the grid). The cell of Ψ_k holding it is code >> 2(K − k).
std::uint64_t fineCellCode(const BinaryTriangulation& mesh, Point2 grid);

/// The data in Morton order of the finest grid, z lowered by zShift. A
/// point's fineCellCode is computed again where it is needed (8 bytes a
/// point fewer to hold through the fit).
struct SortedData {
  std::vector<Point3> points;
  std::vector<double> weights;  ///< empty: all 1
};
/// Throws inputError naming the first point outside the mesh's square.
SortedData sortAlongMortonCurve(std::span<const Point3> input, std::span<const double> weights,
                                const BinaryTriangulation& mesh, double zShift, unsigned threads);

/// Activates the vertex of the finest grid nearest each fixed point (8.9) and
/// returns the vertices with their z − zShift (two on one vertex: the later
/// wins). Throws inputError for a fixed point outside the square or not finite.
std::vector<FixedVertex> activateFixedPoints(BinaryTriangulation& mesh, std::span<const Point3> fixed, double zShift);

/// One level's triangle moments (8.13) over the current triangles `tris`
/// (index `triIndex`, vertex ids `triVerts`, vertex positions `positions`).
/// Triangles of the previous level that were not split keep their moments;
/// the points of split ones are located again below their old triangle and
/// accumulated. Updates triOf (each point's current triangle), previousTris
/// (`tris` moves there) and previousMoments to this level's, and returns
/// previousMoments (the moments move there: one copy serves this level's
/// system and the next level). `level` 1 locates from the roots.
const std::vector<TriangleMoments>& levelMoments(
    const BinaryTriangulation& mesh, int level, const SortedData& data,
    std::vector<BinaryTriangle>&& tris, const KeyIndexMap& triIndex,
    std::span<const Triangle> triVerts, std::span<const Point2> positions,
    std::vector<std::uint32_t>& triOf, std::vector<BinaryTriangle>& previousTris,
    std::vector<TriangleMoments>& previousMoments, unsigned threads);

/// A grid cell of the current level with data: its Morton code at that
/// level, its point count and its largest error.
struct CellRecord {
  std::uint64_t cell = 0;
  std::size_t count = 0;
  double maxError = 0.0;
};
struct LevelErrors {
  std::vector<CellRecord> cells;  ///< in Morton order
  double maxError = 0.0, rmsError = 0.0;
};
/// The fit's errors at the data, overall and per cell of Ψ_level.
LevelErrors levelErrors(const BinaryTriangulation& mesh, const SortedData& data,
                        std::span<const std::uint32_t> triOf, std::span<const Triangle> triVerts,
                        std::span<const Point2> positions, const Vector& coefficients, int level,
                        int gridLevels, unsigned threads);

/// The cells of Ψ_level (Morton codes) that fail every criterion that is set
/// (8.1): count, error above epsilon, curvature |T_e f| > τ of an interior
/// edge whose midpoint lies in the cell.
std::vector<std::uint64_t> cellsToRefine(const RefinementCriteria& criteria, double epsilon,
                                         const LevelErrors& errors, const BinaryTriangulation& mesh,
                                         std::span<const Triangle> triVerts, std::span<const Point2> positions,
                                         const Vector& coefficients, int level, int gridLevels);

}  // namespace tinsmith::fit::multilevel
