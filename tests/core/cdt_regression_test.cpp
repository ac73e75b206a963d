// Regressions of constraint insertion: constraints through input vertices
// that another constraint already passes through, crossings at existing
// vertices, and near-duplicate vertices from rounded crossing points. Each test
// checks the Cdt's own validation and, independently of the CDT's edge flags,
// that every input segment is a chain of mesh edges carrying its feature and
// running along the input segment, and that no two vertices are nearly equal.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;

struct InputSegment {
  Point3 a, b;
  FeatureId feature;
};

// Mesh vertex at exactly p, or an invalid id.
VertexId vertexAt(const Mesh& mesh, const Point2& p) {
  for (std::uint32_t v = 0; v < mesh.vertexCount(); ++v) {
    if (mesh.xy(VertexId(v)) == p) return VertexId(v);
  }
  return {};
}

// Is every input segment a path of mesh edges carrying its feature, from the
// vertex at one end to the vertex at the other, through vertices within `tol`
// metres of the segment? Computed from the mesh and the input only.
::testing::AssertionResult segmentsAreChains(const Mesh& mesh,
                                             const std::vector<InputSegment>& segments,
                                             double tol = 1e-6) {
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> adj(mesh.vertexCount());
  for (std::uint32_t h = 0; h < mesh.halfedgeCount(); ++h) {
    const std::uint32_t o = mesh.origin(HalfedgeId(h)).value;
    const std::uint32_t t = mesh.target(HalfedgeId(h)).value;
    for (std::uint32_t f : mesh.edgeFeatures(HalfedgeId(h))) {
      adj[o].emplace_back(t, f);
      adj[t].emplace_back(o, f);
    }
  }
  std::size_t bad = 0;
  std::string first;
  for (const InputSegment& s : segments) {
    const VertexId a = vertexAt(mesh, s.a.xy()), b = vertexAt(mesh, s.b.xy());
    const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y, len = std::hypot(dx, dy);
    auto nearSegment = [&](std::uint32_t v) {
      const Point2 p = mesh.xy(VertexId(v));
      const double along = ((p.x - s.a.x) * dx + (p.y - s.a.y) * dy) / len;
      const double off = std::fabs((p.x - s.a.x) * dy - (p.y - s.a.y) * dx) / len;
      return off <= tol && along >= -tol && along <= len + tol;
    };
    bool reached = false;
    if (a.valid() && b.valid()) {
      std::vector<std::uint8_t> seen(mesh.vertexCount(), 0);
      std::vector<std::uint32_t> todo{a.value};
      seen[a.value] = 1;
      while (!todo.empty() && !reached) {
        const std::uint32_t v = todo.back();
        todo.pop_back();
        for (const auto& [w, f] : adj[v]) {
          if (f != s.feature || seen[w] || !nearSegment(w)) continue;
          if (w == b.value) reached = true;
          seen[w] = 1;
          todo.push_back(w);
        }
      }
    }
    if (!reached) {
      if (bad++ == 0) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "(%.17g, %.17g)-(%.17g, %.17g) feature %u", s.a.x, s.a.y,
                      s.b.x, s.b.y, s.feature);
        first = buf;
      }
    }
  }
  if (bad == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << bad << " of " << segments.size()
                                       << " input segments are not chains of mesh edges carrying "
                                          "their feature, first "
                                       << first;
}

// No two mesh vertices closer than minDistance (metres).
::testing::AssertionResult noNearDuplicateVertices(const Mesh& mesh, double minDistance = 1e-6) {
  std::vector<Point2> pts;
  for (const Point3& p : mesh.points()) pts.push_back(p.xy());
  std::sort(pts.begin(), pts.end(), [](const Point2& l, const Point2& r) { return l.x < r.x; });
  std::size_t close = 0;
  std::string first;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    for (std::size_t j = i + 1; j < pts.size() && pts[j].x - pts[i].x < minDistance; ++j) {
      if (std::hypot(pts[j].x - pts[i].x, pts[j].y - pts[i].y) < minDistance && close++ == 0) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "(%.17g, %.17g) and (%.17g, %.17g)", pts[i].x, pts[i].y,
                      pts[j].x, pts[j].y);
        first = buf;
      }
    }
  }
  if (close == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << close << " vertex pairs closer than " << minDistance << " m, first " << first;
}

// An 11 × 11 lattice, 10 m apart, offset by (ox, oy).
std::vector<Point3> lattice(double ox, double oy) {
  std::vector<Point3> pts;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j) pts.push_back({ox + 10.0 * i, oy + 10.0 * j, 100.0});
  }
  return pts;
}

void insertSegments(Cdt& cdt, const std::vector<InputSegment>& segments) {
  for (const InputSegment& s : segments) {
    const std::vector<Point3> line{s.a, s.b};
    cdt.insertConstraint(line, s.feature);
  }
}

