// Binary triangulations: activation, SubmeshRefine, point location, strips (2.10).
#include "core/fit/binary_triangulation.hpp"

#include <bit>
#include <cmath>
#include <string>

#include "core/base/error.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::fit {

BinaryTriangulation::BinaryTriangulation(Point2 origin, double size, int gridLevels)
    : origin_(origin), size_(size), gridLevels_(gridLevels), side_(0) {
  if (!(size > 0.0) || !std::isfinite(size)) {
    throw inputError("binary triangulation: the domain size must be positive and finite (got " +
                     std::to_string(size) + ")");
  }
  if (gridLevels < 1 || gridLevels > kMaxGridLevels) {
    throw inputError("binary triangulation: the finest grid level must be within 1.." +
                     std::to_string(kMaxGridLevels) + " (got " + std::to_string(gridLevels) + ")");
  }
  side_ = std::uint64_t{1} << gridLevels;
  for (std::uint64_t k : {key(0, 0), key(side_, 0), key(side_, side_), key(0, side_), key(side_ / 2, side_ / 2)}) {
    activateOne(k);
  }
}

Point2 BinaryTriangulation::position(std::uint64_t k) const {
  const double scale = size_ / static_cast<double>(side_);
  return {origin_.x + static_cast<double>(column(k)) * scale, origin_.y + static_cast<double>(row(k)) * scale};
}


int BinaryTriangulation::depth(std::uint64_t k) const {
  const std::uint64_t i = column(k), j = row(k);
  const std::uint64_t s = std::uint64_t{1} << std::countr_zero(i | j | side_);
  const int m = gridLevels_ - std::countr_zero(s);
  if (m == 0) return 0;
  const bool iOdd = ((i / s) & 1) != 0, jOdd = ((j / s) & 1) != 0;
  return iOdd && jOdd ? 2 * m - 1 : 2 * m;
}

std::vector<std::uint64_t> BinaryTriangulation::parents(std::uint64_t k) const {
  std::vector<std::uint64_t> result;
  const std::uint64_t i = column(k), j = row(k);
  const std::uint64_t s = std::uint64_t{1} << std::countr_zero(i | j | side_);
  const int m = gridLevels_ - std::countr_zero(s);
  if (m <= 1 && ((i / s) & 1) && ((j / s) & 1)) return result;  // the centre
  if (m == 0) return result;                                      // a corner
  const bool iOdd = ((i / s) & 1) != 0, jOdd = ((j / s) & 1) != 0;
  if (iOdd && jOdd) {
    // Centre of a cell of Ψ_{m−1} (spacing 2s): the split edge is the cell
    // diagonal whose ends have an even coordinate sum in Ψ_{m−1}; the parents
    // are the other two corners.
    for (int dy = -1; dy <= 1; dy += 2) {
      for (int dx = -1; dx <= 1; dx += 2) {
        const std::uint64_t ci = dx < 0 ? i - s : i + s, cj = dy < 0 ? j - s : j + s;
        if ((((ci / (2 * s)) + (cj / (2 * s))) & 1) != 0) result.push_back(key(ci, cj));
      }
    }
  } else if (iOdd) {  // midpoint of a horizontal edge: the cell centres above and below
    if (j >= s) result.push_back(key(i, j - s));
    if (j + s <= side_) result.push_back(key(i, j + s));
  } else {  // midpoint of a vertical edge
    if (i >= s) result.push_back(key(i - s, j));
    if (i + s <= side_) result.push_back(key(i + s, j));
  }
  return result;
}

std::array<std::uint64_t, 2> BinaryTriangulation::splitEdge(std::uint64_t k) const {
  const std::uint64_t i = column(k), j = row(k);
  const std::uint64_t s = std::uint64_t{1} << std::countr_zero(i | j | side_);
  const int m = gridLevels_ - std::countr_zero(s);
  const bool iOdd = ((i / s) & 1) != 0, jOdd = ((j / s) & 1) != 0;
  if (m == 0 || (m == 1 && iOdd && jOdd)) {
    throw internalError("binary triangulation: a corner or the centre splits no edge");
  }
  if (iOdd && jOdd) {
    // The diagonal whose ends have an even coordinate sum in Ψ_{m−1}.
    const bool lowerLeftEven = ((((i - s) / (2 * s)) + ((j - s) / (2 * s))) & 1) == 0;
    if (lowerLeftEven) return {key(i - s, j - s), key(i + s, j + s)};
    return {key(i + s, j - s), key(i - s, j + s)};
  }
  if (iOdd) return {key(i - s, j), key(i + s, j)};
  return {key(i, j - s), key(i, j + s)};
}

std::uint64_t BinaryTriangulation::cellCentre(int level, std::uint64_t ci, std::uint64_t cj) const {
  const std::uint64_t spacing = side_ >> level;
  return key(ci * spacing + spacing / 2, cj * spacing + spacing / 2);
}

