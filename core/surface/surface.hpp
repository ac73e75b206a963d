// Queries on a TIN surface: the piecewise linear function over a Mesh
// (book 8.2: evaluation by barycentric coordinates). Works on CDT output and on
// meshes rebuilt from TinData (non-convex, with holes). Points outside every
// triangle give std::nullopt (or NaN in the batched forms). Coordinates are x, y
// in the mesh's CRS (metres); z in metres.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith {

/// Where a point lies: the triangle and its barycentric coordinates
/// (w[i] belongs to corner i; they sum to 1, all ≥ 0 up to rounding).
struct SurfaceLocation {
  TriangleId triangle;
  std::array<double, 3> weights{};
};

/// z, unit upward normal and slope at a point.
struct SurfaceSample {
  double z = 0;
  Point3 normal;            ///< unit, normal.z > 0
  double slope = 0;         ///< |∇z|, rise over run (dimensionless)
  double slopeDegrees = 0;  ///< atan(slope) in degrees
  TriangleId triangle;
};

struct ProfilePoint {
  double distance = 0;  ///< along the polyline from its first vertex, metres
  Point3 point;         ///< x, y on the polyline; z (NaN where outside the TIN)
  bool inside = false;
};

/// A regular grid of sample positions: x = x0 + i·dx, y = y0 + j·dy, i < nx, j < ny.
struct SampleGrid {
  double x0 = 0, y0 = 0, dx = 1, dy = 1;
  std::size_t nx = 0, ny = 0;
};

class Surface {
 public:
  /// Takes the mesh; builds a bucket grid over the triangles for locating.
  explicit Surface(Mesh mesh);
  explicit Surface(const TinData& tin);

  [[nodiscard]] const Mesh& mesh() const { return mesh_; }

  /// The triangle containing p (closed: points on edges and vertices count;
  /// the lowest-id candidate wins, deterministic). `hint`, if valid, is tried
  /// first with a short walk — pass the previous result for coherent queries.
  [[nodiscard]] std::optional<SurfaceLocation> locate(Point2 p, TriangleId hint = {}) const;
  /// Barycentric (linear) z at p.
  [[nodiscard]] std::optional<double> z(Point2 p) const;
  /// z, normal and slope at p (the containing triangle's plane).
  [[nodiscard]] std::optional<SurfaceSample> sample(Point2 p) const;

  /// z for many points, NaN outside; reuses each location as the next hint,
  /// so ordered queries cost about a walk step each.
  [[nodiscard]] std::vector<double> zMany(std::span<const Point2> points) const;
  /// z on a regular grid, row-major (j outer, i inner), NaN outside.
  [[nodiscard]] std::vector<double> zGrid(const SampleGrid& grid) const;

  /// Profile along a polyline: its vertices plus every crossing of a mesh
  /// edge, ordered by distance (duplicates within 1e-12 of the length
  /// removed); where the line leaves the TIN (outside, holes) a sample at the
  /// middle of the gap with inside == false and z NaN. Linear in between.
  [[nodiscard]] std::vector<ProfilePoint> profile(std::span<const Point2> polyline) const;

 private:
  [[nodiscard]] bool contains(TriangleId t, Point2 p) const;
  [[nodiscard]] SurfaceLocation weightsIn(TriangleId t, Point2 p) const;
  [[nodiscard]] std::vector<std::uint32_t> trianglesNearSegment(Point2 a, Point2 b) const;

  Mesh mesh_;
  double minX_ = 0, minY_ = 0, cellW_ = 1, cellH_ = 1;
  std::size_t cellsX_ = 0, cellsY_ = 0;
  std::vector<std::uint32_t> cellBegin_;  // CSR over cells
  std::vector<std::uint32_t> cellTriangles_;
};

}  // namespace tinsmith
