// The tile pyramid's geometry: a quadtree over the project's square domain,
// the same square the binary triangulation lives on, so tile (z, x, y) is cell
// (x, y) of the grid Ψ_z (2^z cells a side; x grows east, y grows north; the
// root is (0, 0, 0)). Coordinates are the project CRS (metres).
//
// Tile corners are computed from the integer grid alone (origin + i · size /
// 2^z with i an integer), so every tile that shares a corner or a side gets
// the same doubles for it: the first condition of crack-free tiles.
#pragma once

#include <algorithm>
#include <cmath>
#include <compare>
#include <cstdint>
#include <string>

#include "core/base/point.hpp"

namespace tinsmith::tiles {

struct TileId {
  int z = 0;
  std::uint32_t x = 0;
  std::uint32_t y = 0;
  friend auto operator<=>(const TileId&, const TileId&) = default;
  [[nodiscard]] TileId child(int i) const {  ///< i = 0..3: (0,0) (1,0) (0,1) (1,1)
    return {z + 1, 2 * x + static_cast<std::uint32_t>(i & 1),
            2 * y + static_cast<std::uint32_t>(i >> 1)};
  }
  [[nodiscard]] TileId parent() const { return {z - 1, x / 2, y / 2}; }
  /// "z/x/y".
  [[nodiscard]] std::string name() const;
};

/// The order tiles are built, emitted and stored in: by zoom, then row by row
/// (y, then x).
inline bool rowMajorLess(const TileId& a, const TileId& b) {
  return a.z < b.z || (a.z == b.z && (a.y < b.y || (a.y == b.y && a.x < b.x)));
}

/// Whether a tile gets children: the pyramid's one refinement rule, also what
/// `tinsmith merge` checks shards against. Its measured error (`error`) is
/// over `tolerance` and it is above `maxZoom`; from the planned finest zoom
/// on, where the children's tolerance is the tile's, the error the children
/// can reach (`reachableError`: without the triangles whose worst point lies
/// within the side margin, which the children's sides share) must be over
/// it. A pit a centimetre from the corner the four zoom-1 tiles share is out
/// of reach at every zoom: it made 9 zooms, each tile around it 206 m off.
inline bool tileRefines(double error, double reachableError, int z, double tolerance,
                        int finestZoom, int maxZoom) {
  return z < maxZoom && (z < finestZoom ? error : reachableError) > tolerance;
}

/// Parses "z/x/y"; throws usageError naming `what` for anything else or a tile
/// outside its zoom's grid.
TileId parseTileId(const std::string& text, const std::string& what);

/// An axis-aligned rectangle (closed).
struct Rect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  [[nodiscard]] bool contains(Point2 p) const {
    return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1;
  }
  [[nodiscard]] double width() const { return x1 - x0; }
  [[nodiscard]] double height() const { return y1 - y0; }
  [[nodiscard]] bool overlaps(const Rect& o) const {
    return !(o.x1 < x0 || o.x0 > x1 || o.y1 < y0 || o.y0 > y1);
  }
};

/// The x, y bounding box of points (empty input: an inverted box that
/// overlaps nothing).
template <class Points>
Rect boundsOf(const Points& points) {
  Rect r{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (const auto& p : points) {
    r.x0 = std::min(r.x0, p.x);
    r.y0 = std::min(r.y0, p.y);
    r.x1 = std::max(r.x1, p.x);
    r.y1 = std::max(r.y1, p.y);
  }
  return r;
}

class PyramidGeometry {
 public:
  /// The square [origin.x, origin.x + size] × [origin.y, origin.y + size].
  PyramidGeometry(Point2 origin, double size) : origin_(origin), size_(size) {}
  [[nodiscard]] Point2 origin() const { return origin_; }
  [[nodiscard]] double size() const { return size_; }

  /// The coordinate of grid line i at zoom z along x (or y): origin + i·size/2^z,
  /// computed as origin + (i / 2^z)·size with an exact quotient, so that a
  /// line of zoom z and the same line seen from zoom z + 1 (index 2i) are the
  /// same double.
  [[nodiscard]] double lineX(int z, std::uint64_t i) const;
  [[nodiscard]] double lineY(int z, std::uint64_t j) const;
  /// p with each coordinate put exactly on the nearest grid line of zoom z
  /// (lineX / lineY) when it lies within `near` metres of it.
  [[nodiscard]] Point2 snapToLines(int z, Point2 p, double near) const;
  [[nodiscard]] Rect bounds(const TileId& t) const {
    return {lineX(t.z, t.x), lineY(t.z, t.y), lineX(t.z, t.x + 1ULL), lineY(t.z, t.y + 1ULL)};
  }
  [[nodiscard]] bool inside(const TileId& t) const {
    return t.z >= 0 && t.z < 31 && t.x < (1ULL << t.z) && t.y < (1ULL << t.z);
  }

 private:
  Point2 origin_;
  double size_;
};

}  // namespace tinsmith::tiles
