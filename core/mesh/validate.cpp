// The mesh validator (see validate.hpp).
//
// Every check is a linear pass over the mesh's arrays, in storage order: the
// triangles (orientation, and each corner's share of its vertex's star), the
// half-edges (twins, constraint flags, features, and the Delaunay test), then
// the few boundary half-edges (loops). No pass walks a vertex's star, whose
// random hops through the arrays cost more than all the rest together on a
// million-vertex TIN. The triangle and half-edge passes run in parts
// (parallelParts); the problems each part finds are merged in part order, so
// the report is the same for any thread count.
#include "core/mesh/validate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "core/base/parallel.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith {
namespace {

/// The problems one part of a pass found, the first `max` of them in text.
class Problems {
 public:
  explicit Problems(std::size_t max) : max_(max) {}
  void add(const std::string& s) {
    ++count_;
    if (listed_.size() < max_) listed_.push_back(s);
  }
  /// Appends another part's problems (the parts are merged in order).
  void add(Problems&& part) {
    count_ += part.count_;
    for (auto& s : part.listed_)
      if (listed_.size() < max_) listed_.push_back(std::move(s));
  }
  void writeTo(ValidationReport& r) && {
    r.ok = count_ == 0;
    r.problemCount = count_;
    r.problems = std::move(listed_);
  }