void BinaryTriangulation::activateOne(std::uint64_t k) {
  if (ids_.insert(k, static_cast<std::uint32_t>(keys_.size()))) keys_.push_back(k);
}

std::size_t BinaryTriangulation::activate(std::uint64_t k) {
  if (k > key(side_, side_)) {
    throw inputError("binary triangulation: vertex key " + std::to_string(k) + " is outside the grid");
  }
  if (isActive(k)) return 0;
  // Depth-first over the ancestors; parents are activated before children so
  // that dense ids grow from coarse to fine along every ancestor chain.
  std::size_t added = 0;
  std::vector<std::uint64_t> stack{k};
  while (!stack.empty()) {
    const std::uint64_t v = stack.back();
    if (isActive(v)) {
      stack.pop_back();
      continue;
    }
    bool ready = true;
    for (std::uint64_t p : parents(v)) {
      if (!isActive(p)) {
        stack.push_back(p);
        ready = false;
      }
    }
    if (ready) {
      activateOne(v);
      ++added;
      stack.pop_back();
    }
  }
  return added;
}

std::array<BinaryTriangle, 4> BinaryTriangulation::roots() const {
  const std::uint64_t bl = key(0, 0), br = key(side_, 0), tr = key(side_, side_), tl = key(0, side_);
  const std::uint64_t c = key(side_ / 2, side_ / 2);
  return {BinaryTriangle{bl, c, br, 4, 0}, BinaryTriangle{br, c, tr, 5, 0}, BinaryTriangle{tr, c, tl, 6, 0},
          BinaryTriangle{tl, c, bl, 7, 0}};
}

std::vector<BinaryTriangle> BinaryTriangulation::triangles() const {
  std::vector<BinaryTriangle> out;
  out.reserve(2 * keys_.size());
  std::vector<BinaryTriangle> stack;
  const int maxDepth = 2 * gridLevels_ - 2;  // deepest triangle whose split vertex exists
  for (const auto& root : roots()) {
    stack.push_back(root);
    while (!stack.empty()) {
      const BinaryTriangle t = stack.back();
      stack.pop_back();
      const std::uint64_t j = (t.l + t.r) / 2;
      if (t.depth <= maxDepth && isActive(j)) {
        // SubmeshRefine(l, a, r): recurse on (a, j, l) and (r, j, a), in
        // this order at even depths and reversed at odd ones, so that the
        // leaves follow a Sierpiński curve (consecutive ones share an edge).
        const BinaryTriangle first{t.a, j, t.l, t.path << 1, t.depth + 1};
        const BinaryTriangle second{t.r, j, t.a, (t.path << 1) | 1, t.depth + 1};
        if (t.depth % 2 == 0) {
          stack.push_back(second);
          stack.push_back(first);
        } else {
          stack.push_back(first);
          stack.push_back(second);
        }
      } else {
        out.push_back(t);
      }
    }
  }
  return out;
}

BinaryTriangle BinaryTriangulation::triangleFromPath(std::uint64_t path) const {
  const int bits = 64 - std::countl_zero(path);
  if (bits < 3) throw internalError("binary triangulation: malformed triangle path");
  const int steps = bits - 3;
  BinaryTriangle t = roots()[(path >> steps) & 3];
  for (int s = steps - 1; s >= 0; --s) {
    const std::uint64_t j = (t.l + t.r) / 2;
    if ((path >> s) & 1) {
      t = BinaryTriangle{t.r, j, t.a, (t.path << 1) | 1, t.depth + 1};
    } else {
      t = BinaryTriangle{t.a, j, t.l, t.path << 1, t.depth + 1};
    }
  }
  return t;
}

BinaryLocation BinaryTriangulation::descend(Point2 g, BinaryTriangle t) const {
  const int maxDepth = 2 * gridLevels_ - 2;
  // Grid coordinates ride along with the keys (midpoints are means of both),
  // so the loop needs no integer division.
  auto grid = [&](std::uint64_t k) { return Point2{static_cast<double>(column(k)), static_cast<double>(row(k))}; };
  Point2 pl = grid(t.l), pa = grid(t.a), pr = grid(t.r);
  while (t.depth <= maxDepth) {
    const std::uint64_t j = (t.l + t.r) / 2;
    if (!isActive(j)) break;
    const Point2 pj{0.5 * (pl.x + pr.x), 0.5 * (pl.y + pr.y)};
    // The line a–j splits (l, r, a); p goes with l when on l's side.
    const bool lSide = geometry::orient2dInexact(pa, pj, g) * geometry::orient2dInexact(pa, pj, pl) >= 0.0;
    if (lSide) {
      t = BinaryTriangle{t.a, j, t.l, t.path << 1, t.depth + 1};
      const Point2 oldA = pa;
      pr = pl;
      pl = oldA;
      pa = pj;
    } else {
      t = BinaryTriangle{t.r, j, t.a, (t.path << 1) | 1, t.depth + 1};
      pl = pr;
      pr = pa;
      pa = pj;
    }
  }
  const double area = geometry::orient2dInexact(pl, pr, pa);
  const double bl = geometry::orient2dInexact(g, pr, pa) / area;
  const double br = geometry::orient2dInexact(pl, g, pa) / area;
  return {t, {bl, br, 1.0 - bl - br}};
}

