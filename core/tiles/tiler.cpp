#include "core/tiles/tiler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/fit/least_squares.hpp"
#include "core/geometry/predicates.hpp"
#include "core/surface/surface.hpp"
#include "core/tiles/chord_sag.hpp"
#include "core/tiles/tile_refiner.hpp"

namespace tinsmith::tiles {

/// What every tile of one zoom shares: the lines simplified to its
/// tolerance (with their bounding boxes).
struct Tiler::Zoom {
  double tolerance = 0;
  std::vector<TerrainLine> lines;
  std::vector<Rect> lineBoxes;
};

/// What a tile's constrained triangulation is made of.
struct Tiler::TileInput {
  std::vector<Point3> ring;         // the tile's sides, CCW
  std::vector<ClippedPiece> lines;  // break lines and rings in the tile (held)
  std::vector<Point3> interior;     // binary vertices inside the tile (free)
};

namespace {

/// The share of a zoom's tolerance that the tile sides and the simplified
/// lines may take: they are held, so no fit corrects them, and the pins
/// beside them are exact, so a triangle between the two can be off by the
/// side's or line's error plus the slope it cuts (measured on Red Butte at
/// 1 m: 0.9 leaves tiles that never converge, 0.4 converges at zoom 4).
constexpr double kEdgeShare = 0.4;

/// The share of a zoom's tolerance a tile side's chords may sag below the
/// curved ground (chord_sag.hpp): a side is cut into pieces no longer than
/// that allows, as the refiner cannot split a side.
constexpr double kSideSagShare = 0.1;

/// The data the fits see: the TIN's vertices, plus points sampled from its
/// triangles where its vertices are sparse (a triangle whose longest edge
/// exceeds twice the median longest edge gets the interior points of a
/// barycentric grid at about that median's spacing, z on the triangle's
/// plane; a DEM's even grid gets none). The samples are at most as many as
/// the TIN's vertices: where the median asks for more, the spacing grows.
/// `tileFit` leaves out what the tile meshes hold exactly — vertices of break
/// lines, and samples of the triangles at them —
/// so a tile's binary fit is not driven to tiny cells by the steps a break
/// line makes (a river lowered below its banks); the least squares over each
/// tile mesh (fitTile) uses it all.
struct FitData {
  /// Empty when the data are the TIN's vertices, every one and nothing else
  /// (allAreTinVertices): a whole TIN with no triangle to sample.
  std::vector<Point3> all;
  bool allAreTinVertices = false;
  std::vector<Point3> tileFit;  // empty when it would be `all` (tileFitIsAll)
  double spacing = 0;           // TilerPlan::fitSpacing
  bool tileFitAll = false;      // TilerPlan::tileFitAllData
  bool tileFitIsAll = false;    // tileFitAll, or no break line leaves anything out
};

/// The longest of a triangle's edges in x, y.
double longestEdge(const Point3& a, const Point3& b, const Point3& c) {
  return std::max({std::hypot(b.x - a.x, b.y - a.y), std::hypot(c.x - b.x, c.y - b.y),
                   std::hypot(a.x - c.x, a.y - c.y)});
}

/// The spacing at which fitData samples a TIN's sparse triangles: the median
/// longest edge, grown until the samples are at most as many as the TIN's
/// vertices (0 for a TIN without triangles).
double fitSpacing(const TinData& tin) {
  const auto longestEdgeOf = [&](const auto& t) {
    return longestEdge(tin.vertices[t[0]], tin.vertices[t[1]], tin.vertices[t[2]]);
  };
  std::vector<double> lengths;
  lengths.reserve(tin.triangles.size());
  for (std::size_t k = 0; k < tin.triangles.size();
       k += std::max<std::size_t>(1, tin.triangles.size() / 20000)) {
    lengths.push_back(longestEdgeOf(tin.triangles[k]));
  }
  if (lengths.empty()) return 0;
  std::nth_element(lengths.begin(),
                   lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2),
                   lengths.end());
  double spacing = lengths[lengths.size() / 2];
  if (!(spacing > 0)) return 0;
  // The budget: at most as many samples as the TIN has vertices. Contours
  // far apart on a plain below close ones on a cliff (a median edge of a few
  // metres, triangles of hundreds) asked for 17 M samples from 127 k
  // vertices (2.9 GB, 160 s); the spacing grows until the estimate fits.
  double sparseArea = 0;
  for (const auto& t : tin.triangles)
    if (longestEdgeOf(t) > 2 * spacing)
      sparseArea += 0.5 * std::abs(geometry::orient2dInexact(tin.vertices[t[0]], tin.vertices[t[1]],
                                                             tin.vertices[t[2]]));
  const double budget = static_cast<double>(tin.vertices.size());
  if (sparseArea / (spacing * spacing) > budget) spacing = std::sqrt(sparseArea / budget);
  return spacing;
}

/// The fit data of the part of the TIN in `within` (with a plan; else all):
/// the vertices inside it and the samples of the triangles whose boxes meet
/// it, in the order the whole TIN gives them, so that the data inside any
/// square in `within` are the same points in the same order.
FitData fitData(const TinData& tin, const TilerPlan* plan, const Rect& within) {
  FitData data;
  std::vector<char> held(tin.vertices.size(), 0);
  for (const auto& e : tin.constrainedEdges) {
    if (e.feature < tin.features.size() && isBreakLineKind(tin.features[e.feature].kind))
      held[e.a] = held[e.b] = 1;
  }
  // Without break lines (a DEM) the two are the same points: kept once.
  const bool anyHeld = std::find(held.begin(), held.end(), 1) != held.end();
  // Every vertex inside: they are put before the samples at the end, and
  // only if there are samples (else the TIN's own vertices serve).
  const bool everyVertex = std::all_of(tin.vertices.begin(), tin.vertices.end(),
                                       [&](const Point3& p) { return within.contains(p.xy()); });
  for (std::size_t v = 0; v < tin.vertices.size(); ++v) {
    if (!within.contains(tin.vertices[v].xy())) continue;
    if (!everyVertex) data.all.push_back(tin.vertices[v]);
    if (anyHeld && !held[v]) data.tileFit.push_back(tin.vertices[v]);
  }
  data.spacing = plan ? plan->fitSpacing : fitSpacing(tin);
  const double spacing = data.spacing;
  for (const auto& t : tin.triangles) {
    if (!(spacing > 0)) break;
    const Point3& a = tin.vertices[t[0]];
    const Point3& b = tin.vertices[t[1]];
    const Point3& c = tin.vertices[t[2]];
    if (longestEdge(a, b, c) <= 2 * spacing) continue;
    if (!within.overlaps(boundsOf(std::array<Point3, 3>{a, b, c}))) continue;
    const bool nearHeld = held[t[0]] || held[t[1]] || held[t[2]];
    // About one sample per spacing² of area (a barycentric grid of n steps
    // has n²/2 points): a long sliver on the hull gets a few, not thousands.
    const double area = 0.5 * std::abs(geometry::orient2dInexact(a, b, c));
    const int n = static_cast<int>(std::min(64.0, std::ceil(std::sqrt(2 * area) / spacing)));
    for (int i = 1; i < n; ++i) {
      for (int j = 1; i + j < n; ++j) {
        const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n,
                     w = 1.0 - u - v;
        const Point3 p{w * a.x + u * b.x + v * c.x, w * a.y + u * b.y + v * c.y,
                       w * a.z + u * b.z + v * c.z};
        data.all.push_back(p);
        if (anyHeld && !nearHeld) data.tileFit.push_back(p);
      }
    }
  }
  data.allAreTinVertices = everyVertex && data.all.empty();
  if (everyVertex && !data.all.empty())
    data.all.insert(data.all.begin(), tin.vertices.begin(), tin.vertices.end());
  const std::size_t allSize = data.allAreTinVertices ? tin.vertices.size() : data.all.size();
  // A TIN that is all break lines still needs something to fit.
  data.tileFitAll = plan ? plan->tileFitAllData : (anyHeld ? data.tileFit.size() : allSize) < 3;
  data.tileFitIsAll = data.tileFitAll || !anyHeld;
  if (data.tileFitIsAll) std::vector<Point3>().swap(data.tileFit);
  data.all.shrink_to_fit();  // grown by doubling: up to half of it unused
  data.tileFit.shrink_to_fit();
  return data;
}

fit::MultilevelOptions binaryFitOptions(const TilerOptions& o, Point2 origin, double size,
                                      double tolerance, int maxLevel, int threads) {
  fit::MultilevelOptions m;
  m.smoothing = fit::Smoothing::ThinPlate;
  m.lambdaFactor = o.lambdaFactor;
  m.criteria.errorAbsolute = tolerance;
  m.maxLevel = std::clamp(maxLevel, 1, fit::BinaryTriangulation::kMaxGridLevels - 1);
  m.domainOrigin = origin;
  m.domainSize = size;
  m.threads = threads;
  return m;
}

/// Whether the points lie on one line, to `slack`: their RMS distance from
/// their principal axis is at most slack.
bool onOneLine(std::span<const Point3> points, double slack) {
  double mx = 0, my = 0;
  for (const auto& p : points) mx += p.x, my += p.y;
  mx /= static_cast<double>(points.size());
  my /= static_cast<double>(points.size());
  double cxx = 0, cyy = 0, cxy = 0;
  for (const auto& p : points) {
    const double dx = p.x - mx, dy = p.y - my;
    cxx += dx * dx, cyy += dy * dy, cxy += dx * dy;
  }
  const double n = static_cast<double>(points.size());
  cxx /= n, cyy /= n, cxy /= n;
  const double across = 0.5 * (cxx + cyy - std::hypot(cxx - cyy, 2 * cxy));  // least variance
  return across <= slack * slack;
}

/// Even-odd test of p against closed rings.
bool insideRings(Point2 p, const std::vector<TerrainLine>& lines) {
  bool inside = false;
  for (const auto& line : lines) {
    if (!line.ring) continue;
    const auto& pts = line.points;
    for (std::size_t i = 0, j = pts.size() - 1; i < pts.size(); j = i++) {
      const Point3& a = pts[i];
      const Point3& b = pts[j];
      if ((a.y > p.y) != (b.y > p.y)) {
        const double x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
        if (p.x < x) inside = !inside;
      }
    }
  }
  return inside;
}

/// A point a tile side must keep: a corner or a binary vertex (z from the
/// TIN), or a line's crossing (z from the line).
struct SidePoint {
  double along;  // x on a south or north side, y on an east or west side
  Point3 p;
  bool onLine;
};

/// How far a new vertex keeps from the sides of a tile at a zoom of
/// `tolerance` (RefineOptions::sideMargin): twice the farthest Draco may move
/// a position (maxQuantization), so quantization cannot carry one across a
/// side and fold a triangle there. A margin of 1e-4 of the width kept a
/// wall's or a pit's vertex half a metre from a 5 km tile's side out of
/// reach, and the tile over its tolerance.
double sideMargin(const Rect& rect, double tolerance) {
  return 2 * maxQuantization(rect.width(), tolerance);
}

/// A point of a tile side's profile: its position along the side, the TIN's
/// z on the side, and how much the TIN changes from the side to the lines
/// the side margin away on either hand (NaN off the TIN).
struct SideSample {
  double along, z, leftStep, rightStep;
};

/// Douglas–Peucker over a side's profile between two points it keeps: the
/// samples (sorted by `along`) where the chord from `from` to `to` misses by
/// more than `tolerance` are appended to `kept`, in order. A chord misses
/// where the TIN's z on the side is off it, or where the step to a margin
/// line is off the step's own chord: no vertex the refiner may add comes
/// closer to the side than the margin, so the strip between is the side's
/// triangles alone, and they follow the TIN there only while its step across
/// the strip is linear along the side. A pit's vertex half a metre inside a
/// side, its slivers 300 m deep, steps 12 m down across a 2 cm strip along
/// 100 m of side and nowhere else: the TIN vertex where that ends is kept,
/// where the z alone dropped it and both tiles beside the side stayed 12 m
/// off at every zoom.
void simplifyProfile(std::span<const SideSample> samples, const SideSample& from,
                     const SideSample& to, double tolerance, std::vector<SideSample>& kept) {
  std::size_t worst = samples.size();
  double worstMiss = tolerance;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const SideSample& p = samples[k];
    const double w = (p.along - from.along) / (to.along - from.along);
    auto miss = [&](double value, double a, double b) {
      return std::isnan(value) || std::isnan(a) || std::isnan(b)
                 ? 0.0
                 : std::abs(value - (a + w * (b - a)));
    };
    const double d =
        std::max({miss(p.z, from.z, to.z), miss(p.leftStep, from.leftStep, to.leftStep),
                  miss(p.rightStep, from.rightStep, to.rightStep)});
    if (d > worstMiss) {
      worstMiss = d;
      worst = k;
    }
  }
  if (worst == samples.size()) return;
  simplifyProfile(samples.first(worst), from, samples[worst], tolerance, kept);
  kept.push_back(samples[worst]);
  simplifyProfile(samples.subspan(worst + 1), samples[worst], to, tolerance, kept);
}

