// The mesh validator (see validate.hpp).
#include "core/mesh/validate.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

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
    << " loops), " << constrainedEdges << " constrained";
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
  std::vector<char> seen(nh, 0);
  long long loopSum = 0;
  std::size_t loops = 0;
  for (std::uint32_t i = 0; i < nh; ++i) {
    if (m.twin(HalfedgeId(i)).valid() || seen[i]) continue;
    ++loops;
    const Point2 o = m.xy(m.origin(HalfedgeId(i)));
    double area = 0;
    HalfedgeId h(i);
    bool broken = false;
    for (std::size_t steps = 0; !seen[h.value]; ++steps) {
      seen[h.value] = 1;
      const Point2 a = m.xy(m.origin(h)), b = m.xy(m.target(h));
      area += (a.x - o.x) * (b.y - o.y) - (b.x - o.x) * (a.y - o.y);
      // Next boundary half-edge leaving target(h): rotate clockwise from next(h).
      HalfedgeId g = Mesh::next(h);
      std::size_t guard = 0;
      while (m.twin(g).valid() && guard++ <= nh) g = Mesh::next(m.twin(g));
      if (guard > nh || steps > nh) {
        broken = true;
        break;
      }
      h = g;
    }
    if (broken) {
      problems.add("boundary loop through half-edge " + std::to_string(i) + " does not close");
      continue;
    }
    loopSum += area > 0 ? 1 : -1;
  }
  r.boundaryLoops = loops;

  std::vector<std::uint32_t> boundaryOut(m.vertexCount(), 0);
  for (std::uint32_t i = 0; i < nh; ++i) {
    if (!m.twin(HalfedgeId(i)).valid()) ++boundaryOut[m.origin(HalfedgeId(i)).value];
  }
  long long pinch = 0;
  std::size_t usedVertices = 0;
  for (std::uint32_t v = 0; v < m.vertexCount(); ++v) {
    if (cornersAt[v] == 0) continue;
    ++usedVertices;
    if (boundaryOut[v] > 1) pinch += boundaryOut[v] - 1;
    // An interior vertex's fan must wind exactly once around it.
    if (boundaryOut[v] == 0) {
      double angle = 0;
      std::size_t fan = 0;
      const Point2 c = m.xy(VertexId(v));
      m.forEachOutgoing(VertexId(v), [&](HalfedgeId h) {
        ++fan;
        const Point2 a = m.xy(m.target(h)), b = m.xy(m.origin(Mesh::prev(h)));
        angle += std::atan2((a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x),
                            (a.x - c.x) * (b.x - c.x) + (a.y - c.y) * (b.y - c.y));
      });
      if (fan != cornersAt[v]) {
        problems.add("vertex " + std::to_string(v) + " has " + std::to_string(cornersAt[v]) +
                     " triangles but its star has " + std::to_string(fan) + " (non-manifold)");
      } else if (std::fabs(angle - 2 * std::numbers::pi) > 1e-6) {
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
