#include "core/tiles/tiler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

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

/// What a tile's constrained triangulation is made of.
struct Tiler::TileInput {
  std::vector<Point3> ring;               // the tile's sides, CCW
  std::vector<ClippedPiece> lines;        // break lines and rings in the tile (held)
  std::vector<Point3> interior;           // binary vertices inside the tile (free)
  std::vector<Point3> pinned;             // TIN points held where the fit missed
};

namespace {

/// The share of a zoom's tolerance that the tile sides and the simplified
/// lines may take: they are held, so no fit corrects them, and the pins
/// beside them are exact, so a triangle between the two can be off by the
/// side's or line's error plus the slope it cuts (measured on Red Butte at
/// 1 m: 0.9 leaves tiles that never converge, 0.4 converges at zoom 4).
constexpr double kEdgeShare = 0.4;

/// A repair round pins the triangles whose error is above this share of the
/// tile's worst (and above the tolerance).
constexpr double kWorstShare = 0.5;

/// The data the fits see: the TIN's vertices, plus points sampled from its
/// triangles where its vertices are sparse (a triangle whose longest edge
/// exceeds twice the median longest edge gets the interior points of a
/// barycentric grid at about that median's spacing, z on the triangle's
/// plane; a DEM's even grid gets none).
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
    const Point3& c = tin.vertices[t[2]];
    lengths.push_back(std::max({std::hypot(b.x - a.x, b.y - a.y), std::hypot(c.x - b.x, c.y - b.y),
                                std::hypot(a.x - c.x, a.y - c.y)}));
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
    // About one sample per spacing² of area (a barycentric grid of n steps
    // has n²/2 points): a long sliver on the hull gets a few, not thousands.
    const double area =
        0.5 * std::abs((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
    const int n = static_cast<int>(std::min(64.0, std::ceil(std::sqrt(2 * area) / spacing)));
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

/// A triangle by its corners (x, y, z), rotated to start at the least (x, y):
/// the same triangle with the same heights in any round has the same key.
using TriangleKey = std::array<double, 9>;
struct TriangleKeyHash {
  std::size_t operator()(const TriangleKey& k) const {
    std::size_t h = 1469598103934665603ULL;
    for (double v : k) h = (h ^ std::hash<double>{}(v)) * 1099511628211ULL;
    return h;
  }
};
TriangleKey triangleKey(const std::vector<Point3>& vertices, const std::array<std::uint32_t, 3>& t) {
  int first = 0;
  for (int i = 1; i < 3; ++i) {
    const Point3& a = vertices[t[i]];
    const Point3& b = vertices[t[first]];
    if (a.x < b.x || (a.x == b.x && a.y < b.y)) first = i;
  }
  TriangleKey key{};
  for (int i = 0; i < 3; ++i) {
    const Point3& p = vertices[t[(first + i) % 3]];
    key[3 * i] = p.x;
    key[3 * i + 1] = p.y;
    key[3 * i + 2] = p.z;
  }
  return key;
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

/// Douglas–Peucker in the vertical: the points of `section` (sorted by
/// `along`, NaN z skipped) farther than `tolerance` from the chord between
/// `from` and `to`, appended to `kept` in order.
void simplifySection(std::span<const std::pair<double, double>> section, std::pair<double, double> from,
                     std::pair<double, double> to, double tolerance,
                     std::vector<std::pair<double, double>>& kept) {
  std::size_t worst = section.size();
  double worstDistance = tolerance;
  for (std::size_t k = 0; k < section.size(); ++k) {
    const auto [u, z] = section[k];
    if (std::isnan(z)) continue;
    const double w = (u - from.first) / (to.first - from.first);
    const double d = std::abs(z - (from.second + w * (to.second - from.second)));
    if (d > worstDistance) {
      worstDistance = d;
      worst = k;
    }
  }
  if (worst == section.size()) return;
  simplifySection(section.first(worst), from, section[worst], tolerance, kept);
  kept.push_back(section[worst]);
  simplifySection(section.subspan(worst + 1), section[worst], to, tolerance, kept);
}

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
  // A chord must stay on the TIN too: a shore simplified across a steep bank
  // would otherwise sit metres off the ground it crosses, at every zoom.
  std::vector<TinIndex::SectionPoint> section;
  const ChordError offTin = [&](const Point3& a, const Point3& b) {
    index_.section(a.xy(), b.xy(), section);
    double worst = 0.0;
    for (const auto& sp : section) {
      if (!std::isnan(sp.z)) worst = std::max(worst, std::abs(sp.z - (a.z + sp.t * (b.z - a.z))));
    }
    return worst;
  };
  for (const auto& line : lines_) {
    TerrainLine simplified = simplify(line, kEdgeShare * zd->tolerance, offTin);
    zd->lineBoxes.push_back(boundsOf(simplified.points));
    zd->lines.push_back(std::move(simplified));
  }
  return zd;
}

TileSurface Tiler::buildTile(const TileId& id) const {
  if (!geometry_.inside(id)) throw usageError("tile " + id.name() + " is outside the pyramid");
  const Zoom& zd = zoom(id.z);
  const Rect rect = geometry_.bounds(id);
  TileInput input = tileInput(id, zd);

  // Fit, measure, and where a triangle misses the zoom's tolerance hold the
  // TIN at its worst points and fit again, within the triangle budget. Each
  // round takes the triangles within kWorstShare of the worst first (greedy
  // in batches): pinning every failing triangle at once spends the budget on
  // the many that barely fail before the few that fail by far.
  TileSurface tile;
  // Each round measures only the triangles it has not measured before (a
  // held triangle stays the same from round to round).
  std::unordered_map<TriangleKey, SurfaceDifference, TriangleKeyHash> measured;
  std::vector<SurfaceDifference> differences;
  std::vector<std::array<std::uint32_t, 3>> unmeasured;
  std::vector<std::size_t> unmeasuredAt;
  for (int round = 0;; ++round) {
    tile = triangulateTile(id, rect, input, zd.lines);
    if (tile.empty()) return tile;
    fitTile(tile, *zd.fit);
    differences.assign(tile.triangles.size(), {});
    unmeasured.clear();
    unmeasuredAt.clear();
    std::vector<TriangleKey> keys(tile.triangles.size());
    for (std::size_t t = 0; t < tile.triangles.size(); ++t) {
      keys[t] = triangleKey(tile.vertices, tile.triangles[t]);
      if (const auto it = measured.find(keys[t]); it != measured.end()) {
        differences[t] = it->second;
      } else {
        unmeasured.push_back(tile.triangles[t]);
        unmeasuredAt.push_back(t);
      }
    }
    const auto fresh = triangleDifferences(tile.vertices, unmeasured, index_);
    for (std::size_t k = 0; k < fresh.size(); ++k) {
      differences[unmeasuredAt[k]] = fresh[k];
      measured.emplace(keys[unmeasuredAt[k]], fresh[k]);
    }
    tile.error = 0;
    for (const auto& d : differences) {
      if (d.maxAbs > tile.error) {
        tile.error = d.maxAbs;
        tile.errorAt = d.at;
      }
    }
    tile.repairRounds = round;
    if (tile.error <= zd.tolerance || round == kRepairRounds ||
        tile.triangles.size() >= options_.maxTriangles ||
        (!addPins(tile, differences, std::max(zd.tolerance, kWorstShare * tile.error), input) &&
         !addPins(tile, differences, zd.tolerance, input)))
      break;
  }
  return tile;
}

bool Tiler::addPins(const TileSurface& tile, std::span<const SurfaceDifference> differences,
                    double target, TileInput& input) const {
  const Rect& rect = tile.bounds;
  // Pins stay inside the tile, a little off its sides (which hold the TIN's
  // section): a TIN vertex on a side, where a crease of the TIN meets it,
  // comes in just beside it. Outside the tile a point is not this tile's.
  const double margin = 1e-4 * rect.width();
  std::vector<Point3> pins;
  bool split = false;
  auto pin = [&](Point2 p) {
    if (!rect.contains(p)) return;
    p.x = std::clamp(p.x, rect.x0 + margin, rect.x1 - margin);
    p.y = std::clamp(p.y, rect.y0 + margin, rect.y1 - margin);
    if (const auto z = index_.z(p)) pins.push_back({p.x, p.y, *z});
  };
  for (std::size_t t = 0; t < differences.size(); ++t) {
    const SurfaceDifference& d = differences[t];
    if (d.maxAbs <= target) continue;
    const auto& tri = tile.triangles[t];
    const std::array<Point3, 3> c{tile.vertices[tri[0]], tile.vertices[tri[1]],
                                  tile.vertices[tri[2]]};
    double longest = 0.0, nearest = HUGE_VAL;
    int nearestCorner = 0;
    for (int i = 0; i < 3; ++i) {
      const Point3& next = c[(i + 1) % 3];
      longest = std::max(longest, std::hypot(next.x - c[i].x, next.y - c[i].y));
      const double distance = std::hypot(c[i].x - d.at.x, c[i].y - d.at.y);
      if (distance < nearest) {
        nearest = distance;
        nearestCorner = i;
      }
    }
    const double area =
        (c[1].x - c[0].x) * (c[2].y - c[0].y) - (c[2].x - c[0].x) * (c[1].y - c[0].y);
    if (!(area > 0)) continue;
    // p's barycentric weight for corner i: its distance from the opposite
    // edge over the corner's. The 5 % strip along a held edge is where a
    // pin would make a sliver of that edge.
    auto weight = [&](Point2 p, int i) {
      const Point3& a = c[(i + 1) % 3];
      const Point3& b = c[(i + 2) % 3];
      return ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / area;
    };
    auto heldOpposite = [&](int i) { return ((tile.heldEdges[t] >> ((i + 1) % 3)) & 1U) != 0; };
    auto inHeldStrip = [&](Point2 p) {
      for (int i = 0; i < 3; ++i) {
        if (heldOpposite(i) && weight(p, i) < 0.05) return true;
      }
      return false;
    };
    // p moved out of every held edge's strip, into the triangle.
    auto offHeld = [&](Point2 p) {
      std::array<double, 3> w{};
      double total = 0.0;
      for (int i = 0; i < 3; ++i) {
        w[i] = heldOpposite(i) ? std::max(weight(p, i), 0.05) : weight(p, i);
        total += w[i];
      }
      Point2 q{0.0, 0.0};
      for (int i = 0; i < 3; ++i) {
        q.x += w[i] / total * c[i].x;
        q.y += w[i] / total * c[i].y;
      }
      return q;
    };
    if (nearest < 0.1 * longest && !(tile.flags[tri[nearestCorner]] & kHeld)) {
      // At (or beside) a free vertex the vertex is what is off: hold it.
      pin(c[nearestCorner].xy());
    } else if (d.vertexAbs > target && !inHeldStrip(d.vertex)) {
      // The worst TIN vertex and the corners of the TIN triangle the worst
      // point lies in: holding the TIN's vertices converges, at worst to the
      // TIN itself.
      pin(d.vertex);
      for (std::uint32_t corner : tin_.triangles[d.tinTriangle]) pin(tin_.vertices[corner].xy());
    } else {
      // A crossing of TIN and mesh edges (on a free edge the triangulation
      // flips it away), with the TIN triangle's corners, so the TIN's own
      // shape comes in: crossings alone may not converge. In the strip of a
      // line's or a ring's held edge the line itself takes the TIN's point:
      // a pin beside a long held edge leaves the edge, and the strip along
      // it, as they were.
      bool splitHere = false;
      for (int i = 0; i < 3 && !splitHere; ++i) {
        if (!heldOpposite(i) || weight(d.at, i) >= 0.05) continue;
        const Point3& a = c[(i + 1) % 3];
        const Point3& b = c[(i + 2) % 3];
        // The worst TIN vertex, if it is the one beside the edge (a line's own
        // vertex the simplification left out), else the worst point's foot.
        const double wv = weight(d.vertex, i);
        const bool vertexBeside = d.vertexAbs > target && wv >= 0 && wv < 0.05;
        const Point2 p = vertexBeside ? d.vertex : d.at;
        const double dx = b.x - a.x, dy = b.y - a.y;
        const double u = ((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy);
        const Point2 foot{a.x + u * dx, a.y + u * dy};
        splitHere = splitLine(foot, vertexBeside ? p : foot, rect, input);
      }
      if (splitHere) {
        split = true;
      } else {
        pin(offHeld(d.at));
      }
      for (std::uint32_t corner : tin_.triangles[d.tinTriangle]) pin(tin_.vertices[corner].xy());
    }
  }
  if (pins.empty()) return split;
  // One pin per spot: points a rounding apart (two triangles' view of one
  // crossing) would make a sliver.
  const double spot = 1e-6 * rect.width();
  pins.insert(pins.end(), input.pinned.begin(), input.pinned.end());
  std::sort(pins.begin(), pins.end(),
            [](const Point3& a, const Point3& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  const std::size_t before = input.pinned.size();
  input.pinned.clear();
  for (const Point3& p : pins) {
    bool near = false;
    for (auto it = input.pinned.rbegin(); it != input.pinned.rend() && p.x - it->x <= spot; ++it) {
      if (std::abs(p.y - it->y) <= spot) {
        near = true;
        break;
      }
    }
    if (!near) input.pinned.push_back(p);
  }
  return split || input.pinned.size() > before;
}

bool Tiler::splitLine(Point2 p, Point2 at, const Rect& rect, TileInput& input) const {
  // The line segment p lies on (within rounding of the tile's size).
  const double near = 1e-6 * rect.width();
  for (auto& piece : input.lines) {
    auto& pts = piece.points;
    const std::size_t n = pts.size();
    for (std::size_t i = 0; i + 1 < n + (piece.closed ? 1 : 0); ++i) {
      const Point3 a = pts[i];
      const Point3 b = pts[(i + 1) % n];
      const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
      if (!(len2 > 0)) continue;
      const double u = ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2;
      if (u <= 1e-6 || u >= 1 - 1e-6) continue;
      if (std::hypot(p.x - (a.x + u * dx), p.y - (a.y + u * dy)) > near) continue;
      const Point2 q = at;
      if (q.x <= rect.x0 || q.x >= rect.x1 || q.y <= rect.y0 || q.y >= rect.y1) return false;
      const auto z = index_.z(q);
      if (!z) return false;
      // A river keeps flowing one way: its new point stays between its ends.
      const double zq = piece.kind == FeatureKind::River
                            ? std::clamp(*z, std::min(a.z, b.z), std::max(a.z, b.z))
                            : *z;
      pts.insert(pts.begin() + static_cast<std::ptrdiff_t>(i + 1), Point3{q.x, q.y, zq});
      return true;
    }
  }
  return false;
}

Tiler::TileInput Tiler::tileInput(const TileId& id, const Zoom& zd) const {
  const auto& fit = *zd.fit;
  const auto& mesh = fit.mesh();
  const Rect rect = geometry_.bounds(id);
  const double snap = rect.width() * 1e-9;
  TileInput input;

  // The lines in this tile.
  for (std::size_t i = 0; i < zd.lines.size(); ++i) {
    if (!zd.lineBoxes[i].overlaps(rect)) continue;
    for (auto& piece : clipToRect(zd.lines[i], rect, snap)) input.lines.push_back(std::move(piece));
  }

  const int gridLevels = mesh.gridLevels();
  const auto zValues = fit.vertexZ();
  auto binaryPoint = [&](std::uint64_t key) {
    return Point3{geometry_.lineX(gridLevels, mesh.column(key)),
                  geometry_.lineY(gridLevels, mesh.row(key)), zValues[mesh.vertexId(key)]};
  };

  // The zoom fit's vertices in the tile: the leaves of its binary
  // triangulation that meet the tile (SubmeshRefine, 2.10, pruned to it).
  const int shift = gridLevels - id.z;
  std::vector<std::uint64_t> keys;
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
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }
  // Side points: the corners, binary vertices on a side, and the lines'
  // crossings.
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
  for (std::uint64_t key : keys) {
    const Point3 p = binaryPoint(key);
    if (p.x == rect.x0 || p.x == rect.x1 || p.y == rect.y0 || p.y == rect.y1) {
      addToSides(p, false);
    } else {
      input.interior.push_back(p);
    }
  }
  for (const auto& piece : input.lines) {
    for (const auto& p : piece.points) addToSides(p, true);
  }

  // Each side is the TIN's section along it, simplified (vertically, to
  // kEdgeShare of the zoom's tolerance) between the points it must keep; those take the
  // TIN's z (the fit's outside the TIN), a line's crossing the line's. Both
  // tiles sharing a side compute it from the same inputs in the same
  // direction (west to east, south to north), so they get the same vertices.
  std::vector<TinIndex::SectionPoint> section;
  std::vector<std::pair<double, double>> along, kept;
  std::array<std::vector<Point3>, 4> sideLines;
  for (int k = 0; k < 4; ++k) {
    auto& side = sides[k];
    const bool horizontal = k == 0 || k == 2;
    const double fixed = k == 0 ? rect.y0 : k == 1 ? rect.x1 : k == 2 ? rect.y1 : rect.x0;
    const double u0 = horizontal ? rect.x0 : rect.y0, u1 = horizontal ? rect.x1 : rect.y1;
    auto at = [&](double u) { return horizontal ? Point2{u, fixed} : Point2{fixed, u}; };
    index_.section(at(u0), at(u1), section);
    along.clear();
    for (const auto& sp : section) along.push_back({u0 + sp.t * (u1 - u0), sp.z});
    auto tinZ = [&](double u) -> std::optional<double> {
      const auto hi = std::lower_bound(along.begin(), along.end(), u,
                                       [](const auto& a, double v) { return a.first < v; });
      if (hi != along.end() && hi->first == u && !std::isnan(hi->second)) return hi->second;
      if (hi == along.begin() || hi == along.end()) return std::nullopt;
      const auto lo = hi - 1;
      if (std::isnan(lo->second) || std::isnan(hi->second)) return std::nullopt;
      const double w = (u - lo->first) / (hi->first - lo->first);
      return lo->second + w * (hi->second - lo->second);
    };
    // Along the side; at equal positions a line point wins (its z is the line's).
    std::stable_sort(side.begin(), side.end(), [](const SidePoint& a, const SidePoint& b) {
      return a.along < b.along || (a.along == b.along && a.onLine > b.onLine);
    });
    std::vector<SidePoint> must;
    for (const auto& sp : side) {
      if (!must.empty() && must.back().along == sp.along) continue;
      must.push_back(sp);
      if (!sp.onLine) {
        const auto z = tinZ(sp.along);
        must.back().p.z = z ? *z : fit.evaluate(sp.p.xy());  // the fit only off the TIN
      }
    }
    auto& out = sideLines[k];
    out.push_back(must.front().p);
    auto first = along.begin();
    for (std::size_t m = 1; m < must.size(); ++m) {
      const double ua = must[m - 1].along, ub = must[m].along;
      const double gap = (ub - ua) * 1e-9;
      while (first != along.end() && first->first <= ua + gap) ++first;
      auto last = first;
      while (last != along.end() && last->first < ub - gap) ++last;
      kept.clear();
      simplifySection({&*first, static_cast<std::size_t>(last - first)},
                      {ua, must[m - 1].p.z}, {ub, must[m].p.z}, kEdgeShare * zd.tolerance, kept);
      for (const auto& [u, z] : kept) {
        const Point2 q = at(u);
        out.push_back({q.x, q.y, z});
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
  const FeatureId binaryFeature = cdt.addFeature(FeatureKind::Raster, "zoom fit");
  const FeatureId pinFeature = cdt.addFeature(FeatureKind::Raster, "held TIN point");
  cdt.insertConstraint(input.ring, sideFeature, true);
  for (std::size_t i = 0; i < input.lines.size(); ++i) {
    cdt.insertConstraint(input.lines[i].points, lineFeature[i], input.lines[i].closed);
  }
  cdt.insertPoints(input.interior, binaryFeature);
  const VertexId firstPin =
      input.pinned.empty() ? VertexId() : cdt.insertPoints(input.pinned, pinFeature);
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
  for (std::size_t v = 0; v < nv; ++v) {
    const Point3& p = points[v];
    if (p.x == rect.x0) flags[v] |= kSideWest;
    if (p.x == rect.x1) flags[v] |= kSideEast;
    if (p.y == rect.y0) flags[v] |= kSideSouth;
    if (p.y == rect.y1) flags[v] |= kSideNorth;
  }
  // A pinned point held at the TIN's z, unless it fell on a line or a side
  // (merged into a vertex those hold).
  for (std::size_t k = 0; k < input.pinned.size(); ++k) {
    const VertexId v = cdt.meshVertex(VertexId(firstPin.value + static_cast<std::uint32_t>(k)));
    if (!v.valid() || (flags[v.value] & (kHeld | 15))) continue;
    points[v.value].z = input.pinned[k].z;
    flags[v.value] |= kHeld | kPinned;
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
    std::uint8_t held = 0;
    for (int i = 0; i < 3; ++i) {
      if (cm.isConstrained(Mesh::halfedge(TriangleId(t), i))) held |= 1U << i;
    }
    tile.heldEdges.push_back(held);
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
    if ((tile.flags[v] & kHeld) && !onSide && !(tile.flags[v] & kPinned)) ++tile.breakLineVertices;
    if (onSide) tile.flags[v] |= kHeld;  // sides keep the TIN's (or the line's) z
  }
  return tile;
}

void Tiler::fitTile(TileSurface& tile, const fit::MultilevelFit& fit) const {
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
}

}  // namespace tinsmith::tiles