/// The TIN's section along a line as (position along it, z), linear between.
class SectionProfile {
 public:
  void take(const TinIndex& index, Point2 a, Point2 b, double u0, double u1) {
    index.section(a, b, section_);
    points_.clear();
    for (const auto& sp : section_) points_.push_back({u0 + sp.t * (u1 - u0), sp.z});
  }
  [[nodiscard]] const std::vector<std::pair<double, double>>& points() const { return points_; }
  /// The TIN's z at u along the line, or nullopt off the TIN.
  [[nodiscard]] std::optional<double> at(double u) const {
    const auto hi = std::lower_bound(points_.begin(), points_.end(), u,
                                     [](const auto& a, double v) { return a.first < v; });
    if (hi != points_.end() && hi->first == u && !std::isnan(hi->second)) return hi->second;
    if (hi == points_.begin() || hi == points_.end()) return std::nullopt;
    const auto lo = hi - 1;
    if (std::isnan(lo->second) || std::isnan(hi->second)) return std::nullopt;
    const double w = (u - lo->first) / (hi->first - lo->first);
    return lo->second + w * (hi->second - lo->second);
  }

 private:
  std::vector<TinIndex::SectionPoint> section_;
  std::vector<std::pair<double, double>> points_;
};

}  // namespace

Tiler::Tiler(const TinData& tin, TilerOptions options) : tin_(tin), options_(options) {
  if (!(options_.tolerance > 0) || !std::isfinite(options_.tolerance)) {
    throw usageError("the tile tolerance must be a positive number of metres (got " +
                         std::to_string(options_.tolerance) + ")",
                     "set [tiles] tolerance or --tolerance to e.g. 1");
  }
  if (options_.maxTriangles < 64) {
    throw usageError("max_triangles must be at least 64 (got " +
                     std::to_string(options_.maxTriangles) + ")");
  }
  // (Part of a TIN, for a region, may hold no triangle and no vertex: the
  // region's tiles are empty.)
  if (!options_.region && (tin.triangles.empty() || tin.vertices.size() < 3)) {
    throw inputError("the TIN has no triangles to tile", {}, "build it with tinsmith tin first");
  }
  const TilerPlan* plan = options_.plan.get();
  if (plan && options_.fixed) throw internalError("Tiler: a plan is for a pyramid of the TIN's own");
  if (options_.region && !plan) throw internalError("Tiler: a region needs the plan of the whole TIN");
  const Rect extent = boundsOf(tin.vertices);
  extent_ = plan ? plan->extent : extent;
  geometry_ = plan             ? plan->geometry
              : options_.fixed ? options_.fixed->geometry
                               : PyramidGeometry({extent.x0, extent.y0},
                                                 std::max(extent.width(), extent.height()));
  if (options_.fixed) {
    const Rect square = geometry_.bounds({});
    if (!(square.x0 <= extent.x0 && extent.x1 <= square.x1 && square.y0 <= extent.y0 &&
          extent.y1 <= square.y1) ||
        options_.fixed->finestZoom < 0 || options_.fixed->finestZoom > 30)
      throw internalError("Tiler: the fixed pyramid does not hold the TIN");
  }
  // levelsPerTile d: a tile refined d + 1 levels holds 2·4^(d+1) triangles;
  // keep that within half the budget, for break lines and sides.
  int d = 0;
  while (2.0 * std::pow(4.0, d + 2) <= static_cast<double>(options_.maxTriangles) / 2) ++d;
  levelsPerTile_ = std::max(d, 1);
  if (options_.region) within_ = tilerReadRegion(*options_.region);
  const Rect dataBox = options_.region ? within_ : extent;  // holds the data, if it has no box
  FitData data = fitData(tin, plan, within_);
  dataOwned_ = std::move(data.all);
  data_ = data.allAreTinVertices ? std::span<const Point3>(tin.vertices) : dataOwned_;
  tileFitData_ = std::move(data.tileFit);
  tileFitIsData_ = data.tileFitIsAll;
  fitSpacing_ = data.spacing;
  tileFitAllData_ = data.tileFitAll;
  // The grids only speed up finding the data in a square (what is found is
  // put in the data's order): over the data's own box.
  auto gridOf = [&](std::span<const Point3> points) {
    const Rect box = points.empty() ? dataBox : boundsOf(points);
    CellGrid grid(box.x0, box.y0, box.x1, box.y1,
                  CellGrid::cellFor(box.width(), box.height(), points.size() / 4 + 1, 1e-9));
    grid.build(points.size(), [&](std::size_t i, auto&& emit) {
      emit(grid.index(grid.cellX(points[i].x), grid.cellY(points[i].y)));
    });
    return grid;
  };
  dataGrid_ = gridOf(data_);
  if (!tileFitIsData_) tileFitGrid_ = gridOf(tileFitData_);
  if (!plan) lines_ = extractTerrainLines(tin);
  finestZoom_ = plan             ? plan->finestZoom
                : options_.fixed ? options_.fixed->finestZoom
                                 : options_.plannedFinestZoom.value_or(-1);
  if (finestZoom_ < 0) {
    planning_ = planFinestZoom();
    finestZoom_ = planning_.finestZoom;
  }
  maxZoom_ =
      std::min(options_.maxZoom.value_or(options_.fixed ? finestZoom_ : finestZoom_ + 6), 30);
  if (plan) {
    mosaicZoom_ = plan->mosaicZoom;
  } else if (!options_.fixed) {
    mosaicZoom_ =
        mosaicZoomFor(tin.vertices.size(), options_.mosaicPoints, std::min(finestZoom_, maxZoom_));
  }
  if (options_.mosaicError) {
    edgeAllowance_ = options_.mosaicError(TileId{});
    if (!(edgeAllowance_ >= 0) || !std::isfinite(edgeAllowance_))
      throw internalError("Tiler: the mosaic's largest error is " + std::to_string(edgeAllowance_));
  }
  if (plan && plan->zoomLines.size() != static_cast<std::size_t>(finestZoom_) + 1)
    throw internalError("Tiler: the plan's lines are not one set a zoom to the finest");
  index_.emplace(tin);
}

