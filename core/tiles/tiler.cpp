#include "core/tiles/tiler.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <unordered_map>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/fit/least_squares.hpp"
#include "core/surface/surface.hpp"

namespace tinsmith::tiles {

/// What every tile of one zoom shares: the zoom's fit, its active vertices by
/// tile, and the lines simplified to its tolerance.
struct Tiler::Zoom {
  int z = 0;
  double tolerance = 0;
  std::unique_ptr<fit::MultilevelFit> fit;
  int gridLevels = 0;
  /// (tile index y·2^z + x, key) for every active vertex, a vertex on a side
  /// listed under each tile it touches; sorted.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> keysByTile;
  std::vector<TerrainLine> lines;
  std::vector<Rect> lineBoxes;
  std::size_t keptLineVertices = 0;
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

/// Adds `piece` to a vertex pool, returns the pool indices of its points.
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
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  for (const auto& v : tin.vertices) {
    x0 = std::min(x0, v.x);
    y0 = std::min(y0, v.y);
    x1 = std::max(x1, v.x);
    y1 = std::max(y1, v.y);
  }
  geometry_ = PyramidGeometry({x0, y0}, std::max(x1 - x0, y1 - y0));
  // levelsPerTile d: a tile refined d + 1 levels holds 2·4^(d+1) triangles;
  // keep that within half the budget, for break lines and sides.
  int d = 0;
  while (2.0 * std::pow(4.0, d + 2) <= static_cast<double>(options_.maxTriangles) / 2) ++d;
  levelsPerTile_ = std::max(d, 1);
  FitData data = fitData(tin);
  data_ = std::move(data.all);
  zoomData_ = std::move(data.zoomFit);
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
  if (finestZoom_ + levelsPerTile_ == cap) {
    auto zoom = std::make_shared<Zoom>();
    zoom->z = finestZoom_;
    zoom->tolerance = options_.tolerance;
    zoom->fit = std::move(planning);
    // The rest of the zoom is filled by zoom() on first use.
    zooms_[-1 - finestZoom_] = zoom;
  }
}

Tiler::~Tiler() = default;

double Tiler::zoomTolerance(int z) const {
  return std::ldexp(options_.tolerance, std::max(0, finestZoom_ - z));
}

std::size_t Tiler::keptLineVertices(int z) const {
  return zoom(z).keptLineVertices;
}

const Tiler::Zoom& Tiler::zoom(int z) const {
  std::shared_ptr<std::once_flag> once;
  {
    std::lock_guard lock(mutex_);
    auto it = zooms_.find(z);
    if (it != zooms_.end()) return *it->second;
    auto& flag = zoomOnce_[z];
    if (!flag) flag = std::make_shared<std::once_flag>();
    once = flag;
  }
  std::call_once(*once, [&] {
    auto zoomData = std::make_shared<Zoom>();
    Zoom& zd = *zoomData;
    zd.z = z;
    zd.tolerance = zoomTolerance(z);
    const int maxLevel = z + levelsPerTile_;
    {
      std::shared_ptr<Zoom> planned;
      {
        std::lock_guard lock(mutex_);
        auto it = zooms_.find(-1 - z);
        if (it != zooms_.end()) planned = it->second;
      }
      if (planned) {
        zd.fit = std::move(planned->fit);
      } else {
        zd.fit = std::make_unique<fit::MultilevelFit>(fit::fitMultilevel(
            zoomData_, zoomFitOptions(options_, geometry_, zd.tolerance, maxLevel)));
      }
    }
    const auto& mesh = zd.fit->mesh();
    zd.gridLevels = mesh.gridLevels();
    const int shift = zd.gridLevels - z;
    const std::uint64_t step = 1ULL << shift, tilesASide = 1ULL << z;
    for (std::uint64_t key : mesh.activeKeys()) {
      const std::uint64_t col = mesh.column(key), row = mesh.row(key);
      std::uint64_t xs[2] = {std::min(col >> shift, tilesASide - 1), 0},
                    ys[2] = {std::min(row >> shift, tilesASide - 1), 0};
      int nx = 1, ny = 1;
      if (col % step == 0 && col > 0 && (col >> shift) < tilesASide) xs[nx++] = (col >> shift) - 1;
      if (row % step == 0 && row > 0 && (row >> shift) < tilesASide) ys[ny++] = (row >> shift) - 1;
      for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j) zd.keysByTile.push_back({ys[j] * tilesASide + xs[i], key});
    }
    std::sort(zd.keysByTile.begin(), zd.keysByTile.end());
    for (const auto& line : lines_) {
      TerrainLine s = simplify(line, zd.tolerance);
      Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (const auto& p : s.points) {
        box.x0 = std::min(box.x0, p.x);
        box.y0 = std::min(box.y0, p.y);
        box.x1 = std::max(box.x1, p.x);
        box.y1 = std::max(box.y1, p.y);
      }
      zd.keptLineVertices += s.points.size();
      zd.lineBoxes.push_back(box);
      zd.lines.push_back(std::move(s));
    }
    std::lock_guard lock(mutex_);
    zooms_.erase(-1 - z);
    zooms_[z] = zoomData;
  });
  std::lock_guard lock(mutex_);
  return *zooms_.at(z);
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
    const Rect& b = zd.lineBoxes[i];
    if (b.x1 < rect.x0 || b.x0 > rect.x1 || b.y1 < rect.y0 || b.y0 > rect.y1) continue;
    for (auto& piece : clipToRect(zd.lines[i], rect, snap)) pieces.push_back(std::move(piece));
  }

  // The binary vertices of the zoom fit in and on the tile.
  const std::uint64_t tileIndex = static_cast<std::uint64_t>(id.y) * (1ULL << id.z) + id.x;
  auto lo = std::lower_bound(zd.keysByTile.begin(), zd.keysByTile.end(),
                             std::pair<std::uint64_t, std::uint64_t>{tileIndex, 0});
  const auto zValues = fit.vertexZ();
  auto binaryPoint = [&](std::uint64_t key) {
    return Point3{geometry_.lineX(zd.gridLevels, mesh.column(key)),
                  geometry_.lineY(zd.gridLevels, mesh.row(key)), zValues[mesh.vertexId(key)]};
  };

  // Side vertices: corners, binary vertices on a side, line points on a side.
  std::array<std::vector<SideVertex>, 4> sides;  // south, east, north, west (CCW)
  auto addToSides = [&](const Point3& p, bool onLine) {
    if (p.y == rect.y0) sides[0].push_back({p.x, p, onLine});
    if (p.x == rect.x1) sides[1].push_back({p.y, p, onLine});
    if (p.y == rect.y1) sides[2].push_back({-p.x, p, onLine});
    if (p.x == rect.x0) sides[3].push_back({-p.y, p, onLine});
  };
  // Corners that are not active vertices take the fit's value there (active
  // ones come with the binary vertices below).
  const int shift = zd.gridLevels - id.z;
  for (std::uint64_t cj = id.y; cj <= id.y + 1ULL; ++cj) {
    for (std::uint64_t ci = id.x; ci <= id.x + 1ULL; ++ci) {
      if (mesh.isActive(mesh.key(ci << shift, cj << shift))) continue;
      const Point2 c{geometry_.lineX(id.z, ci), geometry_.lineY(id.z, cj)};
      addToSides({c.x, c.y, fit.evaluate(c)}, false);
    }
  }
  std::vector<Point3> interior;
  for (auto it = lo; it != zd.keysByTile.end() && it->first == tileIndex; ++it) {
    Point3 p = binaryPoint(it->second);
    if (p.x == rect.x0 || p.x == rect.x1 || p.y == rect.y0 || p.y == rect.y1) {
      addToSides(p, false);
    } else {
      interior.push_back(p);
    }
  }
  // The zoom fit's triangles in the tile, cut at its sides: their edges go in
  // as constraints, so the tile reproduces the zoom's surface exactly before
  // its own fit (a tile smaller than the fit's triangles would otherwise miss
  // the creases between them).
  std::vector<ClippedPiece> binaryEdges;
  {
    const double scale = static_cast<double>(1ULL << shift);
    const double gx0 = static_cast<double>(id.x) * scale, gy0 = static_cast<double>(id.y) * scale;
    const double gx1 = gx0 + scale, gy1 = gy0 + scale;
    std::vector<fit::BinaryTriangle> stack;
    for (const auto& r : mesh.rootTriangles()) stack.push_back(r);
    std::vector<std::pair<std::uint64_t, std::uint64_t>> edges;
    while (!stack.empty()) {
      const fit::BinaryTriangle t = stack.back();
      stack.pop_back();
      const Point2 a = mesh.gridPosition(t.l), b = mesh.gridPosition(t.a),
                   c = mesh.gridPosition(t.r);
      if (std::max({a.x, b.x, c.x}) < gx0 || std::min({a.x, b.x, c.x}) > gx1 ||
          std::max({a.y, b.y, c.y}) < gy0 || std::min({a.y, b.y, c.y}) > gy1) {
        continue;
      }
      if (mesh.isSplit(t)) {
        const std::uint64_t j = (t.l + t.r) / 2;
        // SubmeshRefine (2.10): (l, a, r) splits into (a, j, l) and (r, j, a).
        stack.push_back({t.a, j, t.l, 0, t.depth + 1});
        stack.push_back({t.r, j, t.a, 0, t.depth + 1});
        continue;
      }
      for (auto [u, v] : {std::pair{t.l, t.r}, std::pair{t.r, t.a}, std::pair{t.a, t.l}}) {
        edges.push_back({std::min(u, v), std::max(u, v)});
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (const auto& [u, v] : edges) {
      TerrainLine e;
      e.kind = FeatureKind::Raster;
      e.points = {binaryPoint(u), binaryPoint(v)};
      for (auto& piece : clipToRect(e, rect, snap)) binaryEdges.push_back(std::move(piece));
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
  TinData td = cdt.toTinData();

  // Which vertices are held, and where the domain boundary runs.
  const std::size_t nv = td.vertices.size();
  std::vector<std::uint8_t> flags(nv, 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, bool> ringEdges;
  for (const auto& e : td.constrainedEdges) {
    const FeatureKind kind = td.features[e.feature].kind;
    if (kind == FeatureKind::Raster || kind == FeatureKind::SpotHeight) continue;
    flags[e.a] |= kHeld;
    flags[e.b] |= kHeld;
    if (kind == FeatureKind::Boundary) ringEdges[{e.a, e.b}] = true;
  }
  for (std::size_t v = 0; v < nv; ++v) {
    const Point3& p = td.vertices[v];
    if (p.x == rect.x0) flags[v] |= kSideWest;
    if (p.x == rect.x1) flags[v] |= kSideEast;
    if (p.y == rect.y0) flags[v] |= kSideSouth;
    if (p.y == rect.y1) flags[v] |= kSideNorth;
  }

  // Keep the triangles inside the TIN's (simplified) domain: components
  // bounded by ring edges, each classified once by even-odd.
  const std::size_t nt = td.triangles.size();
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edgeOwner;
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (int i = 0; i < 3; ++i) edgeOwner[{td.triangles[t][i], td.triangles[t][(i + 1) % 3]}] = t;
  }
  std::vector<int> keep(nt, -1);
  for (std::uint32_t seed = 0; seed < nt; ++seed) {
    if (keep[seed] >= 0) continue;
    const auto& s = td.triangles[seed];
    const Point2 centroid{(td.vertices[s[0]].x + td.vertices[s[1]].x + td.vertices[s[2]].x) / 3,
                          (td.vertices[s[0]].y + td.vertices[s[1]].y + td.vertices[s[2]].y) / 3};
    const int inside = insideRings(centroid, zd.lines) ? 1 : 0;
    std::vector<std::uint32_t> stack{seed};
    keep[seed] = inside;
    while (!stack.empty()) {
      const std::uint32_t t = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t a = td.triangles[t][i], b = td.triangles[t][(i + 1) % 3];
        if (ringEdges.contains({std::min(a, b), std::max(a, b)})) continue;
        auto it = edgeOwner.find({b, a});
        if (it == edgeOwner.end() || keep[it->second] >= 0) continue;
        keep[it->second] = inside;
        stack.push_back(it->second);
      }
    }
  }
  std::vector<std::uint32_t> remap(nv, std::numeric_limits<std::uint32_t>::max());
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (keep[t] != 1) continue;
    std::array<std::uint32_t, 3> tri{};
    for (int i = 0; i < 3; ++i) {
      std::uint32_t& r = remap[td.triangles[t][i]];
      if (r == std::numeric_limits<std::uint32_t>::max()) {
        r = static_cast<std::uint32_t>(tile.vertices.size());
        tile.vertices.push_back(td.vertices[td.triangles[t][i]]);
        tile.flags.push_back(flags[td.triangles[t][i]]);
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
  const Surface surface(local);
  std::vector<fit::Sample> samples;
  TriangleId hint;
  for (const auto& p : data_) {
    if (!rect.contains(p.xy())) continue;
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
  // Surface may renumber nothing: its mesh keeps TinData's triangle order.
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
