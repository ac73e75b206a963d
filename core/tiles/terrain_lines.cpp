#include "core/tiles/terrain_lines.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "core/base/error.hpp"

namespace tinsmith::tiles {

namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

double distanceToSegment(const Point3& p, const Point3& a, const Point3& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  const double len2 = dx * dx + dy * dy + dz * dz;
  double t = 0.0;
  if (len2 > 0.0)
    t = std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy + (p.z - a.z) * dz) / len2, 0.0, 1.0);
  const double ex = a.x + t * dx - p.x, ey = a.y + t * dy - p.y, ez = a.z + t * dz - p.z;
  return std::sqrt(ex * ex + ey * ey + ez * ez);
}

/// Marks the vertices of points[first..last] that Douglas–Peucker keeps
/// (iterative, so long lines cannot overflow the stack).
void markKept(std::span<const Point3> points, std::size_t first, std::size_t last, double tolerance,
              const ChordError& chordError, std::vector<char>& keep) {
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j <= i + 1) continue;
    double worst = -1.0;
    std::size_t at = i;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double d = distanceToSegment(points[k], points[i], points[j]);
      if (d > worst) {
        worst = d;
        at = k;
      }
    }
    if (worst > tolerance || (chordError && chordError(points[i], points[j]) > tolerance)) {
      keep[at] = 1;
      stack.push_back({i, at});
      stack.push_back({at, j});
    }
  }
}

bool lexLess(const Point3& a, const Point3& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

}  // namespace

bool isBreakLineKind(FeatureKind kind) {
  return kind == FeatureKind::Road || kind == FeatureKind::River || kind == FeatureKind::Lake ||
         kind == FeatureKind::BreakLine || kind == FeatureKind::Other;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> boundaryHalfEdges(const TinData& tin) {
  // Each half-edge as 2·(its greater end) + 1 when it runs from that end,
  // bucketed by its lesser end (a counting sort), each bucket sorted: twins
  // are neighbours.
  const std::size_t nv = tin.vertices.size();
  if (nv >= (std::size_t{1} << 31))
    throw internalError("boundaryHalfEdges: a TIN of 2^31 vertices or more");
  const auto valid = [&](const std::array<std::uint32_t, 3>& t) {
    return t[0] < nv && t[1] < nv && t[2] < nv && t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
  };
  // start[v]: first of the lesser end v's bucket, once filled backwards.
  std::vector<std::uint32_t> start(nv + 1, 0);
  std::size_t halfEdges = 0;
  for (const auto& t : tin.triangles) {
    if (!valid(t)) continue;
    for (int k = 0; k < 3; ++k) ++start[std::min(t[k], t[(k + 1) % 3])];
    halfEdges += 3;
  }
  if (halfEdges >= (std::size_t{1} << 32))
    throw internalError("boundaryHalfEdges: a TIN of 2^32 half-edges or more");
  for (std::size_t v = 1; v <= nv; ++v) start[v] += start[v - 1];
  std::vector<std::uint32_t> entries(halfEdges);
  for (const auto& t : tin.triangles) {
    if (!valid(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      entries[--start[std::min(a, b)]] = 2 * std::max(a, b) + (a > b ? 1U : 0U);
    }
  }
  std::vector<Edge> boundary;
  for (std::uint32_t lo = 0; lo < nv; ++lo) {
    const auto first = entries.begin() + start[lo], last = entries.begin() + start[lo + 1];
    std::sort(first, last);
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && *j / 2 == *i / 2) ++j;
      const bool twins = j - i == 2 && (*i & 1U) != (*(i + 1) & 1U);
      for (; !twins && i != j; ++i) {
        const std::uint32_t hi = *i / 2;
        boundary.push_back(*i & 1U ? Edge{hi, lo} : Edge{lo, hi});
      }
      i = j;
    }
  }
  std::sort(boundary.begin(), boundary.end());
  return boundary;
}

