// The TIN built block by block (ingest/build/block_tin.hpp) holds exactly the
// triangles one triangulation of all the points has within the circumradius:
// on random points at UTM coordinates, on cocircular grids cut by the blocks
// anywhere, with duplicates, clusters with empty blocks and gaps, and points
// arriving in many chunks from several sources. Bad input names its source
// and leaves no file behind.
#include "ingest/build/block_tin.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

using Corner = std::tuple<double, double, double>;  // x, y, z
using Triangle = std::array<Corner, 3>;

std::vector<Triangle> triangleSet(const TinData& tin) {
  std::vector<Triangle> out;
  for (const auto& t : tin.triangles) {
    Triangle c;
    for (int i = 0; i < 3; ++i) {
      const Point3& p = tin.vertices[t[i]];
      c[i] = {p.x, p.y, p.z};
    }
    std::sort(c.begin(), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// What one machine gives: every point triangulated at once (ties broken
/// alike), the triangles over the radius dropped.
TinData wholeTriangulation(const std::vector<std::vector<Point3>>& sources, double maxRadius) {
  CdtOptions options;
  options.canonicalTies = true;
  Cdt cdt(options);
  for (const auto& points : sources) cdt.insertPoints(points);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  std::erase_if(tin.triangles, [&](const TinData::Triangle& t) {
    return !(circumradius(tin.vertices[t[0]].xy(), tin.vertices[t[1]].xy(),
                          tin.vertices[t[2]].xy()) <= maxRadius);
  });
  return tin;
}

/// Sources handing out their points `chunk` at a time.
std::vector<PointSource> sourcesOf(const std::vector<std::vector<Point3>>& sets,
                                   std::size_t chunk) {
  std::vector<PointSource> out;
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const std::vector<Point3>* points = &sets[k];
    out.push_back({"points-" + std::to_string(k) + ".xyz",
                   [points, chunk](const std::function<void(std::span<const Point3>)>& sink) {
                     for (std::size_t i = 0; i < points->size(); i += chunk)
                       sink({points->data() + i, std::min(chunk, points->size() - i)});
                   }});
  }
  return out;
}

struct Case {
  std::vector<std::vector<Point3>> sources;
  double radius = 1;
  std::size_t blockPoints = 500;
  std::size_t chunk = 777;
};

/// Builds by blocks and checks against the whole triangulation; returns the report.
BlockTinReport expectSameAsWhole(const Case& c, const std::string& name) {
  const auto dir = test::scratchDir("block-tin-" + name);
  BlockTinOptions options;
  options.crs = "EPSG:32612";
  options.blockPoints = c.blockPoints;
  options.maxCircumradius = c.radius;
  const BlockTinReport report =
      buildTinByBlocks(sourcesOf(c.sources, c.chunk), dir / "t.tin", options);
  const TinData blocks = readTinFile(dir / "t.tin");  // checks the contract and the index
  const TinData whole = wholeTriangulation(c.sources, c.radius);
  EXPECT_GT(report.blocks, 4u) << name << ": the case should cut the points into blocks";
  EXPECT_EQ(blocks.crs, "EPSG:32612");
  EXPECT_EQ(blocks.vertices.size(), whole.vertices.size()) << name;
  EXPECT_EQ(report.vertices, blocks.vertices.size());
  EXPECT_EQ(report.triangles, blocks.triangles.size());
  const auto mine = triangleSet(blocks), theirs = triangleSet(whole);
  EXPECT_EQ(mine.size(), theirs.size()) << name;
  EXPECT_TRUE(mine == theirs) << name << ": the blocks' triangles differ from the whole's";
  std::set<Corner> a, b;
  for (const Point3& p : blocks.vertices) a.insert({p.x, p.y, p.z});
  for (const Point3& p : whole.vertices) b.insert({p.x, p.y, p.z});
  EXPECT_TRUE(a == b) << name << ": the vertices differ";
  // Counter-clockwise, every one.
  for (const auto& t : blocks.triangles) {
    const Point3 &p = blocks.vertices[t[0]], &q = blocks.vertices[t[1]], &r = blocks.vertices[t[2]];
    EXPECT_GT((q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x), 0);
  }
  // Nothing left next to the output.
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename(), "t.tin") << "left behind: " << entry.path();
  return report;
}

std::vector<Point3> randomPoints(std::size_t n, std::uint32_t seed, double x0, double y0,
                                 double side) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, side);
  std::vector<Point3> points;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    points.push_back({x0 + x, y0 + y, 0.01 * x + std::sin(y)});
  }
  return points;
}