double Tiler::sagRadius(const Rect& square) const {
  if (!options_.geo) return kEarthRadiusOfCurvature;
  const Rect part{std::max(square.x0, extent_.x0), std::max(square.y0, extent_.y0),
                  std::min(square.x1, extent_.x1), std::min(square.y1, extent_.y1)};
  const bool meets = part.x0 <= part.x1 && part.y0 <= part.y1;
  return chordSagRadius(*options_.geo, meets ? part : square);
}

Rect tilerReadRegion(const Rect& region) {
  const double grow = std::max(1.0, 1e-5 * std::max(region.width(), region.height()));
  return {region.x0 - grow, region.y0 - grow, region.x1 + grow, region.y1 + grow};
}

Rect tilerVertexRegion(const TilerPlan& plan, const Rect& region) {
  const Rect read = tilerReadRegion(region);
  const double finer = std::ldexp(plan.geometry.size(), -(plan.cornerZoom + 1));
  const double grow = kOffTinReach * std::min(region.width(), finer);
  return {read.x0 - grow, read.y0 - grow, read.x1 + grow, read.y1 + grow};
}

TilerPlan Tiler::plan(int cornerZoom) const {
  if (options_.plan) return *options_.plan;
  if (cornerZoom > kMaxCornerZoom)
    throw internalError("Tiler::plan: corners to zoom " + std::to_string(cornerZoom) +
                        ", more than " + std::to_string(kMaxCornerZoom));
  TilerPlan p;
  p.geometry = geometry_;
  p.extent = extent_;
  p.finestZoom = finestZoom_;
  p.fitSpacing = fitSpacing_;
  p.tileFitAllData = tileFitAllData_;
  p.mosaicZoom = mosaicZoom_;
  for (int z = 0; z <= finestZoom_; ++z) p.zoomLines.push_back(simplifiedLines(z));
  // A corner more than a tile width from the TIN's box is left out: the
  // four tiles at it hold no terrain, whatever z it has.
  p.cornerZoom = std::max(cornerZoom, -1);
  const Rect& extent = extent_;
  for (int z = 0; z <= p.cornerZoom; ++z) {
    const double width = std::ldexp(geometry_.size(), -z);
    const Rect near{extent.x0 - width, extent.y0 - width, extent.x1 + width, extent.y1 + width};
    const std::uint32_t lines = (1U << z) + 1;
    for (std::uint32_t row = 0; row < lines; ++row) {
      for (std::uint32_t column = 0; column < lines; ++column) {
        const Point2 corner{geometry_.lineX(z, column), geometry_.lineY(z, row)};
        if (!near.contains(corner) || index_->z(corner)) continue;
        p.offTinCorners.push_back({z, row, column, offTinZ(z, column, row)});
      }
    }
  }
  return p;
}

