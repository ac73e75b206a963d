// Level-of-detail tiles of a TIN (DESIGN.md "Tiles"). Per tile the
// multilevel least-squares fit (Algorithm 8.1) of the TIN's data inside the
// tile's square to its zoom's tolerance (the tile fit), and a constrained
// triangulation of
//   - the tile's sides: the TIN's exact section along each side, simplified in
//     the vertical (Douglas–Peucker) to kEdgeShare of the zoom's tolerance
//     (less the mosaic's error, for a top fitted to a mosaic) between the points a side must keep
//     (corners, the lines' crossings), with the TIN's step across the side margin kept linear along
//     it too (no new vertex comes closer to a side);
//   - the break lines and domain-boundary rings, simplified in 3-D to the same
//     share with every chord also kept within it of the TIN beneath;
//   - the tile fit's binary vertices inside the tile;
// then the constrained least squares (8.9, umbrella smoothing) over that mesh
// with the side, line and ring vertices held. The tile's error is measured
// exactly against the TIN (surface_difference.hpp), and where a triangle
// misses the zoom's tolerance — its vertical error plus its chord's sag below
// the curved Earth (chord_sag.hpp), within (1 − kEncodingShare) of the
// tolerance — the mesh is refined greedily, worst first, with the TIN's
// points (tile_refiner.hpp), within `maxTriangles`. What a tile declares is
// measured again on what is encoded (tile_content.hpp, docs/tile-error.md).
// The fit gives the tile its shape where the terrain is smooth; the TIN
// points are what meets the tolerance on contour-built terrain, whose creases
// no smooth fit follows, and on a DEM's detail below the fit's finest level.
//
// Tolerances: the finest planned zoom Z meets `tolerance`; zoom z's is
// tolerance · 2^(Z − z), and zooms below Z keep `tolerance`. Z is the first
// zoom whose tiles would hold the finest fit's triangles within a quarter of
// `maxTriangles` each on average (the planning fit: one over the whole
// square, or for more than `planningCellPoints` fit points one over each
// square of the first zoom whose fullest square holds at most that many,
// their triangles summed; a plan may give Z instead); a tile fit refines at most
// `levelsPerTile` levels below the zoom. A tile gets children when its
// measured error is above `tolerance` (and z < maxZoom).
//
// Every tile is a pure function of the TIN, the options and its id: tiles can
// be built in any order, on any thread, in separate processes, and give the same
// result. A tile fit sees only the data in the tile's square, so a tile's
// fit costs what its part of the TIN costs, not the whole TIN's. What the
// whole TIN decides (the pyramid, the finest zoom, the fit data's sampling,
// the lines simplified for each zoom) is a TilerPlan: a Tiler given the plan
// and a region needs only the TIN's triangles around the region (and every
// vertex) to build the region's tiles bit for bit.
// Crack-free within a zoom: the vertices on a tile's side are computed
// only from what both tiles sharing it see (the TIN's section along the side,
// the grid, the simplified lines, each crossing from its
// segment's ends in a canonical order), held fixed in both, and no held TIN
// point comes closer to a side than 1e-4 of the tile's width.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "core/base/point.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "core/geometry/cell_grid.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/terrain_lines.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

/// What the whole TIN decides for every tile, found once by a Tiler over the
/// whole TIN (Tiler::plan) and handed to Tilers that see only part of it (a
/// shard's square, TilerOptions::region), whose tiles are then bit for bit
/// those the whole TIN gives.
struct TilerPlan {
  PyramidGeometry geometry{{0, 0}, 1};
  /// The box of the TIN's vertices, which every tile's triangles lie in
  /// (Tiler::sagRadius measures the CRS over a square's part of it).
  Rect extent;
  int finestZoom = 0;
  /// The spacing at which the fit data sample the TIN's sparse triangles (0:
  /// none), from the median edge and the sample budget over the whole TIN.
  double fitSpacing = 0;
  /// The tile fits take all the data, break lines too (a TIN that is all
  /// break lines leaves them nothing else).
  bool tileFitAllData = false;
  /// The break lines and domain rings simplified for zoom k, k = 0 …
  /// finestZoom (the last serves every finer zoom), before each zoom snaps
  /// them to its tile sides. Simplifying keeps every chord on the TIN, which
  /// takes the TIN along the whole line.
  std::vector<std::vector<TerrainLine>> zoomLines;
  /// The z of the tile corners off the TIN (in no triangle) within a tile
  /// width of the TIN's box, at the zooms to cornerZoom (−1: none), as the
  /// whole TIN gives it (Tiler::offTinZ): a Tiler with a region takes them
  /// from here, and need then hold the TIN's vertices around its region
  /// only as far as the finer zooms' corners look (tilerVertexRegion).
  struct OffTinCorner {
    std::int32_t zoom = 0;
    std::uint32_t row = 0, column = 0;  ///< its grid lines: lineY(zoom, row), lineX(zoom, column)
    double z = 0;
    /// What the corners are ordered by.
    [[nodiscard]] auto key() const { return std::tuple(zoom, row, column); }
  };
  int cornerZoom = -1;
  std::vector<OffTinCorner> offTinCorners;  ///< by zoom, row, column
  /// Tiler::mosaicZoom of the whole TIN.
  int mosaicZoom = 0;
};

