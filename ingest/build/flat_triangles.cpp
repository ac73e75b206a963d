#include "ingest/build/flat_triangles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "ingest/tinfile/tin_view.hpp"

namespace tinsmith::ingest {

namespace {

// The analysis reads a TIN through one of two views (tin_view.hpp): TinData
// (tests, loaded files) or the CDT's Mesh (the builder, so that no TinData
// copy exists while it repairs), with the contour edges added here. The
// results are identical.
struct TinContours : TinDataView {
  /// Calls f(a, b) for every edge that a Contour feature constrains (an edge
  /// may come more than once, in either direction).
  template <class F>
  void forEachContourEdge(F&& f) const {
    for (const auto& e : tin.constrainedEdges)
      if (e.feature < tin.features.size() && tin.features[e.feature].kind == FeatureKind::Contour)
        f(e.a, e.b);
  }
  /// The same for (at least) the edges of `triangles`: here every contour edge.
  template <class F>
  void forEachContourEdgeOf(const std::vector<std::uint32_t>&, F&& f) const {
    forEachContourEdge(f);
  }
};

struct MeshContours : MeshView {
  template <class F>
  void forEachContourEdge(F&& f) const {
    for (std::uint32_t h = 0; h < mesh.halfedgeCount(); ++h) {
      const HalfedgeId he(h);
      if (!mesh.isConstrained(he)) continue;
      const HalfedgeId tw = mesh.twin(he);
      if (tw.valid() && tw.value < h) continue;  // each edge once
      visitIfContour(he, f);
    }
  }
  /// Only the edges of `triangles` (each edge once per triangle it borders).
  template <class F>
  void forEachContourEdgeOf(const std::vector<std::uint32_t>& triangles, F&& f) const {
    for (const std::uint32_t t : triangles)
      for (int k = 0; k < 3; ++k) {
        const HalfedgeId he = Mesh::halfedge(TriangleId(t), k);
        if (mesh.isConstrained(he)) visitIfContour(he, f);
      }
  }

