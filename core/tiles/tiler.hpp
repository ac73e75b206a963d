// Level-of-detail tiles of a TIN (DESIGN.md "Tiles"): for each zoom z the
// multilevel least-squares fit (Algorithm 8.1) of the TIN's data to that
// zoom's tolerance, then per tile a constrained triangulation of the fit's
// binary vertices in the tile, the break lines and domain boundary simplified
// to the zoom's tolerance, and the tile's sides; its z is the constrained least
// squares fit (8.9) over that mesh with break-line and boundary vertices held
// at the TIN's z and the tile's side vertices held at the zoom fit's z.
//
// Tolerances: the finest planned zoom Z meets `tolerance`; zoom z's is
// tolerance · 2^(Z − z), and zooms below Z keep `tolerance`. Z is the first
// zoom whose tiles would hold the finest fit's triangles within a quarter of
// `maxTriangles` each on average; a zoom's fit refines at most
// `levelsPerTile` levels below the zoom, so a tile holds at most about
// 2·4^(levelsPerTile + 1) binary triangles, and where the terrain needs more
// (steep ground) the tiles of Z are refined further. A tile gets children
// when its measured error is above `tolerance` (and z < maxZoom).
//
// Every tile is a pure function of the TIN, the options and its id: tiles can
// be built in any order, on any thread, in separate processes, and give the same
// result. Crack-free within a zoom: the vertices on a tile's side are computed
// only from what both tiles sharing it see (the grid, the zoom fit, the
// simplified lines, each crossing from its segment's ends in a canonical
// order), and held fixed in both.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "core/base/point.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "core/geometry/cell_grid.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/terrain_lines.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

struct TilerOptions {
  double tolerance = 1.0;            ///< metres; what the finest zoom meets
  std::size_t maxTriangles = 32768;  ///< per tile, sets levelsPerTile
  /// No tile below this zoom; by default the planned finest zoom + 6.
  std::optional<int> maxZoom;
  /// Thin-plate λ = factor · λ_d in every fit. Light: the tiles approximate a
  /// TIN (no noise), and the samples fill its large triangles.
  double lambdaFactor = 0.01;
  int threads = 0;  ///< for the zoom fits (0 = all cores)
};

/// One tile's surface, in the project CRS.
struct TileSurface {
  TileId id;
  Rect bounds;
  std::vector<Point3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< CCW
  /// Per vertex: bit 0 west side, 1 east, 2 south, 3 north; 4 held fixed.
  std::vector<std::uint8_t> flags;
  double error = 0.0;  ///< measured max |surface − TIN| (m)
  Point2 errorAt;
  std::size_t breakLineVertices = 0;  ///< vertices of break lines kept in the tile
  std::size_t dataPoints = 0;         ///< data points the tile's fit used
  [[nodiscard]] bool empty() const { return triangles.empty(); }
};

inline constexpr std::uint8_t kSideWest = 1, kSideEast = 2, kSideSouth = 4, kSideNorth = 8,
                              kHeld = 16;

class Tiler {
 public:
  /// Plans the pyramid (the finest fit decides the finest zoom). Throws
  /// usageError for a tolerance ≤ 0 or maxTriangles < 64, inputError for a
  /// TIN with no triangles.
  Tiler(const TinData& tin, TilerOptions options);
  ~Tiler();

  [[nodiscard]] const PyramidGeometry& geometry() const { return geometry_; }
  [[nodiscard]] const TilerOptions& options() const { return options_; }
  [[nodiscard]] int finestZoom() const { return finestZoom_; }
  [[nodiscard]] int maxZoom() const { return maxZoom_; }
  [[nodiscard]] int levelsPerTile() const { return levelsPerTile_; }
  [[nodiscard]] double zoomTolerance(int z) const;
  [[nodiscard]] const TinData& tin() const { return tin_; }
  [[nodiscard]] std::size_t dataPointCount() const { return data_.size(); }
  /// Whether a tile with this error gets children (tileRefines).
  [[nodiscard]] bool refines(const TileId& id, double error) const {
    return tileRefines(error, id.z, options_.tolerance, maxZoom_);
  }

  /// The tile's surface (empty when the tile holds none of the TIN). Thread-safe.
  [[nodiscard]] TileSurface buildTile(const TileId& id) const;

 private:
  struct Zoom;
  /// A zoom's shared part, built by the first tile of the zoom that needs it.
  struct ZoomSlot {
    std::once_flag once;
    std::unique_ptr<Zoom> zoom;
  };
  const Zoom& zoom(int z) const;
  std::unique_ptr<Zoom> makeZoom(int z) const;

  const TinData& tin_;
  TilerOptions options_;
  PyramidGeometry geometry_{{0, 0}, 1};
  std::vector<Point3> data_;          // TIN vertices and points sampled from its triangles
  std::vector<Point3> zoomData_;      // the part of data_ the zoom fits refine for
  CellGrid dataGrid_{0, 0, 0, 0, 1};  // data_ by position
  std::vector<TerrainLine> lines_;
  TinIndex index_;
  int finestZoom_ = 0;
  int maxZoom_ = 0;
  int levelsPerTile_ = 5;
  // The planning fit, kept when its options are those of the finest zoom's
  // fit (then zoom(finestZoom_) takes it instead of fitting again).
  mutable std::unique_ptr<fit::MultilevelFit> plannedFit_;
  mutable std::array<ZoomSlot, 31> zooms_;  // by zoom (PyramidGeometry::inside: z < 31)
};

}  // namespace tinsmith::tiles
