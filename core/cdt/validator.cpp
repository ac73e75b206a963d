// Cdt::validate (see cdt.hpp): the mesh's own checks (core/mesh/validate)
// plus what the CDT promised about its input — every input vertex present or
// reported, every constraint segment a chain of edges carrying its feature
// near the input segment.
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/cdt/cdt_impl.hpp"

namespace tinsmith {

namespace {
std::string formatCoord(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
}  // namespace

ValidationReport Cdt::validateCounting(const ValidationOptions& options,
                                       std::size_t& chainSteps) const {
  ValidationReport r = tinsmith::validate(mesh(), options);
  const Impl& m = *impl_;
  if (m.meshOf.size() != m.xy.size()) throw internalError("the input vertex map is out of date");
  auto add = [&](const std::string& s) {
    r.ok = false;
    ++r.problemCount;
    if (r.problems.size() < options.maxProblems) r.problems.push_back(s);
  };
  // Every input vertex is a mesh vertex, or merged/dropped and reported.
  cdt::IdVector<VertexId, std::uint8_t> merged(m.xy.size(), 0);
  for (const auto& mg : m.report.merges) merged[mg.merged] = 1;
  for (std::uint32_t k = 0; k < m.xy.size(); ++k) {
    const VertexId v(k);
    if (m.rep[v] != v && !merged[v]) {
      add("input vertex " + std::to_string(k) + " is neither a vertex nor reported as merged");
    }
    if (m.meshOf[v].valid()) {
      const Point3& p = mesh().point(m.meshOf[v]);
      if (m.rep[v] == v && !(p.xy() == m.xy[v])) {
        add("input vertex " + std::to_string(k) + " moved");
      }
    }
  }
  // Every input constraint segment is a chain of mesh edges carrying its
  // feature and running along the input segment (checked from the input
  // coordinates, not from the edge flags, and when no domain clips the
  // constraints): a path of edges with its feature from the mesh vertex of one
  // end to the other through vertices within rounding/snap distance of the
  // segment (only connected, for features bent by a forced crossing).
  if (!m.domain.hasBoundary && !m.domain.hasHole) {
    const Mesh& me = mesh();
    std::vector<std::vector<std::pair<std::uint32_t, FeatureId>>> adj(me.vertexCount());
    me.forEachConstrained([&](HalfedgeId h) {
      const std::uint32_t o = me.origin(h).value, t = me.target(h).value;
      for (FeatureId f : me.edgeFeatures(h)) {
        adj[o].emplace_back(t, f);
        adj[t].emplace_back(o, f);
      }
    });
    // A crossing moved to a vertex beyond the tolerance is reported (forced);
    // it bends both features' constraints, and later crossings may split the
    // bent edges, so their segments are checked for connectivity only.
    // Crossings snapped to a vertex bend both constraints by the distance
    // moved, and a later crossing on the bent piece may snap again: a
    // feature's chain may stray by the sum of its crossings' moves.
    std::vector<std::uint8_t> bent(m.features.size(), 0);
    std::vector<double> moved(m.features.size(), 0.0);
    for (const auto& ev : m.report.intersections) {
      for (const FeatureId g : {ev.existing, ev.inserted}) {
        if (g >= bent.size()) continue;
        if (ev.forced) bent[g] = 1;
        moved[g] += ev.moved;
      }
    }
    for (std::size_t g = 0; g < m.bend.size() && g < moved.size(); ++g) moved[g] += m.bend[g];
    std::vector<std::uint8_t> visited(me.vertexCount(), 0);  // by the chain search, per segment
    std::vector<std::uint32_t> queue;
    for (const cdt::Segment& s : m.segments) {
      const VertexId ma = m.meshOf[s.a], mb = m.meshOf[s.b];
      if (ma == mb || s.feature >= m.features.size()) continue;
      const std::string name = "constraint segment " + std::to_string(s.a.value) + "-" +
                               std::to_string(s.b.value) + " (feature " +
                               std::to_string(s.feature) + ")";
      if (!ma.valid() || !mb.valid()) {
        add(name + " has an end that is not a mesh vertex");
        continue;
      }
      const std::uint32_t a = ma.value, b = mb.value;  // mesh vertices, as `adj` has them
      const Point2 P = m.xy[s.a], Q = m.xy[s.b];
      const double dx = Q.x - P.x, dy = Q.y - P.y, len2 = dx * dx + dy * dy;
      const double len = std::sqrt(len2);
      const double tol =
          std::max({2 * m.options.snapTolerance,
                    16 * cdt::ConstrainedTriangulation::constructionTolerance(P),
                    16 * cdt::ConstrainedTriangulation::constructionTolerance(Q), 1e-6 * len}) +
          moved[s.feature];
      auto near = [&](std::uint32_t v) {
        const Point2 w = me.xy(VertexId(v));
        const double along = ((w.x - P.x) * dx + (w.y - P.y) * dy) / len;
        return std::fabs((w.x - P.x) * dy - (w.y - P.y) * dx) <= tol * len && along >= -tol &&
               along <= len + tol;
      };
      // Breadth-first over the feature's edges between vertices near the
      // segment (crossings of nearly parallel lines may come out of order
      // along it, so the chain need not be monotone). `visited` is cleared
      // again for the vertices this search queued only: linear in what it
      // reached.
      queue.assign(1, a);
      visited[a] = 1;
      bool reached = false;
      for (std::size_t head = 0; head < queue.size() && !reached; ++head) {
        const std::uint32_t v = queue[head];
        for (const auto& [w, f] : adj[v]) {
          ++chainSteps;
          if (f != s.feature || visited[w]) continue;
          if (w == b) {
            reached = true;
            break;
          }
          if (!bent[s.feature] && !near(w)) continue;
          visited[w] = 1;
          queue.push_back(w);
        }
      }
      for (const std::uint32_t v : queue) visited[v] = 0;
      if (!reached) {
        add(name + " is not a chain of mesh edges carrying its feature within " + formatCoord(tol) +
            " m of it");
      }
    }
  }
  return r;
}

}  // namespace tinsmith