Tiler::Planning Tiler::planFinestZoom() const {
  // The first zoom whose tiles hold the finest fit's triangles within a
  // quarter of the budget each, on average over the square. Zooms below it
  // keep the finest tolerance: they exist only where a tile of the planned
  // finest zoom cannot meet it within levelsPerTile levels.
  const int cap = std::min(options_.maxZoom.value_or(20) + levelsPerTile_,
                           fit::BinaryTriangulation::kMaxGridLevels - 1);
  const std::span<const Point3> data = tileFitData();
  // One square's fit (fewer than 3 points, or points on one line — a
  // raster's last row alone past a square's side — have nothing to fit): a
  // square of zoom k is the whole square's binary triangulation from level
  // k on, so it refines to cap − k.
  std::size_t finestTriangles = 0;
  const auto fitSquare = [&](std::span<const Point3> points, const TileId& id) {
    const double size = std::ldexp(geometry_.size(), -id.z);
    if (points.size() < 3 || onOneLine(points, 1e-4 * size)) return;
    const Rect square = geometry_.bounds(id);
    const auto planning = fit::fitMultilevel(
        points, binaryFitOptions(options_, {square.x0, square.y0}, size, options_.tolerance,
                                 cap - id.z, options_.threads));
    finestTriangles += planning.levels().back().triangles;
  };
  const std::size_t cellPoints = std::max<std::size_t>(options_.planningCellPoints, 1);
  int cellZoom = 0;
  if (data.size() <= cellPoints) {
    fitSquare(data, {});
  } else {
    if (data.size() > std::numeric_limits<std::uint32_t>::max())
      throw inputError("the TIN holds more than 2^32 fit points", {},
                       "tile it in parts (tinsmith slurm) or thin it");
    // Each point's square at kMaxCellZoom, whose squares make up those of
    // every zoom above (their sides are the same doubles,
    // PyramidGeometry::lineX); a point on a side goes to the square above
    // or right of it.
    constexpr int kMaxCellZoom = 10;
    const std::uint64_t finest = std::uint64_t{1} << kMaxCellZoom;
    const auto indexOf = [&](double v, double origin, auto&& lineAt) {
      const double u = (v - origin) / geometry_.size() * static_cast<double>(finest);
      auto k = static_cast<std::uint64_t>(
          std::clamp(std::floor(u), 0.0, static_cast<double>(finest - 1)));
      while (k > 0 && v < lineAt(k)) --k;
      while (k + 1 < finest && v >= lineAt(k + 1)) ++k;
      return static_cast<std::uint32_t>(k);
    };
    std::vector<std::uint32_t> column(data.size()), row(data.size());
    for (std::size_t i = 0; i < data.size(); ++i) {
      column[i] = indexOf(data[i].x, geometry_.origin().x,
                          [&](std::uint64_t k) { return geometry_.lineX(kMaxCellZoom, k); });
      row[i] = indexOf(data[i].y, geometry_.origin().y,
                       [&](std::uint64_t k) { return geometry_.lineY(kMaxCellZoom, k); });
    }
    // The first zoom whose fullest square holds at most cellPoints (a
    // strip fills one row of squares: the average would understate it).
    std::vector<std::uint32_t> start;
    const auto squareOf = [&](std::size_t i) {
      const int shift = kMaxCellZoom - cellZoom;
      return (static_cast<std::size_t>(row[i] >> shift) << cellZoom) + (column[i] >> shift);
    };
    for (cellZoom = 1;; ++cellZoom) {
      start.assign((std::size_t{1} << (2 * cellZoom)) + 1, 0);
      for (std::size_t i = 0; i < data.size(); ++i) ++start[squareOf(i) + 1];
      if (cellZoom == kMaxCellZoom || *std::max_element(start.begin(), start.end()) <= cellPoints)
        break;
    }
    // Each square's points in the data's order (a counting sort by square).
    const std::size_t squares = start.size() - 1;
    for (std::size_t c = 0; c < squares; ++c) start[c + 1] += start[c];
    std::vector<std::uint32_t> order(data.size());
    {
      std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
      for (std::size_t i = 0; i < data.size(); ++i)
        order[next[squareOf(i)]++] = static_cast<std::uint32_t>(i);
    }
    std::vector<std::uint32_t>().swap(column);
    std::vector<std::uint32_t>().swap(row);
    std::vector<Point3> points;
    const std::uint32_t n = 1U << cellZoom;
    for (std::size_t c = 0; c < squares; ++c) {
      points.clear();
      for (std::uint32_t k = start[c]; k < start[c + 1]; ++k) points.push_back(data[order[k]]);
      fitSquare(points,
                {cellZoom, static_cast<std::uint32_t>(c) % n, static_cast<std::uint32_t>(c) / n});
    }
  }
  const double perTile = static_cast<double>(options_.maxTriangles) / 4.0;
  int zmax = 0;
  while (zmax < options_.maxZoom.value_or(20) &&
         static_cast<double>(finestTriangles) > perTile * std::pow(4.0, zmax))
    ++zmax;
  return {zmax, cellZoom, finestTriangles};
}

Tiler::~Tiler() = default;

double Tiler::zoomTolerance(int z) const {
  return std::ldexp(options_.tolerance, std::max(0, finestZoom_ - z));
}

double Tiler::edgeTolerance(int z) const {
  const double tolerance = zoomTolerance(z);
  return kEdgeShare * (tolerance - std::min(edgeAllowance_, 0.5 * tolerance));
}

const Tiler::Zoom& Tiler::zoom(int z) const {
  ZoomSlot& slot = zooms_.at(static_cast<std::size_t>(z));
  std::call_once(slot.once, [&] { slot.zoom = makeZoom(z); });
  return *slot.zoom;
}