BinaryLocation BinaryTriangulation::locate(Point2 p) const {
  const Point2 g = toGrid(p);
  const double n = static_cast<double>(side_);
  if (!(g.x >= 0.0 && g.x <= n && g.y >= 0.0 && g.y <= n)) {
    throw inputError("point (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                         ") is outside the square domain of the binary triangulation",
                     {}, "choose a domain that covers every data point");
  }
  return descend(g, roots()[static_cast<std::size_t>(rootIndex(p))]);
}

int BinaryTriangulation::rootIndex(Point2 p) const {
  const Point2 g = toGrid(p);
  const double n = static_cast<double>(side_);
  const double dx = g.x - n / 2, dy = g.y - n / 2;
  if (std::abs(dy) >= std::abs(dx)) return dy < 0 ? 0 : 2;
  return dx > 0 ? 1 : 3;
}

BinaryLocation BinaryTriangulation::locateFrom(Point2 p, std::uint64_t path) const {
  return descend(toGrid(p), triangleFromPath(path));
}

std::vector<std::uint64_t> BinaryTriangulation::triangleStrip() const {
  // The triangles in SubmeshRefine order follow a Sierpiński curve, so
  // consecutive triangles mostly share an edge. Each is appended with one
  // vertex when it shares the strip's last edge, with a swap (the strip's
  // third-last vertex repeated before its last one: a degenerate triangle)
  // when it shares the previous triangle's other edge at the last vertex, and
  // otherwise the strip restarts through degenerate triangles.
  const auto tris = triangles();
  std::vector<std::uint64_t> s;
  s.reserve(tris.size() * 2);
  auto sameCycle = [](std::uint64_t x, std::uint64_t y, std::uint64_t z, const BinaryTriangle& t) {
    return (x == t.l && y == t.r && z == t.a) || (x == t.r && y == t.a && z == t.l) ||
           (x == t.a && y == t.l && z == t.r);
  };
  // Appends the vertex of t that completes (s[n−2], s[n−1], v), if that
  // triangle, read with the strip's alternating orientation, is t.
  auto tryAppend = [&](const BinaryTriangle& t) {
    const std::size_t n = s.size();
    const std::uint64_t x = s[n - 2], y = s[n - 1];
    if (x == y) return false;
    for (std::uint64_t v : {t.l, t.r, t.a}) {
      if (v == x || v == y) continue;
      const bool even = ((n - 2) % 2) == 0;
      if (even ? sameCycle(x, y, v, t) : sameCycle(y, x, v, t)) {
        s.push_back(v);
        return true;
      }
    }
    return false;
  };
  for (const auto& t : tris) {
    if (s.empty()) {
      s.insert(s.end(), {t.l, t.r, t.a});
      continue;
    }
    if (tryAppend(t)) continue;
    const std::size_t n = s.size();
    if (n >= 3) {
      const std::uint64_t last = s[n - 1];
      s.back() = s[n - 3];
      s.push_back(last);
      if (tryAppend(t)) continue;
      s.pop_back();
      s.back() = last;
    }
    const std::uint64_t last = s.back();
    s.push_back(last);
    s.push_back(t.l);
    s.push_back(t.l);
    if ((s.size() - 1) % 2 == 0) {
      s.insert(s.end(), {t.r, t.a});
    } else {
      s.insert(s.end(), {t.a, t.r});
    }
  }
  return s;
}

std::int32_t NestedLocator::add(const BinaryTriangulation& mesh, const KeyIndexMap& leafIndex,
                               const BinaryTriangle& t) {
  if (!mesh.isSplit(t)) {
    const std::uint32_t id = leafIndex.find(t.path);
    if (id == KeyIndexMap::kNone) throw internalError("nested location: a leaf triangle is not in the triangulation");
    return -1 - static_cast<std::int32_t>(id);
  }
  const std::uint64_t j = (t.l + t.r) / 2;
  const Point2 pl = mesh.gridPosition(t.l), pa = mesh.gridPosition(t.a), pr = mesh.gridPosition(t.r);
  const Point2 pj{0.5 * (pl.x + pr.x), 0.5 * (pl.y + pr.y)};
  const auto index = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({pa, pj, geometry::orient2dInexact(pa, pj, pl), {0, 0}});
  const std::int32_t first = add(mesh, leafIndex, BinaryTriangle{t.a, j, t.l, t.path << 1, t.depth + 1});
  const std::int32_t second = add(mesh, leafIndex, BinaryTriangle{t.r, j, t.a, (t.path << 1) | 1, t.depth + 1});
  nodes_[static_cast<std::size_t>(index)].child[0] = first;
  nodes_[static_cast<std::size_t>(index)].child[1] = second;
  return index;
}

}  // namespace tinsmith::fit