 private:
  std::size_t max_;
  std::size_t count_ = 0;
  std::vector<std::string> listed_;
};

/// Loops of at least this many items run in parts.
constexpr std::size_t kSerialBelow = 1 << 16;
/// Parts of a pass (fixed, so the merge order does not depend on threads).
constexpr unsigned kParts = 64;

/// Runs pass(begin, end, problems, partResult) over [0, n) in parts and
/// merges the parts' problems into `problems` and their results with
/// `combine`, both in part order.
template <class Result, class Pass, class Combine>
void inParts(std::size_t n, unsigned threads, std::size_t maxProblems, Problems& problems,
             Pass&& pass, Combine&& combine) {
  std::vector<Problems> found(kParts, Problems(maxProblems));
  std::vector<Result> results(kParts);
  parallelParts(
      n, kParts, threads,
      [&](std::size_t b, std::size_t e, unsigned part) { pass(b, e, found[part], results[part]); },
      kSerialBelow);
  for (unsigned part = 0; part < kParts; ++part) {
    problems.add(std::move(found[part]));
    combine(results[part]);
  }
}

/// Runs check(h, problems) for every half-edge h, in parts (see inParts).
template <class Check>
void checkHalfedges(const Mesh& m, unsigned threads, std::size_t maxProblems, Problems& problems,
                    Check&& check) {
  struct NoResult {};
  inParts<NoResult>(
      m.halfedgeCount(), threads, maxProblems, problems,
      [&](std::size_t b, std::size_t e, Problems& found, NoResult&) {
        for (std::size_t i = b; i < e; ++i) check(HalfedgeId(static_cast<std::uint32_t>(i)), found);
      },
      [](NoResult&) {});
}

std::string edgeName(const Mesh& m, HalfedgeId h) {
  return std::to_string(m.origin(h).value) + "-" + std::to_string(m.target(h).value);
}

/// Items (triangles, half-edges) ahead of the one being checked whose data
/// is prefetched: a triangle's vertices are anywhere in the point array, a
/// half-edge's twin anywhere in the half-edge arrays.
constexpr std::size_t kPrefetch = 16;

/// Is w in the half-plane "above" c: [0, π) measured from c (y greater, or
/// equal y and x greater)?
bool upperOf(const Point2& c, const Point2& w) {
  return w.y > c.y || (w.y == c.y && w.x > c.x);
}

/// The boundary loops: how many, and Σ of their orientations (+1 CCW, −1 CW).
struct BoundaryLoops {
  std::size_t loops = 0;
  long long orientationSum = 0;
};

BoundaryLoops traceBoundaryLoops(const Mesh& m, const std::vector<HalfedgeId>& boundary,
                                 Problems& problems) {
  BoundaryLoops result;
  const std::size_t nh = m.halfedgeCount();
  std::vector<bool> seen(nh, false);
  for (HalfedgeId start : boundary) {
    if (seen[start.value]) continue;
    ++result.loops;
    const Point2 o = m.xy(m.origin(start));
    double area = 0;
    HalfedgeId h = start;
    bool broken = false;
    bool haveMin = false;
    Point2 minV;
    int minVisits = 0;  // a loop through a pinched vertex may pass it twice
    int turn = 0;
    for (std::size_t steps = 0;; ++steps) {
      if (seen[h.value]) break;
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
      problems.add("boundary loop through half-edge " + std::to_string(start.value) +
                   " does not close");
      continue;
    }
    // At a vertex the loop passes twice (two holes touching there) the
    // local turn says nothing about the loop: take the area's sign.
    if (turn == 0 || minVisits > 1) turn = area > 0 ? 1 : -1;
    result.orientationSum += turn;
  }
  return result;
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
  const std::size_t maxProblems = options.maxProblems;
  const unsigned threads = resolveThreads(options.threads);
  Problems problems(maxProblems);
  for (const auto& p : m.buildProblems()) problems.add(p);

  const std::size_t nv = m.vertexCount(), nt = m.triangleCount(), nh = m.halfedgeCount();
  r.triangles = nt;

  for (std::size_t v = 0; v < nv; ++v) {
    const Point3& p = m.point(VertexId(static_cast<std::uint32_t>(v)));
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      problems.add("vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }

  // Orientation, triangle by triangle, and each corner's share of its
  // vertex's star: going counter-clockwise around a vertex, corner by corner,
  // each corner turns by less than π, so a closed fan of strictly CCW
  // triangles crosses from the lower half-plane around the vertex into the
  // upper one once per turn it winds. A corner "crosses" when its outgoing
  // edge points below and its incoming edge comes from above; the crossings
  // summed over a vertex's corners equal its winding number when its corners
  // form one fan, and exceed 1 when they form several (every closed fan
  // winds at least once).
  std::vector<std::uint8_t> crosses(nh);
  struct NoResult {};
  inParts<NoResult>(
      nt, threads, maxProblems, problems,
      [&](std::size_t b, std::size_t e, Problems& found, NoResult&) {
        const std::uint32_t* corners = m.cornerIndices().data();
        const Point3* points = m.points().data();
        for (std::size_t t = b; t < e; ++t) {
          // In the loop, not in a function: GCC drops calls to a function
          // that only prefetches (it counts as having no effect).
          if (t + kPrefetch < e)
            for (std::size_t k = 3 * (t + kPrefetch); k < 3 * (t + kPrefetch) + 3; ++k)
              __builtin_prefetch(points + corners[k]);
          const auto v = m.vertices(TriangleId(static_cast<std::uint32_t>(t)));
          const Point2 p[3] = {m.xy(v[0]), m.xy(v[1]), m.xy(v[2])};
          if (geometry::orient2d(p[0], p[1], p[2]) <= 0) {
            found.add("triangle " + std::to_string(t) + " (" + std::to_string(v[0].value) + ", " +
                      std::to_string(v[1].value) + ", " + std::to_string(v[2].value) +
                      ") is not strictly counter-clockwise");
          }
          for (int i = 0; i < 3; ++i)
            crosses[3 * t + i] = !upperOf(p[i], p[(i + 1) % 3]) && upperOf(p[i], p[(i + 2) % 3]);
        }
      },
      [](NoResult&) {});

  // Per vertex, one byte (a million vertices fit in a core's cache): whether
  // a triangle uses it (kUsed) and its crossings, counted up to kMostCrossings.
  // Each part owns a range of vertices and reads every corner (a sequential
  // read), so parts never write to the same byte.
  constexpr std::uint8_t kUsed = 0x80, kMostCrossings = 0x7f;
  std::vector<std::uint8_t> star(nv, 0);
  const unsigned vertexParts = std::max(1u, std::min(threads, 8u));
  parallelParts(nv, vertexParts, threads, [&](std::size_t b, std::size_t e, unsigned) {
    const std::uint32_t* corners = m.cornerIndices().data();
    for (std::size_t h = 0; h < nh; ++h) {
      const std::uint32_t v = corners[h];
      if (v < b || v >= e) continue;
      std::uint8_t& s = star[v];
      s |= kUsed;
      if (crosses[h] && (s & kMostCrossings) < kMostCrossings) ++s;
    }
  });
  std::vector<std::uint8_t>().swap(crosses);

  // Twins, constraint flags and features, half-edge by half-edge; the
  // boundary half-edges are collected for the loops. Each pair of twins is
  // checked once, from its lower half-edge h (twin t > h): twin(t) == h, the
  // same two vertices, the same features. A half-edge whose twin is lower is
  // not looked at again, so `pairs` counts what was verified: every
  // half-edge with a twin is in at most one verified pair, and twin() is an
  // involution exactly when the pairs cover them all (2 · pairs ==
  // interiorHalf). When they do not, a second pass names the culprits.
  struct HalfedgeCounts {
    std::size_t boundary = 0, interiorHalf = 0, pairs = 0;
    std::vector<HalfedgeId> boundaryHalfedges;
  };
  HalfedgeCounts counts;
  const std::uint32_t* twins = m.twinIndices().data();
  const std::uint32_t* corners = m.cornerIndices().data();
  inParts<HalfedgeCounts>(
      nh, threads, maxProblems, problems,
      [&](std::size_t b, std::size_t e, Problems& found, HalfedgeCounts& c) {
        for (std::size_t i = b; i < e; ++i) {
          if (i + kPrefetch < e) {
            const std::uint32_t ahead = twins[i + kPrefetch];
            if (ahead > i + kPrefetch && ahead < nh) {
              __builtin_prefetch(twins + ahead);
              __builtin_prefetch(corners + ahead);
            }
          }
          const HalfedgeId h(static_cast<std::uint32_t>(i));
          const HalfedgeId t = m.twin(h);
          if (!t.valid()) {
            ++c.boundary;
            c.boundaryHalfedges.push_back(h);
          } else {
            ++c.interiorHalf;
            if (t.value > i && t.value < nh && m.twin(t) == h) {
              ++c.pairs;
              if (m.origin(t) != m.target(h) || m.target(t) != m.origin(h))
                found.add("half-edge " + std::to_string(i) + " (" + edgeName(m, h) +
                          ") and its twin " + edgeName(m, t) + " do not join the same vertices");
            }
          }
        }
      },
      [&](HalfedgeCounts& c) {
        counts.boundary += c.boundary;
        counts.interiorHalf += c.interiorHalf;
        counts.pairs += c.pairs;
        counts.boundaryHalfedges.insert(counts.boundaryHalfedges.end(),
                                        c.boundaryHalfedges.begin(), c.boundaryHalfedges.end());
      });
  // Constraint flags and features, from the constrained half-edges only:
  // both sides of an edge carry the same features, each known; an edge
  // counts once (a boundary edge has one side).
  const std::size_t featureCount = m.features().size();
  std::size_t constrainedEdges = 0;
  m.forEachConstrained([&](HalfedgeId h) {
    const HalfedgeId t = m.twin(h);
    const bool twinConstrained = t.valid() && t.value < nh && m.isConstrained(t);
    if (!twinConstrained || h < t) ++constrainedEdges;
    const auto fa = m.edgeFeatures(h);
    if (t.valid() && t.value < nh && (!twinConstrained || h < t)) {
      const auto fb = m.edgeFeatures(t);
      if (!std::equal(fa.begin(), fa.end(), fb.begin(), fb.end()))
        problems.add("edge " + edgeName(m, h) + " has different constraint features on its sides");
    }
    for (std::uint32_t f : fa)
      if (f >= featureCount)
        problems.add("edge " + edgeName(m, h) + " names unknown feature " + std::to_string(f));
  });
  if (2 * counts.pairs != counts.interiorHalf) {
    checkHalfedges(m, threads, maxProblems, problems, [&](HalfedgeId h, Problems& found) {
      const HalfedgeId t = m.twin(h);
      if (t.valid() && (t.value >= nh || t == h || m.twin(t) != h))
        found.add("half-edge " + std::to_string(h.value) + " (" + edgeName(m, h) +
                  ") and its twin are not symmetric");
    });
  }
  r.boundaryEdges = counts.boundary;
  r.edges = counts.boundary + counts.interiorHalf / 2;
  r.constrainedEdges = constrainedEdges;

  // Boundary loops, their orientation, and pinched vertices.
  const BoundaryLoops loops = traceBoundaryLoops(m, counts.boundaryHalfedges, problems);
  r.boundaryLoops = loops.loops;

  // Boundary half-edges leaving and entering each boundary vertex (few: a
  // map, not vertex-sized arrays).
  std::unordered_map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> boundaryOutIn;
  for (HalfedgeId h : counts.boundaryHalfedges) {
    ++boundaryOutIn[m.origin(h).value].first;
    ++boundaryOutIn[m.target(h).value].second;
  }
  long long pinch = 0;
  std::size_t usedVertices = 0;
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (!(star[v] & kUsed)) continue;
    ++usedVertices;
    const std::uint32_t crossings = star[v] & kMostCrossings;
    const auto at = boundaryOutIn.find(v);
    const auto [out, in] = at == boundaryOutIn.end() ? std::pair<std::uint32_t, std::uint32_t>{}
                                                      : at->second;
    if (out > 1) pinch += out - 1;
    if (out != in) {
      problems.add("vertex " + std::to_string(v) + " has " + std::to_string(out) +
                   " boundary edges out but " + std::to_string(in) + " in (non-manifold)");
    } else if (out == 0 && crossings != 1) {
      // An interior vertex's star must be one fan winding exactly once.
      problems.add("the star of interior vertex " + std::to_string(v) +
                   (crossings == 0 ? " does not close around it"
                                   : " winds " + std::string(crossings == kMostCrossings ? "at least " : "") +
                                         std::to_string(crossings) +
                                         " times around it (folded triangles, or several "
                                         "fans: non-manifold)"));
    }
  }
  r.vertices = usedVertices;

  const long long euler = static_cast<long long>(usedVertices) - static_cast<long long>(r.edges) +
                          static_cast<long long>(nt);
  const long long expected = loops.orientationSum - pinch;
  if (nt > 0 && euler != expected) {
    problems.add("Euler characteristic V - E + F = " + std::to_string(euler) + ", expected " +
                 std::to_string(expected) + " from " + std::to_string(loops.loops) +
                 " boundary loops");
  }

  if (options.checkDelaunay) {
    checkHalfedges(m, threads, maxProblems, problems, [&](HalfedgeId h, Problems& found) {
      const HalfedgeId t = m.twin(h);
      if (!t.valid() || t < h || m.isConstrained(h) || m.twin(t) != h) return;
      const Point2 a = m.xy(m.origin(h)), b = m.xy(m.target(h));
      const Point2 c = m.xy(m.origin(Mesh::prev(h))), d = m.xy(m.origin(Mesh::prev(t)));
      if (geometry::incircle(a, b, c, d) > 0)
        found.add("edge " + edgeName(m, h) + " is not locally Delaunay");
    });
  }
  std::move(problems).writeTo(r);
  return r;
}

ValidationReport validate(const TinData& tin, const ValidationOptions& options) {
  return validate(Mesh::fromTinData(tin), options);
}

}  // namespace tinsmith