std::unique_ptr<Tiler::Zoom> Tiler::makeZoom(int z) const {
  auto zd = std::make_unique<Zoom>();
  zd->tolerance = zoomTolerance(z);
  // A line vertex within rounding of one of the zoom's tile sides goes onto
  // it exactly: a raster's boundary runs along the same rows and columns as
  // the tile sides (both are whole cells from its corner), and a vertex an
  // ulp off a side made a sliver with it in one tile and a different crossing
  // in its neighbour. Both tiles see the snapped vertex on their side.
  const double near = 1e-9 * geometry_.size();
  const std::vector<TerrainLine>* simplified = nullptr;
  std::vector<TerrainLine> coarser;  // this zoom's own, above the finest
  if (options_.plan) {
    simplified = &options_.plan->zoomLines[static_cast<std::size_t>(std::min(z, finestZoom_))];
  } else if (z >= finestZoom_) {  // zoomTolerance(z) is the finest tolerance
    std::call_once(finestLinesOnce_, [&] { finestLines_ = simplifiedLines(z); });
    simplified = &finestLines_;
  } else {
    coarser = simplifiedLines(z);
    simplified = &coarser;
  }
  // A Tiler of a region leaves out the break lines that miss it; every ring
  // stays, as a tile's inside test counts the crossings of them all.
  for (const auto& line : *simplified) {
    if (options_.region && !line.ring && !within_.overlaps(boundsOf(line.points))) continue;
    TerrainLine snapped = line;
    auto& pts = snapped.points;
    for (auto& p : pts) {
      const Point2 q = geometry_.snapToLines(z, p.xy(), near);
      p.x = q.x;
      p.y = q.y;
    }
    pts.erase(
        std::unique(pts.begin(), pts.end(),
                    [](const Point3& a, const Point3& b) { return a.x == b.x && a.y == b.y; }),
        pts.end());
    if (pts.size() < (snapped.closed ? 3U : 2U)) continue;
    zd->lineBoxes.push_back(boundsOf(snapped.points));
    zd->lines.push_back(std::move(snapped));
  }
  return zd;
}

std::vector<TerrainLine> Tiler::simplifiedLines(int z) const {
  // A chord must stay on the TIN too: a shore simplified across a steep bank
  // would otherwise sit metres off the ground it crosses, at every zoom.
  std::vector<TinIndex::SectionPoint> section;
  const ChordError offTin = [&](const Point3& a, const Point3& b) {
    index_->section(a.xy(), b.xy(), section);
    double worst = 0.0;
    for (const auto& sp : section) {
      if (!std::isnan(sp.z)) worst = std::max(worst, std::abs(sp.z - (a.z + sp.t * (b.z - a.z))));
    }
    return worst;
  };
  std::vector<TerrainLine> out;
  out.reserve(lines_.size());
  for (const auto& line : lines_) out.push_back(simplify(line, edgeTolerance(z), offTin));
  return out;
}

TileSurface Tiler::buildTile(const TileId& id, double encodingAllowance) const {
  if (!geometry_.inside(id)) throw usageError("tile " + id.name() + " is outside the pyramid");
  const Zoom& zd = zoom(id.z);
  const Rect rect = geometry_.bounds(id);
  const std::optional<fit::MultilevelFit> fit = tileFit(id, zd.tolerance);
  const double radius = sagRadius(rect);
  const TileInput input = tileInput(id, zd, fit ? &*fit : nullptr, radius);
  TileSurface tile = triangulateTile(id, rect, input, zd.lines);
  if (tile.empty()) return tile;
  fitTile(tile, fit ? &*fit : nullptr);
  // Where the fit misses the zoom's tolerance, the TIN's points, worst first.
  // They stay off the sides (which hold the TIN's section already and are
  // shared with the neighbour) by the side margin.
  // Each triangle's chord sag counts (the content is straight triangles on
  // the curved Earth), and encoding keeps its share of the tolerance.
  const double mosaicError = options_.mosaicError ? options_.mosaicError(id) : 0.0;
  if (!(mosaicError >= 0) || !std::isfinite(mosaicError))
    throw internalError("Tiler: the mosaic's error under tile " + id.name() + " is " +
                        std::to_string(mosaicError));
  RefineOptions refine;
  refine.tolerance = std::max((1 - kEncodingShare) * zd.tolerance - encodingAllowance - mosaicError,
                              0.5 * (1 - kEncodingShare) * zd.tolerance);
  refine.maxTriangles = options_.maxTriangles;
  refine.sideMargin = sideMargin(rect, zd.tolerance);
  refine.earthRadius = radius;
  tile.heldPoints = refineTile(tile, *index_, refine);
  tile.tolerance = zd.tolerance;
  if (mosaicError > 0) {
    tile.error += mosaicError;
    for (double& e : tile.triangleErrors) e += mosaicError;
  }
  return tile;
}

std::optional<fit::MultilevelFit> Tiler::tileFit(const TileId& id, double tolerance) const {
  const Rect rect = geometry_.bounds(id);
  std::vector<std::uint32_t> inTile;
  const std::span<const Point3> data = tileFitData();
  (tileFitIsData_ ? dataGrid_ : tileFitGrid_)
      .forEachInBox(rect.x0, rect.y0, rect.x1, rect.y1, [&](std::uint32_t i) {
        if (rect.contains(data[i].xy())) inTile.push_back(i);
      });
  if (inTile.size() < 3) return std::nullopt;
  // The data's order, whatever the grid's. A tile holding all the data (the
  // root, most often) fits them where they are, not a copy of them.
  std::vector<Point3> copied;
  std::span<const Point3> points = data;
  if (inTile.size() < data.size()) {
    std::sort(inTile.begin(), inTile.end());
    copied.reserve(inTile.size());
    for (const std::uint32_t i : inTile) copied.push_back(data[i]);
    points = copied;
  }
  std::vector<std::uint32_t>().swap(inTile);
  // Thin-plate smoothing leaves planes free: data on one line (a raster's
  // row along the tile's side, straight or nearly) cannot fix the slope
  // across it, and the system is singular.
  if (onOneLine(points, 1e-4 * rect.width())) return std::nullopt;
  // One thread: the tiles are built in parallel (and a fit's result does not
  // depend on its thread count).
  return fit::fitMultilevel(points,
                            binaryFitOptions(options_, {rect.x0, rect.y0},
                                           std::ldexp(geometry_.size(), -id.z), tolerance,
                                           levelsPerTile_, 1));
}

double Tiler::fitZ(const fit::MultilevelFit* fit, Point2 p) const {
  if (fit) {
    const auto& mesh = fit->mesh();
    const Point2 o = mesh.origin();
    const double size = mesh.size();
    return fit->evaluate({std::clamp(p.x, o.x, o.x + size), std::clamp(p.y, o.y, o.y + size)});
  }
  return index_->z(p).value_or(0.0);
}