// Three break lines A: (40,60)-(70,60), B: (60,40)-(40,100), C: (60,80)-(40,60).
// B crosses A at (53.3…, 60), a rounded point; B and C both pass exactly
// through node (50, 70); C ends at A's start. B's rest after the rounded
// crossing must still run through (50, 70), and C's piece (50,70)-(40,60)
// must be an edge.
void checkThreeSegmentLattice(double ox, double oy) {
  Cdt cdt;
  cdt.insertPoints(lattice(ox, oy));
  std::vector<InputSegment> segs;
  const double coords[3][4] = {
      {40.000000000000000, 60.000000000000000, 70.000000000000000, 60.000000000000000},
      {60.000000000000000, 40.000000000000000, 40.000000000000000, 100.00000000000000},
      {60.000000000000000, 80.000000000000000, 40.000000000000000, 60.000000000000000}};
  for (const auto& c : coords) {
    const FeatureId f = cdt.addFeature(FeatureKind::Other, "break line");
    segs.push_back({{ox + c[0], oy + c[1], 100.01000000000000},
                    {ox + c[2], oy + c[3], 100.01100000000000},
                    f});
  }
  insertSegments(cdt, segs);
  cdt.finalize();
  const Mesh& mesh = cdt.mesh();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_TRUE(segmentsAreChains(mesh, segs));
  EXPECT_TRUE(noNearDuplicateVertices(mesh));
  // The one proper crossing (A × B) is the only new vertex.
  EXPECT_EQ(mesh.vertexCount(), 122u);
  // The piece of C from the shared node to A's start is an edge carrying C only.
  const VertexId node = vertexAt(mesh, {ox + 50.000000000000000, oy + 70.000000000000000});
  const VertexId end = vertexAt(mesh, {ox + 40.000000000000000, oy + 60.000000000000000});
  ASSERT_TRUE(node.valid() && end.valid());
  bool found = false;
  mesh.forEachOutgoing(node, [&](HalfedgeId h) {
    if (mesh.target(h) != end) return;
    found = true;
    const auto fs = mesh.edgeFeatures(h);
    EXPECT_EQ(std::vector<std::uint32_t>(fs.begin(), fs.end()),
              std::vector<std::uint32_t>{segs[2].feature});
  });
  EXPECT_TRUE(found);
  EXPECT_EQ(cdt.report().intersections.size(), 1u);
}

TEST(CdtConstraintRegression, ConstraintThroughNodeAfterRoundedCrossingIsChained) {
  checkThreeSegmentLattice(0.0, 0.0);
}

TEST(CdtConstraintRegression, ConstraintThroughNodeAfterRoundedCrossingIsChainedAtUtm) {
  checkThreeSegmentLattice(500000.00000000000, 7000000.0000000000);
}

// 2000 random points plus the lattice at a UTM offset, and random segments
// between lattice nodes: many pass exactly through nodes, many cross at rounded
// points, several meet at the same non-representable point.
TEST(CdtConstraintRegression, RandomLatticeSegmentsAreAllChained) {
  const double ox = 500000.00000000000, oy = 7000000.0000000000;
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::vector<Point3> pts;
  for (int i = 0; i < 2000; ++i) pts.push_back({ox + u(rng), oy + u(rng), 100.0});
  const std::vector<Point3> nodes = lattice(ox, oy);
  pts.insert(pts.end(), nodes.begin(), nodes.end());
  Cdt cdt;
  cdt.insertPoints(pts);
  const FeatureId f = cdt.addFeature(FeatureKind::Other, "break lines");
  const int count = testing::kSanitized ? 150 : 500;
  std::uniform_int_distribution<std::size_t> pick(0, nodes.size() - 1);
  std::vector<InputSegment> segs;
  while (segs.size() < static_cast<std::size_t>(count)) {
    const std::size_t a = pick(rng), b = pick(rng);
    if (a == b) continue;
    segs.push_back({nodes[a], nodes[b], f});
  }
  insertSegments(cdt, segs);
  cdt.finalize();
  const Mesh& mesh = cdt.mesh();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_TRUE(segmentsAreChains(mesh, segs));
  EXPECT_TRUE(noNearDuplicateVertices(mesh));
}

// Break lines through one input node (and others meeting elsewhere): the
// crossing of two lines at an existing vertex is that vertex, never a
// constructed point next to it.
void checkLinesThroughNode(const std::vector<std::array<double, 4>>& lines) {
  const double ox = 500000.00000000000, oy = 7000000.0000000000;
  Cdt cdt;
  cdt.insertPoints(lattice(ox, oy));
  std::vector<InputSegment> segs;
  for (const auto& l : lines) {
    const FeatureId f = cdt.addFeature(FeatureKind::Other, "break line");
    segs.push_back({{ox + l[0], oy + l[1], 100.0}, {ox + l[2], oy + l[3], 100.0}, f});
  }
  insertSegments(cdt, segs);
  cdt.finalize();
  const Mesh& mesh = cdt.mesh();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_TRUE(segmentsAreChains(mesh, segs));
  EXPECT_TRUE(noNearDuplicateVertices(mesh));
}