/// The square a Tiler with a region must read the TIN in: `region` grown by
/// far more than a tile side's margin lines (which sections sample just
/// outside a tile) and any rounding of the tile squares.
Rect tilerReadRegion(const Rect& region);
/// How far, in tile widths, a tile corner off the TIN looks for its nearest
/// TIN vertex (whose z it takes).
inline constexpr double kOffTinReach = 4;
/// The deepest zoom TilerPlan::offTinCorners may go to (4^10 corners).
inline constexpr int kMaxCornerZoom = 10;
/// The box a Tiler with `plan` and `region` (a tile's square) must hold
/// every TIN vertex of: the region grown by kOffTinReach tile widths of the
/// coarsest zoom in it whose corners the plan does not hold.
Rect tilerVertexRegion(const TilerPlan& plan, const Rect& region);

class GeoReference;  // tile_content.hpp

/// The first zoom k ≤ cap whose 4^k squares `vertices` fill with at most
/// `mosaicPoints` each on average (0 when mosaicPoints is 0): the mosaic
/// zoom of a TIN (TilerOptions::mosaicPoints) with cap its finest zoom.
[[nodiscard]] inline int mosaicZoomFor(std::size_t vertices, std::size_t mosaicPoints, int cap) {
  if (mosaicPoints == 0) return 0;
  const double fill = static_cast<double>(vertices) / static_cast<double>(mosaicPoints);
  int k = 0;
  while (k < cap && fill > std::ldexp(1.0, 2 * k)) ++k;
  return k;
}