double Tiler::offTinZ(int z, std::uint64_t column, std::uint64_t row) const {
  // A Tiler of a region takes the plan's corners, made from the whole TIN;
  // one the plan leaves out lies more than a tile width from the TIN's box,
  // so every tile at it is empty and its z does not matter.
  const TilerPlan* plan = options_.plan.get();
  if (options_.region && z <= plan->cornerZoom) {
    const TilerPlan::OffTinCorner wanted{z, static_cast<std::uint32_t>(row),
                                         static_cast<std::uint32_t>(column), 0.0};
    const auto& corners = plan->offTinCorners;
    const auto found =
        std::lower_bound(corners.begin(), corners.end(), wanted,
                         [](const auto& a, const auto& b) { return a.key() < b.key(); });
    return found == corners.end() || found->key() != wanted.key() ? 0.0 : found->z;
  }
  // The nearest TIN vertex's z (the lowest index among equally near ones),
  // looked for in boxes that grow with the zoom's tile width: the same in
  // every tile that holds the corner.
  const Point2 p{geometry_.lineX(z, column), geometry_.lineY(z, row)};
  const double width = std::ldexp(geometry_.size(), -z);
  std::vector<std::uint32_t> found;
  for (double r = width / 64; r <= kOffTinReach * width; r *= 2) {
    index_->verticesIn({p.x - r, p.y - r, p.x + r, p.y + r}, found);
    if (found.empty()) continue;
    std::uint32_t best = found.front();
    double bestD = std::numeric_limits<double>::infinity();
    for (const std::uint32_t v : found) {
      const Point3& q = tin_.vertices[v];
      const double d = std::hypot(q.x - p.x, q.y - p.y);
      if (d < bestD || (d == bestD && v < best)) {
        bestD = d;
        best = v;
      }
    }
    return tin_.vertices[best].z;
  }
  return 0.0;
}

Tiler::TileInput Tiler::tileInput(const TileId& id, const Zoom& zd, const fit::MultilevelFit* fit,
                                  double radius) const {
  const Rect rect = geometry_.bounds(id);
  const double snap = rect.width() * 1e-9;
  TileInput input;

  // The lines in this tile.
  for (std::size_t i = 0; i < zd.lines.size(); ++i) {
    if (!zd.lineBoxes[i].overlaps(rect)) continue;
    for (auto& piece : clipToRect(zd.lines[i], rect, snap)) input.lines.push_back(std::move(piece));
  }

  // The tile fit's vertices inside the tile, on the pyramid's grid lines
  // (the same doubles as the tile's sides). Those on a side are left out:
  // another tile's fit does not have them, and the side is the TIN's section.
  if (fit) {
    const auto& mesh = fit->mesh();
    const int gridLevels = mesh.gridLevels();
    const auto zValues = fit->vertexZ();
    const std::uint64_t column0 = static_cast<std::uint64_t>(id.x) << gridLevels;
    const std::uint64_t row0 = static_cast<std::uint64_t>(id.y) << gridLevels;
    const std::uint64_t last = 1ULL << gridLevels;
    for (const std::uint64_t key : mesh.activeKeys()) {
      const std::uint64_t i = mesh.column(key), j = mesh.row(key);
      if (i == 0 || j == 0 || i == last || j == last) continue;
      input.interior.push_back({geometry_.lineX(id.z + gridLevels, column0 + i),
                                geometry_.lineY(id.z + gridLevels, row0 + j),
                                zValues[mesh.vertexId(key)]});
    }
  }
  // Side points: the corners and the lines' crossings.
  std::array<std::vector<SidePoint>, 4> sides;  // south, east, north, west
  auto addToSides = [&](const Point3& p, bool onLine) {
    if (p.y == rect.y0) sides[0].push_back({p.x, p, onLine});
    if (p.x == rect.x1) sides[1].push_back({p.y, p, onLine});
    if (p.y == rect.y1) sides[2].push_back({p.x, p, onLine});
    if (p.x == rect.x0) sides[3].push_back({p.y, p, onLine});
  };
  for (const double y : {rect.y0, rect.y1}) {
    for (const double x : {rect.x0, rect.x1}) addToSides({x, y, 0.0}, false);
  }
  for (const auto& piece : input.lines) {
    for (const auto& p : piece.points) addToSides(p, true);
  }
  // A line vertex on a side is kept there even when the line only touches
  // the tile (both its segments in the neighbour, so no piece was clipped
  // here): the neighbour keeps it, and a side without it would be a crack.
  for (std::size_t i = 0; i < zd.lines.size(); ++i) {
    if (!zd.lineBoxes[i].overlaps(rect)) continue;
    for (const auto& p : zd.lines[i].points) {
      if (rect.contains(p.xy()) &&
          (p.x == rect.x0 || p.x == rect.x1 || p.y == rect.y0 || p.y == rect.y1))
        addToSides(p, true);
    }
  }

  // Each side is the TIN's section along it, simplified (vertically, to
  // edgeTolerance, and with the TIN's step to the lines
  // the side margin away on either hand: simplifyProfile) between the points
  // it must keep; those take the TIN's z (the fit's outside the TIN), a
  // line's crossing the line's. Both tiles sharing a side compute it from the
  // same inputs in the same direction (west to east, south to north), so they
  // get the same vertices.
  SectionProfile onSide, left, right;
  std::vector<SideSample> samples, kept;
  std::array<std::vector<Point3>, 4> sideLines;
  const double margin = sideMargin(rect, zd.tolerance);
  for (int k = 0; k < 4; ++k) {
    auto& side = sides[k];
    const bool horizontal = k == 0 || k == 2;
    // L² / 8R within kSideSagShare of the tolerance, R the smaller of the two
    // tiles' that share the side, so that both cut it alike (a side on the
    // pyramid's edge: its one tile's).
    const double w = rect.width(), h = rect.height();
    const Rect across = k == 0   ? Rect{rect.x0, rect.y0 - h, rect.x1, rect.y0}
                        : k == 1 ? Rect{rect.x1, rect.y0, rect.x1 + w, rect.y1}
                        : k == 2 ? Rect{rect.x0, rect.y1, rect.x1, rect.y1 + h}
                                 : Rect{rect.x0 - w, rect.y0, rect.x0, rect.y1};
    const Rect square = geometry_.bounds({});
    const bool shared = across.x0 >= square.x0 && across.x1 <= square.x1 &&
                        across.y0 >= square.y0 && across.y1 <= square.y1;
    const double sideRadius = shared ? std::min(radius, sagRadius(across)) : radius;
    const double maxSideChord = std::sqrt(8 * sideRadius * kSideSagShare * zd.tolerance);
    const double fixed = k == 0 ? rect.y0 : k == 1 ? rect.x1 : k == 2 ? rect.y1 : rect.x0;
    const double u0 = horizontal ? rect.x0 : rect.y0, u1 = horizontal ? rect.x1 : rect.y1;
    auto at = [&](double u, double offset = 0.0) {
      return horizontal ? Point2{u, fixed + offset} : Point2{fixed + offset, u};
    };
    onSide.take(*index_, at(u0), at(u1), u0, u1);
    left.take(*index_, at(u0, -margin), at(u1, -margin), u0, u1);
    right.take(*index_, at(u0, margin), at(u1, margin), u0, u1);
    auto tinZ = [&](double u) { return onSide.at(u); };
    // Inside the corners' squares of the margin no vertex can be added at
    // all, so a step's kink there (where a TIN edge from the corner crosses
    // a margin line) is not kept: the kept point would make a square whose
    // diagonal is the Delaunay tie's, not the TIN's.
    auto sample = [&](double u, double z, bool end = false) {
      const auto zs = onSide.at(u), zl = left.at(u), zr = right.at(u);
      const double nan = std::nan("");
      if (!end && (u < u0 + 2 * margin || u > u1 - 2 * margin)) return SideSample{u, z, nan, nan};
      return SideSample{u, z, zs && zl ? *zl - *zs : nan, zs && zr ? *zr - *zs : nan};
    };
    // The side's profile: every point of the three sections, by position.
    samples.clear();
    std::vector<double> positions;
    for (const auto* profile : {&onSide, &left, &right})
      for (const auto& [u, z] : profile->points()) positions.push_back(u);
    std::sort(positions.begin(), positions.end());
    positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
    for (const double u : positions) {
      const auto z = tinZ(u);
      if (z) samples.push_back(sample(u, *z));
    }
    // Along the side; at equal positions a line point wins (its z is the line's).
    std::stable_sort(side.begin(), side.end(), [](const SidePoint& a, const SidePoint& b) {
      return a.along < b.along || (a.along == b.along && a.onLine > b.onLine);
    });
    std::vector<SidePoint> must;
    for (const auto& sp : side) {
      if (!must.empty() && must.back().along == sp.along) continue;
      must.push_back(sp);
      if (!sp.onLine) {
        // A corner: the TIN at the point (it is on two sides of each of
        // four tiles, whose sections reach it in different arithmetic),
        // else — off the TIN — the nearest TIN vertex's z.
        const auto z = index_->z(sp.p.xy());
        must.back().p.z = z ? *z
                            : offTinZ(id.z, id.x + (sp.p.x == rect.x1 ? 1U : 0U),
                                      id.y + (sp.p.y == rect.y1 ? 1U : 0U));
      }
    }
    auto& out = sideLines[k];
    out.push_back(must.front().p);
    auto first = samples.begin();
    for (std::size_t m = 1; m < must.size(); ++m) {
      const double ua = must[m - 1].along, ub = must[m].along;
      const double gap = (ub - ua) * 1e-9;
      while (first != samples.end() && first->along <= ua + gap) ++first;
      auto last = first;
      while (last != samples.end() && last->along < ub - gap) ++last;
      kept.clear();
      const SideSample end = sample(ub, must[m].p.z, true);
      simplifyProfile(std::span<const SideSample>(first, last), sample(ua, must[m - 1].p.z, true),
                      end, edgeTolerance(id.z), kept);
      kept.push_back(end);
      // Chords too long for the Earth's curvature are cut evenly, each cut
      // on the TIN (the chord's line off it): from the same doubles in both
      // tiles sharing the side.
      std::pair<double, double> from{ua, must[m - 1].p.z};
      for (const auto& to : kept) {
        const auto pieces = std::ceil((to.along - from.first) / maxSideChord);
        for (double k = 1; k < pieces; ++k) {
          const double u = from.first + (to.along - from.first) * (k / pieces);
          const auto z = tinZ(u);
          const Point2 q = at(u);
          out.push_back({q.x, q.y, z ? *z : from.second + (to.z - from.second) * (k / pieces)});
        }
        if (to.along != ub) {
          const Point2 q = at(to.along);
          out.push_back({q.x, q.y, to.z});
        }
        from = {to.along, to.z};
      }
      out.push_back(must[m].p);
      first = last;
    }
  }
  // The ring, CCW: south and east as computed, north and west reversed.
  std::reverse(sideLines[2].begin(), sideLines[2].end());
  std::reverse(sideLines[3].begin(), sideLines[3].end());
  for (const auto& side : sideLines) {
    for (const Point3& p : side) {
      if (!input.ring.empty() && input.ring.back().x == p.x && input.ring.back().y == p.y) continue;
      input.ring.push_back(p);
    }
  }
  if (input.ring.size() > 1 && input.ring.front().x == input.ring.back().x &&
      input.ring.front().y == input.ring.back().y)
    input.ring.pop_back();
  return input;
}