std::vector<TerrainLine> extractTerrainLines(const TinData& tin) {
  std::vector<TerrainLine> lines;
  const std::size_t nv = tin.vertices.size();

  // Break lines: every break-line edge once, with the highest-priority kind.
  std::map<Edge, FeatureKind> edges;
  for (const auto& e : tin.constrainedEdges) {
    if (e.feature >= tin.features.size()) continue;
    const FeatureKind kind = tin.features[e.feature].kind;
    if (!isBreakLineKind(kind)) continue;
    const Edge key{std::min(e.a, e.b), std::max(e.a, e.b)};
    auto [it, inserted] = edges.emplace(key, kind);
    if (!inserted && constraintPriority(kind) > constraintPriority(it->second)) it->second = kind;
  }
  std::vector<std::vector<std::pair<std::uint32_t, FeatureKind>>> adjacent(edges.empty() ? 0 : nv);
  for (const auto& [e, kind] : edges) {
    adjacent[e.first].push_back({e.second, kind});
    adjacent[e.second].push_back({e.first, kind});
  }
  for (auto& a : adjacent)
    std::sort(a.begin(), a.end(), [](auto& p, auto& q) { return p.first < q.first; });
  auto isNode = [&](std::uint32_t v) {
    return adjacent[v].size() != 2 || adjacent[v][0].second != adjacent[v][1].second;
  };
  std::set<Edge> used;
  auto take = [&](std::uint32_t a, std::uint32_t b) {
    return used.insert(Edge{std::min(a, b), std::max(a, b)}).second;
  };
  auto walk = [&](std::uint32_t start, std::uint32_t next, FeatureKind kind, bool closed) {
    TerrainLine line;
    line.kind = kind;
    line.closed = closed;
    line.points.push_back(tin.vertices[start]);
    std::uint32_t prev = start, at = next;
    while (true) {
      if (closed && at == start) break;
      line.points.push_back(tin.vertices[at]);
      if (!closed && isNode(at)) break;
      std::uint32_t following = prev;
      for (const auto& [w, k] : adjacent[at]) {
        if (w != prev && k == kind) following = w;
      }
      if (following == prev || !take(at, following)) break;
      prev = at;
      at = following;
    }
    if (line.points.size() >= 2) lines.push_back(std::move(line));
  };
  for (std::uint32_t v = 0; v < adjacent.size(); ++v) {
    if (!isNode(v)) continue;
    for (const auto& [w, kind] : adjacent[v]) {
      if (take(v, w)) walk(v, w, kind, false);
    }
  }
  for (std::uint32_t v = 0; v < adjacent.size(); ++v) {  // closed loops without a node
    for (const auto& [w, kind] : adjacent[v]) {
      if (take(v, w)) walk(v, w, kind, true);
    }
  }

  // Domain boundary: half-edges without a twin (interior on their left),
  // chained from the lowest origin, each step to the lowest unused target.
  const std::vector<Edge> boundary = boundaryHalfEdges(tin);
  std::vector<char> done(boundary.size(), 0);
  for (std::size_t first = 0; first < boundary.size(); ++first) {
    if (done[first]) continue;
    TerrainLine ring;
    ring.kind = FeatureKind::Boundary;
    ring.ring = ring.closed = true;
    const std::uint32_t start = boundary[first].first;
    std::uint32_t at = start;
    while (true) {
      auto it = std::lower_bound(boundary.begin(), boundary.end(), Edge{at, 0});
      while (it != boundary.end() && it->first == at && done[it - boundary.begin()]) ++it;
      if (it == boundary.end() || it->first != at) break;
      done[it - boundary.begin()] = 1;
      ring.points.push_back(tin.vertices[at]);
      at = it->second;
      if (at == start) break;
    }
    if (ring.points.size() >= 3) lines.push_back(std::move(ring));
  }
  return lines;
}

TerrainLine simplify(const TerrainLine& line, double tolerance, const ChordError& chordError) {
  TerrainLine out;
  out.kind = line.kind;
  out.ring = line.ring;
  out.closed = line.closed;
  const auto& pts = line.points;
  if (pts.size() <= 2 || (line.closed && pts.size() <= 3)) {
    out.points = pts;
    return out;
  }
  std::vector<char> keep(pts.size(), 0);
  keep.front() = 1;
  if (line.closed) {
    // Anchor at the first vertex and the vertex farthest from it.
    std::size_t far = 1;
    double best = -1.0;
    for (std::size_t k = 1; k < pts.size(); ++k) {
      const double d = distanceToSegment(pts[k], pts[0], pts[0]);  // to the point
      if (d > best) {
        best = d;
        far = k;
      }
    }
    keep[far] = 1;
    markKept(pts, 0, far, tolerance, chordError, keep);
    std::vector<Point3> tail(pts.begin() + static_cast<std::ptrdiff_t>(far), pts.end());
    tail.push_back(pts[0]);
    std::vector<char> keepTail(tail.size(), 0);
    markKept(tail, 0, tail.size() - 1, tolerance, chordError, keepTail);
    for (std::size_t k = 1; k + 1 < tail.size(); ++k) {
      if (keepTail[k]) keep[far + k] = 1;
    }
    // A ring keeps at least three vertices: add the farthest from the chord.
    if (std::count(keep.begin(), keep.end(), 1) < 3) {
      double worst = -1.0;
      std::size_t at = 0;
      for (std::size_t k = 1; k < pts.size(); ++k) {
        if (keep[k]) continue;
        const double d = distanceToSegment(pts[k], pts[0], pts[far]);
        if (d > worst) {
          worst = d;
          at = k;
        }
      }
      keep[at] = 1;
    }
  } else {
    keep.back() = 1;
    markKept(pts, 0, pts.size() - 1, tolerance, chordError, keep);
  }
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (keep[k]) out.points.push_back(pts[k]);
  }
  return out;
}