TEST(CdtConstraintRegression, ThreeLinesThroughAnInputPointMakeNoNearDuplicateVertices) {
  // All three pass through node (50, 50).
  checkLinesThroughNode(
      {{30.000000000000000, 0.0000000000000000, 70.000000000000000, 100.00000000000000},
       {0.0000000000000000, 50.000000000000000, 100.00000000000000, 50.000000000000000},
       {10.000000000000000, 30.000000000000000, 90.000000000000000, 70.000000000000000}});
}

TEST(CdtConstraintRegression, FiveLinesThroughAnInputPointMakeNoNearDuplicateVertices) {
  checkLinesThroughNode(
      {{80.000000000000000, 10.000000000000000, 0.0000000000000000, 80.000000000000000},
       {70.000000000000000, 0.0000000000000000, 90.000000000000000, 20.000000000000000},
       {30.000000000000000, 0.0000000000000000, 70.000000000000000, 100.00000000000000},
       {0.0000000000000000, 50.000000000000000, 100.00000000000000, 50.000000000000000},
       {10.000000000000000, 30.000000000000000, 90.000000000000000, 70.000000000000000}});
}

// A constrained edge R–L with a vertex one ulp from L, so the triangle beside
// the edge on that side is a sliver; a second break line crosses the edge near
// R. The rounded crossing falls on the wrong side of the sliver's long edge and
// cannot split R–L into four triangles; it once went to the nearest vertex,
// 1.1 m away. Moved a few ulps back across R–L it lies in the triangle on the
// other side, so it goes in there and R–L's constraint runs through it: a new
// vertex on both lines.
TEST(CdtConstraintRegression, CrossingBesideASliverStaysOnBothLines) {
  using namespace testing::crossing_beside_a_sliver;
  Cdt cdt;
  cdt.insertPoints(points());
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  const std::vector<InputSegment> segs{{R, L, road}, {A, B, river}};
  insertSegments(cdt, segs);
  cdt.finalize();
  const Mesh& mesh = cdt.mesh();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_TRUE(segmentsAreChains(mesh, segs, 1e-8));
  EXPECT_EQ(mesh.vertexCount(), 10u);  // seven points, A, B and the crossing
  ASSERT_EQ(cdt.report().intersections.size(), 1u);
  const CdtReport::Intersection& x = cdt.report().intersections[0];
  EXPECT_FALSE(x.forced);
  EXPECT_EQ(x.moved, 0.0);
  // Both features pass through the crossing vertex.
  const VertexId v = vertexAt(mesh, x.at.xy());
  ASSERT_TRUE(v.valid());
  int roadEdges = 0, riverEdges = 0;
  mesh.forEachOutgoing(v, [&](HalfedgeId h) {
    for (FeatureId f : mesh.edgeFeatures(h)) {
      roadEdges += f == road;
      riverEdges += f == river;
    }
  });
  EXPECT_EQ(roadEdges, 2);
  EXPECT_EQ(riverEdges, 2);
}

// Found by the fuzzer: a closed, self-crossing break line at UTM coordinates,
// one vertex an ulp off a lattice value. Rounded crossings fall just outside
// slivers beside the crossed edges; each goes into the triangle on the edge's
// other side (as computed, or moved a few ulps across the edge), and no
// crossing is moved to a vertex.
TEST(CdtConstraintRegression, SelfCrossingRingWithAnUlpOffVertexKeepsEveryCrossing) {
  const std::vector<Point3> ring{{6999998.9000000004, 6999998.9000000004, 0},
                                 {6999998.5, 6999998.4000000004, 27},
                                 {6999998.5000000009, 7000001.5, 49},
                                 {6999998.5, 6999998.5, 58},
                                 {6999998.4000000004, 6999999.5, 53},
                                 {6999999, 7000001.7999999998, 0},
                                 {6999998, 6999998, 0}};
  for (const std::size_t split : {std::size_t{6}, std::size_t{50000}}) {
    CdtOptions options;
    options.splitMinPoints = split;
    Cdt cdt(options);
    const FeatureId f = cdt.addFeature(FeatureKind::Contour, "ring");
    cdt.insertConstraint(ring, f, true);
    cdt.finalize();
    std::vector<InputSegment> segs;
    for (std::size_t i = 0; i < ring.size(); ++i) {
      segs.push_back({ring[i], ring[(i + 1) % ring.size()], f});
    }
    EXPECT_TRUE(isValid(cdt));
    EXPECT_TRUE(segmentsAreChains(cdt.mesh(), segs));
    for (const CdtReport::Intersection& x : cdt.report().intersections) {
      EXPECT_FALSE(x.forced) << "moved " << x.moved;
    }
  }
}

}  // namespace
}  // namespace tinsmith