struct TilerOptions {
  double tolerance = 1.0;            ///< metres; what the finest zoom meets
  std::size_t maxTriangles = 32768;  ///< per tile, sets levelsPerTile
  /// No tile below this zoom; by default the planned finest zoom + 6.
  std::optional<int> maxZoom;
  /// λ = factor · λ_d in every fit (thin-plate in the tile fits' binary triangulations, umbrella in
  /// the tile fits). Light: the tiles approximate a TIN (no noise), and the
  /// samples fill its large triangles.
  double lambdaFactor = 0.01;
  int threads = 0;  ///< for the planning fit (0 = all cores)
  /// The planning fit runs over the whole square up to this many fit
  /// points, else over the squares of the first zoom (to 10) whose fullest
  /// square holds at most this many, one at a time (its memory is a
  /// square's, not the whole TIN's; a square whose points lie on one line is
  /// left out); the finest zoom counts their triangles together.
  /// They hold a few fewer than the whole fit (no square refines beside its
  /// neighbour to keep the whole triangulation conforming): on SRTM
  /// N44W072 at 10 m and 40 m, 0.2–1.8 % fewer over 4, 16 and 64 squares,
  /// the same finest zoom; up to a fifth fewer where the fit goes to the
  /// data's own spacing (more triangles than points).
  std::size_t planningCellPoints = std::size_t{1} << 18;
  /// The tiles above the mosaic zoom K are fitted to the mosaic of zoom
  /// K's tiles (tile_mosaic.hpp, buildPyramid), not to the TIN: K is the
  /// first zoom whose squares the TIN's vertices fill with at most this
  /// many each on average (vertices ≤ mosaicPoints · 4^K), and at most the
  /// finest zoom (whose tolerance a tile above can leave room in) and the
  /// max zoom; 0 — every tile from the TIN — for a TIN of up to this many
  /// vertices, and for a fixed pyramid. The top is then what a task can
  /// build from the subtrees' zoom-K tiles alone (issue 24), and every tile
  /// above K that holds terrain refines. 0: K = 0 for every TIN.
  std::size_t mosaicPoints = std::size_t{1} << 18;
  /// A fixed pyramid instead of the TIN's bounding square and the planned
  /// finest zoom: the square, the finest zoom (which meets `tolerance`, each
  /// zoom above twice the one below) and the zooms every tile with terrain
  /// refines above. Geographic terrain (terrain_tiling.hpp) tiles the globe's
  /// grid, whose levels' errors are fixed by the client.
  struct FixedPyramid {
    PyramidGeometry geometry{{0, 0}, 1};
    int finestZoom = 0;
    int refineBelow = 0;
  };
  std::optional<FixedPyramid> fixed;
  /// The finest zoom a plan of this job already chose (a shard of tinsmith
  /// slurm, whose plan ran the planning fit once): no planning fit is run.
  /// It must be what the planning gives for this TIN and these options, or
  /// the tiles are those of another pyramid.
  std::optional<int> plannedFinestZoom;
  /// The plan of this job's whole TIN (Tiler::plan, made with these
  /// options): its pyramid, finest zoom, fit sampling and simplified lines
  /// are taken instead of found here. Not with `fixed`.
  std::shared_ptr<const TilerPlan> plan;
  /// With a plan: every tile asked for lies in this square (a shard's
  /// subtree). The TIN need then hold only the triangles and the constrained
  /// edges whose boxes meet tilerReadRegion(region), the vertices they use
  /// and those in tilerVertexRegion(region), in the whole TIN's order
  /// (ingest::readTinFilePart): the fit data, the index and the lines are
  /// those of the square, not of the whole TIN.
  std::optional<Rect> region;
  /// Set when the TIN is the mosaic of a finer zoom's tiles (tile_mosaic.hpp)
  /// rather than the terrain: how far the mosaic lies from the terrain under
  /// a tile's square, vertically (the largest error of its tiles there; ≥ 0,
  /// called from several threads). A tile's errors, measured against the
  /// mosaic, have it added — a bound against the terrain itself, by the
  /// triangle inequality — and its refinement aims at its zoom's tolerance
  /// less it (never below half the tolerance: a larger one leaves the tile
  /// over it). Its sides and lines are simplified to a share of the
  /// tolerance less the root's E (the mosaic's largest: a value both tiles
  /// at a side agree on; at most half the tolerance), against the mosaic.
  std::function<double(const TileId&)> mosaicError;
  /// The project CRS's place on the Earth: chord sag is then planned with the
  /// radius chordSagRadius gives over the part of each tile's square the
  /// TIN's box covers (Tiler::sagRadius), a side with the smaller of its two
  /// tiles' (a projection that bends straight lines more or less than the
  /// sphere allows for), else with kEarthRadiusOfCurvature. Must outlive the
  /// Tiler.
  const GeoReference* geo = nullptr;
};

/// One tile's surface, in the project CRS.
struct TileSurface {
  TileId id;
  Rect bounds;
  std::vector<Point3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< CCW
  /// Per triangle: bit i set when its edge from corner i to corner i + 1 is
  /// a constrained edge (a side, a line or a ring).
  std::vector<std::uint8_t> heldEdges;
  /// Per triangle: the bits of heldEdges that are edges of a river.
  std::vector<std::uint8_t> riverEdges;
  /// Per vertex: bit 0 west side, 1 east, 2 south, 3 north; 4 held fixed;
  /// 5 a TIN point held where the fit missed the tolerance.
  std::vector<std::uint8_t> flags;
  /// Measured max |surface − TIN| (m), vertical, in the project CRS: before
  /// encoding (tile_content.hpp adds what encoding moves).
  double error = 0.0;
  Point2 errorAt;
  /// Per triangle: its own measured max |surface − TIN| (m), as `error`.
  std::vector<double> triangleErrors;
  /// Per triangle: 1 when the refiner left it over the tolerance because its
  /// worst point is out of any new vertex's reach (tile_refiner.hpp): on a
  /// side or within the side margin, which the children share.
  std::vector<std::uint8_t> outOfReach;
  double tolerance = 0.0;             ///< the zoom's tolerance (m)
  std::size_t breakLineVertices = 0;  ///< vertices of break lines kept in the tile
  std::size_t dataPoints = 0;         ///< data points the tile's fit used
  std::size_t heldPoints = 0;         ///< TIN points the refinement added or held
  [[nodiscard]] bool empty() const { return triangles.empty(); }
};