std::vector<ClippedPiece> clipToRect(const TerrainLine& line, const Rect& rect, double snap) {
  std::vector<ClippedPiece> pieces;
  const auto& pts = line.points;
  const std::size_t n = pts.size();
  if (n < 2) return pieces;
  const std::size_t segments = line.closed ? n : n - 1;

  bool allInside = true;
  for (const auto& p : pts) allInside = allInside && rect.contains(p.xy());
  if (allInside) {
    pieces.push_back({pts, line.kind, line.ring, line.closed});
    return pieces;
  }

  auto snapToCorner = [&](Point3 p) {
    const double cx = std::abs(p.x - rect.x0) <= snap
                          ? rect.x0
                          : (std::abs(p.x - rect.x1) <= snap ? rect.x1 : p.x);
    const double cy = std::abs(p.y - rect.y0) <= snap
                          ? rect.y0
                          : (std::abs(p.y - rect.y1) <= snap ? rect.y1 : p.y);
    if ((cx == rect.x0 || cx == rect.x1) && (cy == rect.y0 || cy == rect.y1)) {
      p.x = cx;
      p.y = cy;
    }
    return p;
  };

  ClippedPiece current{{}, line.kind, line.ring, false};
  auto flush = [&] {
    if (current.points.size() >= 2) pieces.push_back(current);
    current.points.clear();
  };
  for (std::size_t s = 0; s < segments; ++s) {
    const Point3& a = pts[s];
    const Point3& b = pts[(s + 1) % n];
    const bool aFirst = lexLess(a, b) || !lexLess(b, a);
    const Point3& c0 = aFirst ? a : b;
    const Point3& c1 = aFirst ? b : a;
    // Points along a → b: the ends and the crossings of the side lines.
    std::vector<std::pair<double, Point3>> along{{0.0, a}, {1.0, b}};
    auto crossing = [&](bool vertical, double line) {
      const double p0 = vertical ? c0.x : c0.y, p1 = vertical ? c1.x : c1.y;
      if (!((p0 < line && line < p1) || (p1 < line && line < p0))) return;
      const double t = (line - p0) / (p1 - p0);
      Point3 q;
      q.z = c0.z + t * (c1.z - c0.z);
      if (vertical) {
        q.x = line;
        q.y = c0.y + t * (c1.y - c0.y);
        if (q.y < rect.y0 - snap || q.y > rect.y1 + snap) return;
        q.y = std::clamp(q.y, rect.y0, rect.y1);
      } else {
        q.y = line;
        q.x = c0.x + t * (c1.x - c0.x);
        if (q.x < rect.x0 - snap || q.x > rect.x1 + snap) return;
        q.x = std::clamp(q.x, rect.x0, rect.x1);
      }
      along.push_back({aFirst ? t : 1.0 - t, snapToCorner(q)});
    };
    crossing(true, rect.x0);
    crossing(true, rect.x1);
    crossing(false, rect.y0);
    crossing(false, rect.y1);
    std::sort(along.begin(), along.end(),
              [](const auto& p, const auto& q) { return p.first < q.first; });
    for (std::size_t k = 0; k + 1 < along.size(); ++k) {
      const Point3& p = along[k].second;
      const Point3& q = along[k + 1].second;
      if (p.x == q.x && p.y == q.y) continue;
      const Point2 mid{0.5 * (p.x + q.x), 0.5 * (p.y + q.y)};
      if (!rect.contains(mid)) {
        flush();
        continue;
      }
      if (current.points.empty()) current.points.push_back(p);
      current.points.push_back(q);
    }
  }
  flush();
  // A closed line that started inside: its last piece continues into its first.
  if (line.closed && pieces.size() >= 2 && rect.contains(pts[0].xy())) {
    auto& first = pieces.front();
    auto& last = pieces.back();
    if (last.points.back().x == first.points.front().x &&
        last.points.back().y == first.points.front().y) {
      last.points.insert(last.points.end(), first.points.begin() + 1, first.points.end());
      pieces.front() = std::move(last);
      pieces.pop_back();
    }
  }
  return pieces;
}

}  // namespace tinsmith::tiles