std::vector<Point3> grid(int n, double x0, double y0, double step) {
  std::vector<Point3> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      points.push_back({x0 + i * step, y0 + j * step, double((i * 7 + j * 3) % 11)});
  return points;
}

TEST(BlockTin, RandomPointsAtUtmCoordinates) {
  Case c;
  c.sources = {randomPoints(20000, 1, 431000, 4512000, 2000)};
  c.radius = 60;  // the mean spacing is about 14 m
  c.blockPoints = 1000;
  const auto report = expectSameAsWhole(c, "random");
  EXPECT_GT(report.leftOut, 0u) << "the hull's slivers are over 60 m";
  // Each block holds its own points and a ring 120 m wide around its square.
  EXPECT_LT(report.largestTriangulated, 4000u);
}

TEST(BlockTin, ACocircularGridCutAnywhere) {
  // Every quad a tie; block sides fall between and on the grid's lines.
  for (const std::size_t blockPoints : {300u, 517u, 1000u}) {
    Case c;
    c.sources = {grid(120, 487000.5, 5012000.25, 0.5)};
    c.radius = 0.36;  // a grid square's circle is 0.354: the holes are the sliver-free grid
    c.blockPoints = blockPoints;
    const auto report = expectSameAsWhole(c, "grid-" + std::to_string(blockPoints));
    EXPECT_EQ(report.triangles, 2u * 119 * 119);
  }
}

TEST(BlockTin, DuplicatesKeepTheFirstHeight) {
  std::vector<Point3> points = randomPoints(6000, 2, 0, 0, 500);
  std::vector<Point3> repeats;
  for (std::size_t i = 0; i < points.size(); i += 7)
    repeats.push_back({points[i].x, points[i].y, -99});
  Case c;
  c.sources = {points, repeats};  // the second source's repeats come later
  c.radius = 40;
  const auto report = expectSameAsWhole(c, "duplicates");
  EXPECT_EQ(report.duplicates, repeats.size());
}

TEST(BlockTin, ClustersEmptyBlocksAndAGap) {
  // Three dense clusters far apart on a mostly empty square: blocks without
  // points, and the triangles across the gaps left out.
  Case c;
  c.sources = {randomPoints(3000, 3, 0, 0, 100), randomPoints(3000, 4, 900, 50, 100),
               randomPoints(2000, 5, 400, 800, 60), grid(20, 450, 450, 3)};
  c.radius = 12;
  c.chunk = 1;
  const auto report = expectSameAsWhole(c, "clusters");
  EXPECT_LT(report.blocks, report.gridBlocks);
  EXPECT_GT(report.leftOut, 0u);
}

TEST(BlockTin, ALargeRadiusReachesAcrossBlocks) {
  // A reach of several blocks: a block triangulates the points of blocks
  // beyond its neighbours.
  Case c;
  c.sources = {randomPoints(5000, 6, 200, 300, 400)};
  c.radius = 150;
  c.blockPoints = 100;
  expectSameAsWhole(c, "reach");
}