/// The share of a zoom's tolerance left to encoding (tile_content.hpp): the
/// tiles are refined until each triangle's vertical error plus its chord sag
/// is within (1 − kEncodingShare) of the tolerance, and positions are
/// quantized within half the share (the other half is float rounding).
inline constexpr double kEncodingShare = 0.02;
/// The farthest Draco's quantization may move a position (m) of a tile
/// `width` metres wide at a zoom of `tolerance` metres: half the encoding
/// share, and never less than 1 cm, nor than 5·10⁻⁸ of the width (the
/// float32 rounding its positions around the tile's centre have before
/// quantization). The refiner keeps twice this from the tile's sides
/// (sideMargin), so quantization cannot fold a triangle there.
[[nodiscard]] inline double maxQuantization(double width, double tolerance) {
  return std::max({0.01, 5e-8 * width, 0.5 * kEncodingShare * tolerance});
}
/// The finest step the encoder takes on a tile `width` metres wide, where
/// the encoding share allows it: 0.5 mm, or 10⁻⁶ of the width (about 20 bits
/// a coordinate). Every bit counts twice: in the tile's bytes, and in
/// Draco's encoder, which counts the symbols in an array of 2^bits entries —
/// 1 GB at 29 bits, 1 cm steps across 3 000 km, and seconds a tile.
[[nodiscard]] inline double minQuantization(double width) {
  return std::max(0.0005, 1e-6 * width);
}

inline constexpr std::uint8_t kSideWest = 1, kSideEast = 2, kSideSouth = 4, kSideNorth = 8,
                              kHeld = 16, kPinned = 32;

class Tiler {
 public:
  /// Plans the pyramid (the finest fit decides the finest zoom). Throws
  /// usageError for a tolerance ≤ 0 or maxTriangles < 64, inputError for a
  /// TIN with no triangles.
  Tiler(const TinData& tin, TilerOptions options);
  /// The Tiler keeps a reference to the TIN: it must outlive it.
  Tiler(TinData&& tin, TilerOptions options) = delete;
  ~Tiler();

  [[nodiscard]] const PyramidGeometry& geometry() const { return geometry_; }
  [[nodiscard]] const TilerOptions& options() const { return options_; }
  [[nodiscard]] int finestZoom() const { return finestZoom_; }
  [[nodiscard]] int maxZoom() const { return maxZoom_; }
  /// TilerOptions::mosaicPoints' K: the tiles above it are fitted to the
  /// mosaic of its tiles (a plan's, for a Tiler with a plan).
  [[nodiscard]] int mosaicZoom() const { return mosaicZoom_; }
  /// The zoom of the squares the planning fit ran over (0: the whole
  /// square; −1: no planning fit ran, a plan or options gave the finest
  /// zoom), and the triangles of its finest levels, which chose the zoom.
  [[nodiscard]] int planningCellZoom() const { return planning_.cellZoom; }
  [[nodiscard]] std::size_t planningTriangles() const { return planning_.triangles; }
  /// The radius chord sag is planned with over a tile's square: the
  /// sphere's without a georeference, else chordSagRadius over the part of
  /// the square the TIN's box covers, where the tile's triangles lie (over
  /// the whole square when it covers none of it) — the root of a strip of
  /// terrain does not take the bending of a CRS far off the strip.
  [[nodiscard]] double sagRadius(const Rect& square) const;
  [[nodiscard]] int levelsPerTile() const { return levelsPerTile_; }
  [[nodiscard]] double zoomTolerance(int z) const;
  [[nodiscard]] const TinData& tin() const { return tin_; }
  [[nodiscard]] std::size_t dataPointCount() const { return data_.size(); }
  /// Whether a tile with these errors gets children (tileRefines; every
  /// tile above the mosaic zoom or a fixed pyramid's refineBelow does).
  [[nodiscard]] bool refines(const TileId& id, double error, double reachableError) const {
    return (options_.fixed && id.z < options_.fixed->refineBelow) || id.z < mosaicZoom_ ||
           tileRefines(error, reachableError, id.z, options_.tolerance, finestZoom_, maxZoom_);
  }

  /// The tile's surface (empty when the tile holds none of the TIN). Thread-safe.
  /// `encodingAllowance` (metres) is kept from the refinement's target
  /// besides kEncodingShare, for an encoding whose rounding the caller
  /// cannot choose (quantized-mesh's 0..32767 over the tile).
  [[nodiscard]] TileSurface buildTile(const TileId& id, double encodingAllowance = 0.0) const;
  /// What tiles of this pyramid need of the whole TIN, for Tilers that see
  /// only part of it (TilerOptions::plan and region), with the off-TIN
  /// corners of the zooms to `cornerZoom` (at most kMaxCornerZoom; −1: none).
  /// Simplifies the lines for every zoom to the finest: call it once.
  [[nodiscard]] TilerPlan plan(int cornerZoom = -1) const;