 private:
  template <class F>
  void visitIfContour(HalfedgeId he, F& f) const {
    const auto& features = mesh.features();
    for (const std::uint32_t id : mesh.edgeFeatures(he)) {
      if (id < features.size() && features[id].kind == FeatureKind::Contour) {
        f(mesh.origin(he).value, mesh.target(he).value);
        return;
      }
    }
  }
};

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

double segmentDistance(const Point3& p, const Point3& a, const Point3& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

// Triangle adjacency for a subset of triangles: across[3i+k] is the triangle
// across the edge from corner k to corner k+1 of subset[i], or kNone when
// that neighbour is not in the subset (or there is none). The subset must
// hold both triangles of every edge wanted.
template <class View>
std::vector<std::uint32_t> neighbours(const View& tin, const std::vector<std::uint32_t>& subset) {
  struct Half {
    std::uint64_t key;
    std::uint32_t half;  // 3 × (index into subset) + corner
  };
  std::vector<Half> halves;
  halves.reserve(subset.size() * 3);
  for (std::uint32_t i = 0; i < subset.size(); ++i) {
    const auto tri = tin.triangle(subset[i]);
    for (std::uint32_t k = 0; k < 3; ++k) halves.push_back({edgeKey(tri[k], tri[(k + 1) % 3]), 3 * i + k});
  }
  std::sort(halves.begin(), halves.end(), [](const Half& a, const Half& b) {
    return a.key != b.key ? a.key < b.key : a.half < b.half;
  });
  std::vector<std::uint32_t> across(subset.size() * 3, kNone);
  for (std::size_t i = 0; i + 1 < halves.size(); ++i) {
    if (halves[i].key == halves[i + 1].key) {
      across[halves[i].half] = subset[halves[i + 1].half / 3];
      across[halves[i + 1].half] = subset[halves[i].half / 3];
      ++i;
    }
  }
  return across;
}

// The contour edges of `triangles` (and maybe others, but only edges with
// both ends marked in `ends`), as sorted keys.
template <class View>
std::vector<std::uint64_t> contourEdgeKeys(const View& tin, const std::vector<std::uint32_t>& triangles,
                                           const std::vector<char>& ends) {
  std::vector<std::uint64_t> keys;
  tin.forEachContourEdgeOf(triangles, [&](std::uint32_t a, std::uint32_t b) {
    if (ends[a] && ends[b]) keys.push_back(edgeKey(a, b));
  });
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

template <class View>
bool isFlat(const View& tin, const std::vector<char>& onContour, std::uint32_t t) {
  const auto tri = tin.triangle(t);
  if (!onContour[tri[0]] || !onContour[tri[1]] || !onContour[tri[2]]) return false;
  const auto& V = tin.points();
  const double z = V[tri[0]].z;
  return V[tri[1]].z == z && V[tri[2]].z == z;
}

template <class View>
std::vector<char> contourVerticesOf(const View& tin) {
  std::vector<char> on(tin.points().size(), 0);
  tin.forEachContourEdge([&on](std::uint32_t a, std::uint32_t b) { on[a] = on[b] = 1; });
  return on;
}

template <class View>
std::size_t countFlat(const View& tin) {
  const auto on = contourVerticesOf(tin);
  std::size_t n = 0;
  for (std::uint32_t t = 0; t < tin.triangleCount(); ++t) n += isFlat(tin, on, t) ? 1 : 0;
  return n;
}

template <class View>
FlatTriangleAnalysis analyse(const View& tin, double minSpacing) {
  FlatTriangleAnalysis out;
  const auto on = contourVerticesOf(tin);
  const std::size_t nt = tin.triangleCount();
  for (std::uint32_t t = 0; t < nt; ++t)
    if (isFlat(tin, on, t)) out.flatTriangles.push_back(t);
  if (out.flatTriangles.empty()) return out;
  // flatTriangles is ascending: a binary search tells whether t is flat.
  auto flat = [&out](std::uint32_t t) {
    return std::binary_search(out.flatTriangles.begin(), out.flatTriangles.end(), t);
  };

  // Only flat triangles and the triangles next to them need adjacency: those
  // share at least two vertices with a flat triangle. Keeps the analysis of a
  // million-triangle TIN with few flat triangles to linear scans, and its
  // memory to the size of that subset (nothing per triangle of the TIN).
  std::vector<char> onFlat(tin.points().size(), 0);
  for (const std::uint32_t t : out.flatTriangles)
    for (auto v : tin.triangle(t)) onFlat[v] = 1;
  std::vector<std::uint32_t> subset;  // ascending
  for (std::uint32_t t = 0; t < nt; ++t) {
    const auto tri = tin.triangle(t);
    if (onFlat[tri[0]] + onFlat[tri[1]] + onFlat[tri[2]] >= 2) subset.push_back(t);
  }
  auto local = [&subset](std::uint32_t t) {
    return static_cast<std::size_t>(std::lower_bound(subset.begin(), subset.end(), t) - subset.begin());
  };
  const auto acrossSubset = neighbours(tin, subset);
  auto acrossOf = [&](std::uint32_t t, std::uint32_t k) { return acrossSubset[3 * local(t) + k]; };
  // Every edge asked about below is an edge of a flat triangle.
  const auto contourKeys = contourEdgeKeys(tin, out.flatTriangles, onFlat);
  auto isContourEdge = [&](std::uint32_t a, std::uint32_t b) {
    return std::binary_search(contourKeys.begin(), contourKeys.end(), edgeKey(a, b));
  };
  const auto& V = tin.points();

  std::vector<std::uint32_t> regionOfLocal(subset.size(), kNone);
  auto region = [&](std::uint32_t t) -> std::uint32_t& { return regionOfLocal[local(t)]; };
  std::unordered_set<std::uint64_t> usedMidpoints;
  std::vector<std::uint32_t> members, stack;
  for (const std::uint32_t seed : out.flatTriangles) {
    if (region(seed) != kNone) continue;
    const auto id = static_cast<std::uint32_t>(out.regions++);
    const double z0 = V[tin.triangle(seed)[0]].z;
    // Flood the region: flat neighbours at the same level across non-contour edges.
    members.clear();
    stack.assign(1, seed);
    region(seed) = id;
    std::vector<std::pair<Point3, Point3>> ownContour;  // the region's z0 contour edges
    std::vector<Point3> exits;                          // vertices at another level next to it
    std::vector<double> outside;                        // levels across its contour edges
    while (!stack.empty()) {
      const std::uint32_t t = stack.back();
      stack.pop_back();
      members.push_back(t);
      const auto tri = tin.triangle(t);
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
        const std::uint32_t n = acrossOf(t, k);
        const bool contourEdge = isContourEdge(a, b);
        if (contourEdge) ownContour.push_back({V[a], V[b]});
        if (n == kNone) continue;
        if (!contourEdge && flat(n) && V[tin.triangle(n)[0]].z == z0) {
          if (region(n) == kNone) {
            region(n) = id;
            stack.push_back(n);
          }
          continue;
        }
        // The neighbour's vertex opposite the shared edge.
        std::uint32_t opposite = kNone;
        for (auto v : tin.triangle(n))
          if (v != a && v != b) opposite = v;
        if (opposite == kNone || V[opposite].z == z0) continue;
        if (contourEdge)
          outside.push_back(V[opposite].z);
        else
          exits.push_back(V[opposite]);
      }
    }
    std::sort(members.begin(), members.end());  // deterministic proposal order

    // Candidate positions, one per flat triangle.
    std::vector<Point3> candidates;
    for (const std::uint32_t t : members) {
      const auto tri = tin.triangle(t);
      int longest = 0;
      double best = -1;
      for (int k = 0; k < 3; ++k) {
        const Point3& a = V[tri[k]];
        const Point3& b = V[tri[(k + 1) % 3]];
        const double len = std::hypot(b.x - a.x, b.y - a.y);
        if (len > best) {
          best = len;
          longest = k;
        }
      }
      const std::uint32_t a = tri[longest], b = tri[(longest + 1) % 3];
      Point3 p;
      if (!isContourEdge(a, b)) {
        if (!usedMidpoints.insert(edgeKey(a, b)).second) continue;
        p = {0.5 * (V[a].x + V[b].x), 0.5 * (V[a].y + V[b].y), z0};
      } else {
        p = {(V[tri[0]].x + V[tri[1]].x + V[tri[2]].x) / 3.0,
             (V[tri[0]].y + V[tri[1]].y + V[tri[2]].y) / 3.0, z0};
      }
      double nearest = std::numeric_limits<double>::infinity();
      for (auto v : tri) nearest = std::min(nearest, std::hypot(p.x - V[v].x, p.y - V[v].y));
      if (nearest <= minSpacing) continue;
      candidates.push_back(p);
    }
    if (candidates.empty()) continue;

    auto distanceToContour = [&](const Point3& p) {
      double d = std::numeric_limits<double>::infinity();
      for (const auto& [a, b] : ownContour) d = std::min(d, segmentDistance(p, a, b));
      if (!std::isfinite(d))  // no contour edge on the region: its vertices are on the level
        for (const std::uint32_t t : members)
          for (auto v : tin.triangle(t)) d = std::min(d, std::hypot(p.x - V[v].x, p.y - V[v].y));
      return d;
    };

    if (!exits.empty()) {
      for (Point3 p : candidates) {
        const double d0 = distanceToContour(p);
        double d1 = std::numeric_limits<double>::infinity();
        double z1 = z0;
        for (const Point3& q : exits) {
          const double d = std::hypot(p.x - q.x, p.y - q.y);
          if (d < d1) {
            d1 = d;
            z1 = q.z;
          }
        }
        p.z = z0 + (z1 - z0) * d0 / (d0 + d1);
        out.proposals.push_back(p);
      }
    } else if (!outside.empty()) {
      ++out.closedRegions;
      std::size_t below = 0;
      std::vector<double> steps;
      for (double z : outside) {
        below += z < z0 ? 1 : 0;
        steps.push_back(std::abs(z - z0));
      }
      std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2),
                       steps.end());
      const double h = 0.5 * steps[steps.size() / 2];
      const double sign = 2 * below >= outside.size() ? 1.0 : -1.0;  // summit : pit
      std::vector<double> d0(candidates.size());
      double d0max = 0;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        d0[i] = distanceToContour(candidates[i]);
        d0max = std::max(d0max, d0[i]);
      }
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        Point3 p = candidates[i];
        p.z = z0 + sign * h * (d0max > 0 ? d0[i] / d0max : 1.0);
        out.proposals.push_back(p);
      }
    }
  }
  return out;
}

}  // namespace

std::vector<char> contourVertices(const TinData& tin) { return contourVerticesOf(TinContours{{tin}}); }
std::vector<char> contourVertices(const Mesh& mesh) { return contourVerticesOf(MeshContours{{mesh}}); }

std::size_t countFlatTriangles(const TinData& tin) { return countFlat(TinContours{{tin}}); }
std::size_t countFlatTriangles(const Mesh& mesh) { return countFlat(MeshContours{{mesh}}); }

FlatTriangleAnalysis analyseFlatTriangles(const TinData& tin, double minSpacing) {
  return analyse(TinContours{{tin}}, minSpacing);
}
FlatTriangleAnalysis analyseFlatTriangles(const Mesh& mesh, double minSpacing) {
  return analyse(MeshContours{{mesh}}, minSpacing);
}

}  // namespace tinsmith::ingest