TEST(BlockTin, TheDefaultRadiusIsEightMeanSpacings) {
  Case c;
  c.sources = {randomPoints(4000, 9, 0, 0, 400)};  // 6.3 m apart on average
  c.radius = 8 * std::sqrt(400.0 * 400.0 / 4000);
  const auto dir = test::scratchDir("block-tin-default");
  BlockTinOptions options;
  options.blockPoints = 500;
  const auto report = buildTinByBlocks(sourcesOf(c.sources, 1000), dir / "t.tin", options);
  // The box is a hair inside the square the points were drawn in.
  EXPECT_NEAR(report.maxCircumradius, c.radius, 0.05);
  EXPECT_EQ(triangleSet(readTinFile(dir / "t.tin")),
            triangleSet(wholeTriangulation(c.sources, report.maxCircumradius)));
}

TEST(BlockTin, StagesRunApartGiveTheSameBytes) {
  // As a cluster runs them: the tasks in any order, one twice, one missing
  // at first (the assembly names it), then the .tin of one process.
  const auto dir = test::scratchDir("block-tin-stages");
  const std::vector<std::vector<Point3>> sets = {randomPoints(8000, 10, 431000, 4512000, 900),
                                                 grid(40, 431200, 4512200, 2)};
  BlockTinOptions options;
  options.crs = "EPSG:32612";
  options.blockPoints = 700;
  options.maxCircumradius = 30;
  buildTinByBlocks(sourcesOf(sets, 5000), dir / "one.tin", options);
  const auto work = dir / "work";
  const auto prepared = prepareBlocks(sourcesOf(sets, 333), work, options);
  const std::size_t tasks = blockTasks(work);
  EXPECT_EQ(tasks, prepared.blocks);
  ASSERT_GT(tasks, 8u);
  std::vector<std::size_t> order(tasks);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(4));
  const std::size_t missing = order.back();
  order.pop_back();
  order.push_back(order.front());
  for (const std::size_t k : order) triangulateBlock(work, k, 2);
  EXPECT_EQ(untriangulatedBlocks(work), std::vector<std::size_t>{missing});
  try {
    assembleBlocks(work, dir / "staged.tin");
    ADD_FAILURE() << "assembled without task " << missing;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("block task " + std::to_string(missing) + " of"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "staged.tin"));
  triangulateBlock(work, missing);
  const auto report = assembleBlocks(work, dir / "staged.tin");
  EXPECT_TRUE(untriangulatedBlocks(work).empty());
  EXPECT_EQ(test::readFile(dir / "staged.tin"), test::readFile(dir / "one.tin"));
  EXPECT_EQ(report.triangles, readTinFile(dir / "one.tin").triangles.size());
  EXPECT_GE(report.triangulated, report.vertices);
}

TEST(BlockTin, BadInputNamesItsSourceAndLeavesNothing) {
  const auto dir = test::scratchDir("block-tin-bad");
  BlockTinOptions options;
  options.maxCircumradius = 5;
  auto expectError = [&](const std::vector<std::vector<Point3>>& sets, const std::string& what,
                         const BlockTinOptions& o) {
    try {
      buildTinByBlocks(sourcesOf(sets, 100), dir / "bad.tin", o);
      ADD_FAILURE() << "no error for " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir)) << what << ": something was left behind";
  };
  std::vector<Point3> points = randomPoints(1000, 7, 0, 0, 100);
  points[500].z = std::nan("");
  expectError({randomPoints(10, 8, 0, 0, 1), points}, "points-1.xyz", options);
  expectError({randomPoints(10, 8, 0, 0, 1), points}, "point 501 has a non-finite", options);
  expectError({grid(30, 0, 0, 1)}, "no triangle has a circumradius within", [] {
    BlockTinOptions o;
    o.maxCircumradius = 0.5;  // under a unit square's 0.707
    return o;
  }());
  std::vector<Point3> line;
  for (int i = 0; i < 100; ++i) line.push_back({double(i), 2.0 * i, 0});
  expectError({line}, "no triangle", options);
  BlockTinOptions none = options;
  none.maxCircumradius = -1;
  expectError({grid(5, 0, 0, 1)}, "greater than 0", none);
}

}  // namespace
}  // namespace tinsmith::ingest