TileSurface Tiler::triangulateTile(const TileId& id, const Rect& rect, const TileInput& input,
                                   const std::vector<TerrainLine>& zoomLines) const {
  TileSurface tile;
  tile.id = id;
  tile.bounds = rect;

  // Lines first: a vertex where a ring (priority 0, as the sides and pins)
  // meets a side point or a pin takes the earlier feature's z, the line's.
  Cdt cdt(CdtOptions{});
  std::vector<FeatureId> lineFeature;
  for (const auto& piece : input.lines) {
    lineFeature.push_back(cdt.addFeature(piece.ring ? FeatureKind::Boundary : piece.kind, "line"));
  }
  const FeatureId sideFeature = cdt.addFeature(FeatureKind::Other, "tile side");
  const FeatureId binaryFeature = cdt.addFeature(FeatureKind::Raster, "tile fit");
  cdt.insertConstraint(input.ring, sideFeature, true);
  for (std::size_t i = 0; i < input.lines.size(); ++i) {
    cdt.insertConstraint(input.lines[i].points, lineFeature[i], input.lines[i].closed);
  }
  const VertexId firstBinary =
      input.interior.empty() ? VertexId() : cdt.insertPoints(input.interior, binaryFeature);
  cdt.finalize();
  const Mesh& cm = cdt.mesh();
  std::vector<Point3> points = cm.points();

  // Which vertices are held (on a line, a ring or a side), and where the
  // domain boundary runs.
  const std::size_t nv = cm.vertexCount(), nt = cm.triangleCount();
  auto hasKind = [&](HalfedgeId h, auto&& test) {
    for (std::uint32_t f : cm.edgeFeatures(h)) {
      if (test(cm.features()[f].kind)) return true;
    }
    return false;
  };
  auto isRingEdge = [&](HalfedgeId h) {
    return hasKind(h, [](FeatureKind k) { return k == FeatureKind::Boundary; });
  };
  std::vector<std::uint8_t> flags(nv, 0);
  for (std::uint32_t h = 0; h < cm.halfedgeCount(); ++h) {
    if (!hasKind(HalfedgeId(h), [](FeatureKind k) { return k != FeatureKind::Raster; })) continue;
    flags[cm.origin(HalfedgeId(h)).value] |= kHeld;
    flags[cm.target(HalfedgeId(h)).value] |= kHeld;
  }
  // A binary vertex that a line or ring runs through exactly (a raster's
  // boundary along the grid's rows) is held as part of it: with the TIN's z,
  // not the fit's (a vertex merged into a line's already has the line's).
  for (std::size_t k = 0; k < input.interior.size(); ++k) {
    const VertexId v = cdt.meshVertex(VertexId(firstBinary.value + static_cast<std::uint32_t>(k)));
    if (!v.valid() || !(flags[v.value] & kHeld) || points[v.value].z != input.interior[k].z)
      continue;
    if (const auto z = index_->z(points[v.value].xy())) points[v.value].z = *z;
  }
  for (std::size_t v = 0; v < nv; ++v) {
    const Point3& p = points[v];
    if (p.x == rect.x0) flags[v] |= kSideWest;
    if (p.x == rect.x1) flags[v] |= kSideEast;
    if (p.y == rect.y0) flags[v] |= kSideSouth;
    if (p.y == rect.y1) flags[v] |= kSideNorth;
  }
  // Keep the triangles inside the TIN's (simplified) domain: components
  // bounded by ring edges, each classified once by even-odd.
  std::vector<int> keep(nt, -1);
  for (std::uint32_t seed = 0; seed < nt; ++seed) {
    if (keep[seed] >= 0) continue;
    const auto corners = cm.vertices(TriangleId(seed));
    const Point2 centroid{
        (points[corners[0].value].x + points[corners[1].value].x + points[corners[2].value].x) / 3,
        (points[corners[0].value].y + points[corners[1].value].y + points[corners[2].value].y) / 3};
    const int inside = insideRings(centroid, zoomLines) ? 1 : 0;
    std::vector<std::uint32_t> stack{seed};
    keep[seed] = inside;
    while (!stack.empty()) {
      const std::uint32_t t = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const HalfedgeId h = Mesh::halfedge(TriangleId(t), i);
        if (cm.isBoundary(h) || isRingEdge(h)) continue;
        const std::uint32_t across = Mesh::triangle(cm.twin(h)).value;
        if (keep[across] >= 0) continue;
        keep[across] = inside;
        stack.push_back(across);
      }
    }
  }
  std::vector<std::uint32_t> remap(nv, std::numeric_limits<std::uint32_t>::max());
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (keep[t] != 1) continue;
    std::array<std::uint32_t, 3> tri{};
    const auto corners = cm.vertices(TriangleId(t));
    std::uint8_t held = 0, river = 0;
    for (int i = 0; i < 3; ++i) {
      const HalfedgeId h = Mesh::halfedge(TriangleId(t), i);
      if (cm.isConstrained(h)) held |= 1U << i;
      if (hasKind(h, [](FeatureKind k) { return k == FeatureKind::River; })) river |= 1U << i;
    }
    tile.heldEdges.push_back(held);
    tile.riverEdges.push_back(river);
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t v = corners[i].value;
      std::uint32_t& r = remap[v];
      if (r == std::numeric_limits<std::uint32_t>::max()) {
        r = static_cast<std::uint32_t>(tile.vertices.size());
        tile.vertices.push_back(points[v]);
        tile.flags.push_back(flags[v]);
      }
      tri[i] = r;
    }
    tile.triangles.push_back(tri);
  }
  for (std::size_t v = 0; v < tile.vertices.size(); ++v) {
    const bool onSide = (tile.flags[v] & 15) != 0;
    if ((tile.flags[v] & kHeld) && !onSide) ++tile.breakLineVertices;
    if (onSide) tile.flags[v] |= kHeld;  // sides keep the TIN's (or the line's) z
  }
  return tile;
}

