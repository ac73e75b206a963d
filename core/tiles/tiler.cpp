#include "core/tiles/tiler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/fit/least_squares.hpp"
#include "core/surface/surface.hpp"

namespace tinsmith::tiles {

/// What every tile of one zoom shares: the zoom's fit and the lines
/// simplified to its tolerance (with their bounding boxes).
struct Tiler::Zoom {
  double tolerance = 0;
  std::unique_ptr<fit::MultilevelFit> fit;
  std::vector<TerrainLine> lines;
  std::vector<Rect> lineBoxes;
};

namespace {

/// The data the fits see: the TIN's vertices, plus points sampled from its
/// triangles where its vertices are sparse (a triangle whose longest edge
/// exceeds twice the median edge gets the interior points of a barycentric
/// grid at about the median edge's spacing, z on the triangle's plane).
/// `zoomFit` leaves out what the tile meshes hold exactly — vertices of break
/// lines, and samples of the triangles at them —
/// so a zoom's binary fit is not driven to tiny cells by the steps a break
/// line makes (a river lowered below its banks); the tiles' own fits use it all.
struct FitData {
  std::vector<Point3> all;
  std::vector<Point3> zoomFit;
};

FitData fitData(const TinData& tin) {
  FitData data;
  data.all = tin.vertices;
  std::vector<char> held(tin.vertices.size(), 0);
  for (const auto& e : tin.constrainedEdges) {
    if (e.feature < tin.features.size() && isBreakLineKind(tin.features[e.feature].kind))
      held[e.a] = held[e.b] = 1;
  }
  for (std::size_t v = 0; v < tin.vertices.size(); ++v)
    if (!held[v]) data.zoomFit.push_back(tin.vertices[v]);
  std::vector<double> lengths;
  lengths.reserve(tin.triangles.size());
  for (std::size_t k = 0; k < tin.triangles.size();
       k += std::max<std::size_t>(1, tin.triangles.size() / 20000)) {
    const auto& t = tin.triangles[k];
    const Point3& a = tin.vertices[t[0]];
    const Point3& b = tin.vertices[t[1]];
    lengths.push_back(std::hypot(b.x - a.x, b.y - a.y));
  }
  if (lengths.empty()) return data;
  std::nth_element(lengths.begin(),
                   lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2),
                   lengths.end());
  const double spacing = lengths[lengths.size() / 2];
  if (!(spacing > 0)) return data;
  for (const auto& t : tin.triangles) {
    const Point3& a = tin.vertices[t[0]];
    const Point3& b = tin.vertices[t[1]];
    const Point3& c = tin.vertices[t[2]];
    const double longest =
        std::max({std::hypot(b.x - a.x, b.y - a.y), std::hypot(c.x - b.x, c.y - b.y),
                  std::hypot(a.x - c.x, a.y - c.y)});
    if (longest <= 2 * spacing) continue;
    const bool nearHeld = held[t[0]] || held[t[1]] || held[t[2]];
    const int n = static_cast<int>(std::min(64.0, std::ceil(longest / spacing)));
    for (int i = 1; i < n; ++i) {
      for (int j = 1; i + j < n; ++j) {
        const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n,
                     w = 1.0 - u - v;
        const Point3 p{w * a.x + u * b.x + v * c.x, w * a.y + u * b.y + v * c.y,
                       w * a.z + u * b.z + v * c.z};
        data.all.push_back(p);
        if (!nearHeld) data.zoomFit.push_back(p);
      }
    }
  }
  // A TIN that is all break lines still needs something to fit.
  if (data.zoomFit.size() < 3) data.zoomFit = data.all;
  return data;
}

fit::MultilevelOptions zoomFitOptions(const TilerOptions& o, const PyramidGeometry& g,
                                      double tolerance, int maxLevel) {
  fit::MultilevelOptions m;
  m.smoothing = fit::Smoothing::ThinPlate;
  m.lambdaFactor = o.lambdaFactor;
  m.criteria.errorAbsolute = tolerance;
  m.maxLevel = std::clamp(maxLevel, 1, fit::BinaryTriangulation::kMaxGridLevels - 1);
  m.domainOrigin = g.origin();
  m.domainSize = g.size();
  m.threads = o.threads;
  return m;
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

/// A vertex on one side of a tile and where along the side it lies.
struct SideVertex {
  double along;  // coordinate along the side
  Point3 p;
  bool onLine;
};

}  // namespace

Tiler::Tiler(const TinData& tin, TilerOptions options) : tin_(tin), options_(options), index_(tin) {
  if (!(options_.tolerance > 0) || !std::isfinite(options_.tolerance)) {
    throw usageError("the tile tolerance must be a positive number of metres (got " +
                         std::to_string(options_.tolerance) + ")",
                     "set [tiles] tolerance or --tolerance to e.g. 1");
  }
  if (options_.maxTriangles < 64) {
    throw usageError("max_triangles must be at least 64 (got " +
                     std::to_string(options_.maxTriangles) + ")");
  }
  if (tin.triangles.empty() || tin.vertices.size() < 3) {
    throw inputError("the TIN has no triangles to tile", {}, "build it with tinsmith tin first");
  }
  const Rect extent = boundsOf(tin.vertices);
  geometry_ = PyramidGeometry({extent.x0, extent.y0}, std::max(extent.width(), extent.height()));
  // levelsPerTile d: a tile refined d + 1 levels holds 2·4^(d+1) triangles;
  // keep that within half the budget, for break lines and sides.
  int d = 0;
  while (2.0 * std::pow(4.0, d + 2) <= static_cast<double>(options_.maxTriangles) / 2) ++d;
  levelsPerTile_ = std::max(d, 1);
  FitData data = fitData(tin);
  data_ = std::move(data.all);
  zoomData_ = std::move(data.zoomFit);
  dataGrid_ =
      CellGrid(extent.x0, extent.y0, extent.x1, extent.y1,
               CellGrid::cellFor(extent.width(), extent.height(), data_.size() / 4 + 1, 1e-9));
  dataGrid_.build(data_.size(), [&](std::size_t i, auto&& emit) {
    emit(dataGrid_.index(dataGrid_.cellX(data_[i].x), dataGrid_.cellY(data_[i].y)));
  });
  lines_ = extractTerrainLines(tin);

  // The finest planned zoom: the first whose tiles hold the finest fit's
  // triangles within a quarter of the budget each, on average over the
  // square. Zooms below it keep the finest tolerance: they exist only where a
  // tile of the planned finest zoom cannot meet it within levelsPerTile levels.
  const int cap = std::min(options_.maxZoom.value_or(20) + levelsPerTile_,
                           fit::BinaryTriangulation::kMaxGridLevels - 1);
  auto planning = std::make_unique<fit::MultilevelFit>(
      fit::fitMultilevel(zoomData_, zoomFitOptions(options_, geometry_, options_.tolerance, cap)));
  const double finestTriangles = static_cast<double>(planning->levels().back().triangles);
  const double perTile = static_cast<double>(options_.maxTriangles) / 4.0;
  int zmax = 0;
  while (zmax < options_.maxZoom.value_or(20) && finestTriangles > perTile * std::pow(4.0, zmax))
    ++zmax;
  finestZoom_ = zmax;
  maxZoom_ = std::min(options_.maxZoom.value_or(finestZoom_ + 6), 30);
  if (finestZoom_ + levelsPerTile_ == cap) plannedFit_ = std::move(planning);
}

Tiler::~Tiler() = default;

double Tiler::zoomTolerance(int z) const {
  return std::ldexp(options_.tolerance, std::max(0, finestZoom_ - z));
}

const Tiler::Zoom& Tiler::zoom(int z) const {
  ZoomSlot& slot = zooms_.at(static_cast<std::size_t>(z));
  std::call_once(slot.once, [&] { slot.zoom = makeZoom(z); });
  return *slot.zoom;
}

std::unique_ptr<Tiler::Zoom> Tiler::makeZoom(int z) const {
  auto zd = std::make_unique<Zoom>();
  zd->tolerance = zoomTolerance(z);
  if (z == finestZoom_ && plannedFit_) {
    zd->fit = std::move(plannedFit_);  // only this zoom's once-call touches it
  } else {
    zd->fit = std::make_unique<fit::MultilevelFit>(fit::fitMultilevel(
        zoomData_, zoomFitOptions(options_, geometry_, zd->tolerance, z + levelsPerTile_)));
  }
  for (const auto& line : lines_) {
    TerrainLine simplified = simplify(line, zd->tolerance);
    zd->lineBoxes.push_back(boundsOf(simplified.points));
    zd->lines.push_back(std::move(simplified));
  }
  return zd;
}

TileSurface Tiler::buildTile(const TileId& id) const {
  if (!geometry_.inside(id)) throw usageError("tile " + id.name() + " is outside the pyramid");
  const Zoom& zd = zoom(id.z);
  const auto& fit = *zd.fit;
  const auto& mesh = fit.mesh();
  const Rect rect = geometry_.bounds(id);
  const double snap = rect.width() * 1e-9;

  TileSurface tile;
  tile.id = id;
  tile.bounds = rect;

  // The lines in this tile.
  std::vector<ClippedPiece> pieces;
  for (std::size_t i = 0; i < zd.lines.size(); ++i) {
    if (!zd.lineBoxes[i].overlaps(rect)) continue;
    for (auto& piece : clipToRect(zd.lines[i], rect, snap)) pieces.push_back(std::move(piece));
  }

  const int gridLevels = mesh.gridLevels();
  const auto zValues = fit.vertexZ();
  auto binaryPoint = [&](std::uint64_t key) {
    return Point3{geometry_.lineX(gridLevels, mesh.column(key)),
                  geometry_.lineY(gridLevels, mesh.row(key)), zValues[mesh.vertexId(key)]};
  };

  // The zoom fit's triangles that meet the tile (SubmeshRefine, 2.10, pruned
  // to the tile): their vertices in the tile, and their edges cut at its
  // sides, which go in as constraints so the tile reproduces the zoom's
  // surface exactly before its own fit (a tile smaller than the fit's
  // triangles would otherwise miss the creases between them).
  const int shift = gridLevels - id.z;
  std::vector<std::uint64_t> keys;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> edges;
  {
    const double scale = static_cast<double>(1ULL << shift);
    const Rect grid{static_cast<double>(id.x) * scale, static_cast<double>(id.y) * scale,
                    static_cast<double>(id.x + 1ULL) * scale,
                    static_cast<double>(id.y + 1ULL) * scale};
    std::vector<fit::BinaryTriangle> stack;
    for (const auto& r : mesh.rootTriangles()) stack.push_back(r);
    while (!stack.empty()) {
      const fit::BinaryTriangle t = stack.back();
      stack.pop_back();
      const std::array corners{mesh.gridPosition(t.l), mesh.gridPosition(t.a),
                               mesh.gridPosition(t.r)};
      if (!boundsOf(corners).overlaps(grid)) continue;
      if (mesh.isSplit(t)) {
        const std::uint64_t j = (t.l + t.r) / 2;
        // (l, a, r) splits into (a, j, l) and (r, j, a).
        stack.push_back({t.a, j, t.l, 0, t.depth + 1});
        stack.push_back({t.r, j, t.a, 0, t.depth + 1});
        continue;
      }
      for (int i = 0; i < 3; ++i) {
        if (grid.contains(corners[i])) keys.push_back(i == 0 ? t.l : i == 1 ? t.a : t.r);
      }
      for (auto [u, v] : {std::pair{t.l, t.r}, std::pair{t.r, t.a}, std::pair{t.a, t.l}}) {
        edges.push_back({std::min(u, v), std::max(u, v)});
      }
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  std::vector<ClippedPiece> binaryEdges;
  for (const auto& [u, v] : edges) {
    TerrainLine e;
    e.kind = FeatureKind::Raster;
    e.points = {binaryPoint(u), binaryPoint(v)};
    for (auto& piece : clipToRect(e, rect, snap)) binaryEdges.push_back(std::move(piece));
  }

  // Side vertices: corners, binary vertices on a side, line points on a side.
  std::array<std::vector<SideVertex>, 4> sides;  // south, east, north, west (CCW)
  auto addToSides = [&](const Point3& p, bool onLine) {
    if (p.y == rect.y0) sides[0].push_back({p.x, p, onLine});
    if (p.x == rect.x1) sides[1].push_back({p.y, p, onLine});
    if (p.y == rect.y1) sides[2].push_back({-p.x, p, onLine});
    if (p.x == rect.x0) sides[3].push_back({-p.y, p, onLine});
  };
  // Corners that are not active vertices take the fit's value there (active
  // ones are among the binary vertices).
  for (std::uint64_t cj = id.y; cj <= id.y + 1ULL; ++cj) {
    for (std::uint64_t ci = id.x; ci <= id.x + 1ULL; ++ci) {
      if (mesh.isActive(mesh.key(ci << shift, cj << shift))) continue;
      const Point2 c{geometry_.lineX(id.z, ci), geometry_.lineY(id.z, cj)};
      addToSides({c.x, c.y, fit.evaluate(c)}, false);
    }
  }
  std::vector<Point3> interior;
  for (std::uint64_t key : keys) {
    const Point3 p = binaryPoint(key);
    if (p.x == rect.x0 || p.x == rect.x1 || p.y == rect.y0 || p.y == rect.y1) {
      addToSides(p, false);
    } else {
      interior.push_back(p);
    }
  }
  for (const auto& piece : binaryEdges) {
    for (const auto& p : piece.points) addToSides(p, false);
  }
  for (const auto& piece : pieces) {
    for (const auto& p : piece.points) addToSides(p, true);
  }
  std::vector<Point3> ring;
  for (auto& side : sides) {
    // Along the side; at equal positions a line point wins (its z is the line's).
    std::stable_sort(side.begin(), side.end(), [](const SideVertex& a, const SideVertex& b) {
      return a.along < b.along || (a.along == b.along && a.onLine > b.onLine);
    });
    for (std::size_t k = 0; k < side.size(); ++k) {
      if (k > 0 && side[k].along == side[k - 1].along) continue;
      if (!ring.empty() && ring.back().x == side[k].p.x && ring.back().y == side[k].p.y) continue;
      ring.push_back(side[k].p);
    }
  }
  if (ring.size() > 1 && ring.front().x == ring.back().x && ring.front().y == ring.back().y)
    ring.pop_back();

  // The tile's constrained triangulation.
  Cdt cdt(CdtOptions{});
  const FeatureId binaryFeature = cdt.addFeature(FeatureKind::Raster, "zoom fit");
  const FeatureId sideFeature = cdt.addFeature(FeatureKind::Other, "tile side");
  std::vector<FeatureId> pieceFeature;
  for (const auto& piece : pieces) {
    pieceFeature.push_back(cdt.addFeature(piece.ring ? FeatureKind::Boundary : piece.kind, "line"));
  }
  cdt.insertConstraint(ring, sideFeature, true);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    cdt.insertConstraint(pieces[i].points, pieceFeature[i], pieces[i].closed);
  }
  cdt.insertPoints(interior, binaryFeature);
  for (const auto& piece : binaryEdges) cdt.insertConstraint(piece.points, binaryFeature);
  cdt.finalize();
  const Mesh& cm = cdt.mesh();
  const auto& points = cm.points();

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
    const int inside = insideRings(centroid, zd.lines) ? 1 : 0;
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
  if (tile.triangles.empty()) return tile;
  for (std::size_t v = 0; v < tile.vertices.size(); ++v) {
    const bool onSide = (tile.flags[v] & 15) != 0;
    if ((tile.flags[v] & kHeld) && !onSide) ++tile.breakLineVertices;
    if (onSide) tile.flags[v] |= kHeld;  // sides keep the zoom fit's (or the line's) z
  }

  // The constrained least-squares fit (8.9) over the tile's mesh.
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
  for (std::uint32_t i : inTile) {
    const Point3& p = data_[i];
    const auto loc = surface.locate({p.x - rect.x0, p.y - rect.y0}, hint);
    if (!loc) continue;
    hint = loc->triangle;
    samples.push_back({loc->triangle.value, loc->weights, p.z, 1.0});
  }
  tile.dataPoints = samples.size();
  // Each free vertex also carries the zoom fit's value as a weak sample, so
  // a vertex with no data in its triangles (slivers beside a break line make
  // λ_d small) stays near the zoom's surface instead of being undetermined.
  constexpr double kPriorWeight = 0.25;
  std::vector<Point2> xy;
  xy.reserve(local.vertices.size());
  for (const auto& v : local.vertices) xy.push_back(v.xy());
  fit::LeastSquaresOptions ls;
  ls.smoothing = fit::Smoothing::ThinPlate;
  ls.lambdaFactor = options_.lambdaFactor;
  std::size_t freeCount = 0;
  fit::Vector initial(static_cast<Eigen::Index>(tile.vertices.size()));
  for (std::uint32_t v = 0; v < tile.vertices.size(); ++v) {
    if (tile.flags[v] & kHeld) {
      ls.fixed.push_back({v, tile.vertices[v].z});
    } else {
      ++freeCount;
      tile.vertices[v].z = fit.evaluate(tile.vertices[v].xy());
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

  const SurfaceDifference diff = maxVerticalDifference(tile.vertices, tile.triangles, index_);
  tile.error = diff.maxAbs;
  tile.errorAt = diff.at;
  return tile;
}

}  // namespace tinsmith::tiles
