// The mesh validator (see validate.hpp).
#include "core/mesh/validate.hpp"

#include <cmath>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "core/geometry/predicates.hpp"

namespace tinsmith {
namespace {

class Collector {
 public:
  Collector(ValidationReport& r, std::size_t max) : r_(r), max_(max) {}
  void add(const std::string& s) {
    r_.ok = false;
    ++r_.problemCount;
    if (r_.problems.size() < max_) r_.problems.push_back(s);
  }

 private:
  ValidationReport& r_;
  std::size_t max_;
};

std::string edgeName(const Mesh& m, HalfedgeId h) {
  return std::to_string(m.origin(h).value) + "-" + std::to_string(m.target(h).value);
}

}  // namespace

std::string ValidationReport::summary() const {
  std::ostringstream s;
  s << (ok ? "ok" : "FAILED") << ": " << vertices << " vertices, " << triangles << " triangles, "
    << edges << " edges (" << boundaryEdges << " on the boundary in " << boundaryLoops
    << (boundaryLoops == 1 ? " loop), " : " loops), ") << constrainedEdges << " constrained edges";
  if (!ok) {
    s << "; " << problemCount << " problems";
    for (const auto& p : problems) s << "\n  " << p;
    if (problems.size() < problemCount) s << "\n  …";
  }
  return s.str();
}

ValidationReport validate(const Mesh& m, const ValidationOptions& options) {
  ValidationReport r;
  Collector problems(r, options.maxProblems);
  for (const auto& p : m.buildProblems()) problems.add(p);

  const std::size_t nt = m.triangleCount(), nh = m.halfedgeCount();
  r.triangles = nt;
  std::vector<std::uint32_t> cornersAt(m.vertexCount(), 0);

  for (std::size_t v = 0; v < m.vertexCount(); ++v) {
    const Point3& p = m.point(VertexId(static_cast<std::uint32_t>(v)));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      problems.add("vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }

  // Orientation.
  for (std::uint32_t t = 0; t < nt; ++t) {
    const auto v = m.vertices(TriangleId(t));
    for (VertexId x : v) ++cornersAt[x.value];
    if (geometry::orient2d(m.xy(v[0]), m.xy(v[1]), m.xy(v[2])) <= 0) {
      problems.add("triangle " + std::to_string(t) + " (" + std::to_string(v[0].value) + ", " +
                   std::to_string(v[1].value) + ", " + std::to_string(v[2].value) +
                   ") is not strictly counter-clockwise");
    }
  }

  // Twins and constraint flags.
  std::size_t boundary = 0, interiorHalf = 0, constrained = 0;
  for (std::uint32_t i = 0; i < nh; ++i) {
    const HalfedgeId h(i);
    const HalfedgeId t = m.twin(h);
    if (!t.valid()) {
      ++boundary;
      if (m.isConstrained(h)) ++constrained;
    } else {
      ++interiorHalf;
      if (t.value >= nh || m.twin(t) != h || m.origin(t) != m.target(h) ||
          m.target(t) != m.origin(h)) {
        problems.add("half-edge " + std::to_string(i) + " (" + edgeName(m, h) +
                     ") and its twin are not symmetric");
        continue;
      }
      const auto fa = m.edgeFeatures(h), fb = m.edgeFeatures(t);
      if (!std::equal(fa.begin(), fa.end(), fb.begin(), fb.end())) {
        problems.add("edge " + edgeName(m, h) + " has different constraint features on its sides");
      }
      if (i < t.value && m.isConstrained(h)) ++constrained;
    }
    for (std::uint32_t f : m.edgeFeatures(h)) {
      if (f >= m.features().size()) {
        problems.add("edge " + edgeName(m, h) + " names unknown feature " + std::to_string(f));
      }
    }
  }
  r.boundaryEdges = boundary;
  r.edges = boundary + interiorHalf / 2;
  r.constrainedEdges = constrained;

  // Boundary loops, their orientation, and pinched vertices.
  std::vector<bool> seen(nh, false);
  long long loopSum = 0;
  std::size_t loops = 0;
  for (std::uint32_t i = 0; i < nh; ++i) {
    if (m.twin(HalfedgeId(i)).valid() || seen[i]) continue;
    ++loops;
    const Point2 o = m.xy(m.origin(HalfedgeId(i)));
    double area = 0;
    HalfedgeId h(i);
    bool broken = false;
    bool haveMin = false;
    Point2 minV;
    int minVisits = 0;  // a loop through a pinched vertex may pass it twice
    int turn = 0;
    for (std::size_t steps = 0; !seen[h.value]; ++steps) {
      seen[h.value] = true;
      const Point2 a = m.xy(m.origin(h)), b = m.xy(m.target(h));
      area += geometry::orient2dInexact(o, a, b);
      // Next boundary half-edge leaving target(h): rotate clockwise from next(h).
      HalfedgeId g = Mesh::next(h);
      std::size_t guard = 0;
      while (m.twin(g).valid() && guard++ <= nh) g = Mesh::next(m.twin(g));
      if (guard > nh || steps > nh) {
        broken = true;
        break;
      }
      // The loop's turn at its lexicographically smallest vertex gives its
      // orientation exactly (the float area can be wrong for slivers).
      const Point2 v = b;
      if (!haveMin || v.x < minV.x || (v.x == minV.x && v.y < minV.y)) {
        haveMin = true;
        minV = v;
        minVisits = 1;
        turn = geometry::orient2d(a, b, m.xy(m.target(g)));
      } else if (v == minV) {
        ++minVisits;
      }
      h = g;
    }
    if (broken) {
      problems.add("boundary loop through half-edge " + std::to_string(i) + " does not close");
      continue;
    }
    // At a vertex the loop passes twice (two holes touching there) the
    // local turn says nothing about the loop: take the area's sign.
    if (turn == 0 || minVisits > 1) turn = area > 0 ? 1 : -1;
    loopSum += turn;
  }
  r.boundaryLoops = loops;

  // Boundary half-edges leaving each boundary vertex (few: a map, not a
  // vertex-sized array).
  std::unordered_map<std::uint32_t, std::uint32_t> boundaryOutOf;
  for (std::uint32_t i = 0; i < nh; ++i) {
    if (!m.twin(HalfedgeId(i)).valid()) ++boundaryOutOf[m.origin(HalfedgeId(i)).value];
  }
  long long pinch = 0;
  std::size_t usedVertices = 0;
  for (std::uint32_t v = 0; v < m.vertexCount(); ++v) {
    if (cornersAt[v] == 0) continue;
    ++usedVertices;
    const auto out = boundaryOutOf.find(v);
    const std::uint32_t boundaryOut = out == boundaryOutOf.end() ? 0 : out->second;
    if (boundaryOut > 1) pinch += boundaryOut - 1;
    // An interior vertex's fan must wind exactly once around it.
    if (boundaryOut == 0) {
      // Winding number, exactly: each CCW step turns by less than π, so count
      // the steps from the lower half-plane [π, 2π) into the upper [0, π).
      std::size_t fan = 0, winding = 0;
      const Point2 c = m.xy(VertexId(v));
      auto upper = [&c](const Point2& w) { return w.y > c.y || (w.y == c.y && w.x > c.x); };
      const HalfedgeId start = m.outgoing(VertexId(v));
      HalfedgeId h = start;
      do {
        ++fan;
        if (!upper(m.xy(m.target(h))) && upper(m.xy(m.origin(Mesh::prev(h))))) ++winding;
        h = m.twin(Mesh::prev(h));
      } while (h.valid() && h != start && fan <= cornersAt[v]);
      if (fan != cornersAt[v]) {
        problems.add("vertex " + std::to_string(v) + " has " + std::to_string(cornersAt[v]) +
                     " triangles but its star has " + std::to_string(fan) + " (non-manifold)");
      } else if (winding != 1) {
        problems.add("the star of interior vertex " + std::to_string(v) +
                     " does not wind once around it (folded triangles)");
      }
    }
  }
  r.vertices = usedVertices;

  const long long euler = static_cast<long long>(usedVertices) - static_cast<long long>(r.edges) +
                          static_cast<long long>(nt);
  if (nt > 0 && euler != loopSum - pinch) {
    problems.add("Euler characteristic V - E + F = " + std::to_string(euler) + ", expected " +
                 std::to_string(loopSum - pinch) + " from " + std::to_string(loops) +
                 " boundary loops");
  }

  if (options.checkDelaunay) {
    for (std::uint32_t i = 0; i < nh; ++i) {
      const HalfedgeId h(i);
      const HalfedgeId t = m.twin(h);
      if (!t.valid() || t.value < i || m.isConstrained(h) || m.twin(t) != h) continue;
      const Point2 a = m.xy(m.origin(h)), b = m.xy(m.target(h));
      const Point2 c = m.xy(m.origin(Mesh::prev(h))), d = m.xy(m.origin(Mesh::prev(t)));
      if (geometry::incircle(a, b, c, d) > 0) {
        problems.add("edge " + edgeName(m, h) + " is not locally Delaunay");
      }
    }
  }
  return r;
}

ValidationReport validate(const TinData& tin, const ValidationOptions& options) {
  return validate(Mesh::fromTinData(tin), options);
}

}  // namespace tinsmith