void Tiler::fitTile(TileSurface& tile, const fit::MultilevelFit* fit) const {
  // The constrained least-squares fit (8.9) over the tile's mesh.
  const Rect& rect = tile.bounds;
  TinData local;
  local.vertices = tile.vertices;
  for (auto& v : local.vertices) {
    v.x -= rect.x0;
    v.y -= rect.y0;
  }
  for (const auto& t : tile.triangles) local.triangles.push_back(t);
  // A sample names its triangle by index into local.triangles: Surface keeps
  // TinData's triangle order (it drops none of a valid CDT mesh's).
  const Surface surface(local);
  std::vector<fit::Sample> samples;
  TriangleId hint;
  std::vector<std::uint32_t> inTile;
  dataGrid_.forEachInBox(rect.x0, rect.y0, rect.x1, rect.y1, [&](std::uint32_t i) {
    if (rect.contains(data_[i].xy())) inTile.push_back(i);
  });
  std::sort(inTile.begin(), inTile.end());  // the data's order, whatever the grid's
  // A coarse tile over dense data (a DEM's every cell) fits a thinned share,
  // every k-th point in the data's order: a few per triangle of the budget
  // fix its shape as well, and the held TIN points meet the tolerance.
  const std::size_t cap = 4 * options_.maxTriangles;
  const std::size_t stride = (inTile.size() + cap - 1) / cap;
  if (stride > 1) {
    std::size_t kept = 0;
    for (std::size_t k = 0; k < inTile.size(); k += stride) inTile[kept++] = inTile[k];
    inTile.resize(kept);
  }
  // Sized once (a point each, and a prior for each vertex, below): grown by
  // doubling it held up to three times its 48 bytes a sample at once, a
  // subtree shard's largest holding (19 MB of 131 k points).
  samples.reserve(inTile.size() + tile.vertices.size());
  for (std::uint32_t i : inTile) {
    const Point3& p = data_[i];
    const auto loc = surface.locate({p.x - rect.x0, p.y - rect.y0}, hint);
    if (!loc) continue;
    hint = loc->triangle;
    samples.push_back({loc->triangle.value, loc->weights, p.z, 1.0});
  }
  tile.dataPoints = samples.size();
  // Each free vertex also carries the tile fit's value as a weak sample, so
  // a vertex with no data in its triangles (slivers beside a break line make
  // λ_d small) stays near the fit's surface instead of being undetermined.
  constexpr double kPriorWeight = 0.25;
  std::vector<Point2> xy;
  xy.reserve(local.vertices.size());
  for (const auto& v : local.vertices) xy.push_back(v.xy());
  fit::LeastSquaresOptions ls;
  // The umbrella operator: the tile meshes have slivers beside lines and
  // sides, where the thin-plate energy's 1/area weights would dominate.
  ls.smoothing = fit::Smoothing::UmbrellaWeighted;
  ls.lambdaFactor = options_.lambdaFactor;
  std::size_t freeCount = 0;
  fit::Vector initial(static_cast<Eigen::Index>(tile.vertices.size()));
  for (std::uint32_t v = 0; v < tile.vertices.size(); ++v) {
    if (tile.flags[v] & kHeld) {
      ls.fixed.push_back({v, tile.vertices[v].z});
    } else {
      ++freeCount;
      tile.vertices[v].z = fitZ(fit, tile.vertices[v].xy());
      const auto loc = surface.locate(xy[v], hint);
      if (loc) {
        hint = loc->triangle;
        samples.push_back({loc->triangle.value, loc->weights, tile.vertices[v].z, kPriorWeight});
      }
    }
    initial[v] = tile.vertices[v].z;
  }
  if (freeCount > 0 && !samples.empty()) {
    ls.solver = tile.vertices.size() <= 40000 ? fit::SolverKind::Direct
                                              : fit::SolverKind::ConjugateGradient;
    const auto result = fit::fitLeastSquares(xy, local.triangles, samples, ls, initial);
    for (std::uint32_t v = 0; v < tile.vertices.size(); ++v) {
      if (!(tile.flags[v] & kHeld)) tile.vertices[v].z = result.coefficients[v];
    }
  }
}

}  // namespace tinsmith::tiles