 private:
  struct Zoom;
  struct TileInput;
  /// A zoom's shared part, built by the first tile of the zoom that needs it.
  struct ZoomSlot {
    std::once_flag once;
    std::unique_ptr<Zoom> zoom;
  };
  const Zoom& zoom(int z) const;
  std::unique_ptr<Zoom> makeZoom(int z) const;
  /// What zoom z's sides and lines are simplified to (m).
  [[nodiscard]] double edgeTolerance(int z) const;
  /// The lines simplified to edgeTolerance(z) (not snapped to its sides).
  [[nodiscard]] std::vector<TerrainLine> simplifiedLines(int z) const;
  struct Planning {
    int finestZoom = 0;
    int cellZoom = -1;
    std::size_t triangles = 0;
  };
  [[nodiscard]] Planning planFinestZoom() const;
  /// The tile's own fit: Algorithm 8.1 over the tile's square, levelsPerTile
  /// levels, to the zoom's tolerance, of the fit data inside the square
  /// (nullopt when fewer than 3): a function of the tile alone.
  [[nodiscard]] std::optional<fit::MultilevelFit> tileFit(const TileId& id,
                                                          double tolerance) const;
  /// The fit's z at p (clamped into its square), or the TIN's without a fit.
  [[nodiscard]] double fitZ(const fit::MultilevelFit* fit, Point2 p) const;
  /// A z for a tile corner of zoom z off the TIN that every tile holding it
  /// agrees on: the nearest TIN vertex's (the plan's, to its cornerZoom).
  [[nodiscard]] double offTinZ(int z, std::uint64_t column, std::uint64_t row) const;
  /// `radius`: sagRadius of the tile's square.
  [[nodiscard]] TileInput tileInput(const TileId& id, const Zoom& zd, const fit::MultilevelFit* fit,
                                    double radius) const;
  [[nodiscard]] TileSurface triangulateTile(const TileId& id, const Rect& rect,
                                            const TileInput& input,
                                            const std::vector<TerrainLine>& zoomLines) const;
  void fitTile(TileSurface& tile, const fit::MultilevelFit* fit) const;
  [[nodiscard]] std::span<const Point3> tileFitData() const {
    return tileFitIsData_ ? data_ : std::span<const Point3>(tileFitData_);
  }

  const TinData& tin_;
  TilerOptions options_;
  PyramidGeometry geometry_{{0, 0}, 1};
  Rect extent_;  // the whole TIN's vertices' box (the plan's, with a region)
  // TIN vertices and points sampled from its triangles: the TIN's own
  // vertices, not a copy, when they are all of it (a whole TIN, no samples),
  // else dataOwned_.
  std::span<const Point3> data_;
  std::vector<Point3> dataOwned_;
  // The part of data_ the tile fits refine for: data_ itself when
  // tileFitIsData_ (no break line leaves a point out), else tileFitData_.
  std::vector<Point3> tileFitData_;
  bool tileFitIsData_ = false;
  CellGrid dataGrid_{0, 0, 0, 0, 1};     // data_ by position
  CellGrid tileFitGrid_{0, 0, 0, 0, 1};  // tileFitData_ by position, unless tileFitIsData_
  std::vector<TerrainLine> lines_;    // empty with a plan, which has them simplified
  // The plane, or with a region the part of it the TIN was read in.
  Rect within_{-HUGE_VAL, -HUGE_VAL, HUGE_VAL, HUGE_VAL};
  double fitSpacing_ = 0;            // TilerPlan::fitSpacing
  bool tileFitAllData_ = false;      // TilerPlan::tileFitAllData
  // Built last in the constructor, after the planning fit: the two are the
  // largest things a Tiler of a whole TIN holds, and are not needed at once.
  std::optional<TinIndex> index_;
  int finestZoom_ = 0;
  Planning planning_;  // what the planning fit found (cellZoom −1: none ran)
  int maxZoom_ = 0;
  int mosaicZoom_ = 0;
  // Sides and lines are simplified to kEdgeShare of a zoom's tolerance
  // less this (the mosaic's largest error, TilerOptions::mosaicError).
  double edgeAllowance_ = 0;
  int levelsPerTile_ = 5;
  mutable std::array<ZoomSlot, 31> zooms_;  // by zoom (PyramidGeometry::inside: z < 31)
  // The lines simplified to the finest zoom's tolerance, which every zoom
  // from finestZoom_ on has: simplified once (each zoom snaps them to its own
  // sides). Simplifying keeps every chord on the TIN, a section per chord
  // tried: a third of a job's time on a contoured mesa, once for each zoom.
  mutable std::once_flag finestLinesOnce_;
  mutable std::vector<TerrainLine> finestLines_;
};

}  // namespace tinsmith::tiles
