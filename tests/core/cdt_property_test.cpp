// Property test: random points and random crossing constraints (seeded). The
// validator passes, every input point is a vertex or reported as merged, and
// every constraint is a chain of edges (Cdt::validate checks both). A few hard
// cases are exported and checked by the independent ../shared/tools/check_tin.py.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;
using testing::kSanitized;

TEST(CdtProperty, RandomPointsAndCrossingConstraints) {
  const int rounds = kSanitized ? 6 : 40;
  for (int seed = 1; seed <= rounds; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> d(0, 100);
    std::uniform_int_distribution<int> kindPick(0, 5);
    // Coordinates on a coarse lattice some rounds (many exact degeneracies).
    const bool lattice = seed % 3 == 0;
    auto coord = [&] { return lattice ? std::floor(d(rng) / 10) * 10 : d(rng); };
    Cdt cdt;
    std::vector<FeatureId> feats;
    for (int k = 0; k < 6; ++k) {
      feats.push_back(cdt.addFeature(static_cast<FeatureKind>(k), "f" + std::to_string(k)));
    }
    std::vector<Point3> pts;
    for (int i = 0; i < 200 + seed * 10; ++i) pts.push_back({coord(), coord(), d(rng)});
    cdt.insertPoints(pts);
    for (int c = 0; c < 10 + seed; ++c) {
      std::vector<Point3> line;
      const int n = 2 + c % 4;
      for (int i = 0; i < n; ++i) line.push_back({coord(), coord(), d(rng)});
      cdt.insertConstraint(line, feats[kindPick(rng)]);
    }
    cdt.finalize();
    ASSERT_TRUE(isValid(cdt)) << "seed " << seed;
  }
}

bool checkerAvailable(std::filesystem::path& script) {
  script = std::filesystem::path(TINSMITH_SHARED_DATA) / ".." / "tools" / "check_tin.py";
  return std::filesystem::exists(script) && std::system("python3 --version > /dev/null 2>&1") == 0;
}

void runChecker(const std::string& name, Cdt& cdt, const std::vector<Point3>& points,
                const std::vector<std::vector<Point3>>& lines) {
  std::filesystem::path script;
  if (!checkerAvailable(script)) GTEST_SKIP() << "check_tin.py or python3 missing";
  const auto dir = testing::scratchDir(name);
  testing::exportCase(dir, cdt.mesh(), points, lines);
  const std::string cmd = "python3 " + script.string() + " " + (dir / "mesh.obj").string() + " " +
                          (dir / "points.xyz").string() + " " +
                          (dir / "lines.geojson").string() + " > " +
                          (dir / "check.txt").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream in(dir / "check.txt");
  const std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(rc, 0) << name << ": " << out;
}

TEST(CdtIndependentCheck, CrossingStarAtUtmCoordinates) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Road, "star");
  std::vector<Point3> pts;
  for (const Point3& p : testing::randomPoints(400, 3, -50, 50)) {
    pts.push_back({500000 + p.x, 7000000 + p.y, p.z});
  }
  cdt.insertPoints(pts);
  std::vector<std::vector<Point3>> lines;
  for (int i = 0; i < 12; ++i) {
    const double a = std::numbers::pi * i / 12;
    lines.push_back({{500000 + 60 * std::cos(a), 7000000 + 60 * std::sin(a), 0},
                     {500000 - 60 * std::cos(a), 7000000 - 60 * std::sin(a), 0}});
    cdt.insertConstraint(lines.back(), f);
    for (const auto& p : lines.back()) pts.push_back(p);
  }
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  runChecker("star", cdt, pts, lines);
}

TEST(CdtIndependentCheck, GridWithConstraintThroughVerticesAndTJunctions) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Contour, "c");
  std::vector<Point3> pts;
  for (int j = 0; j < 40; ++j) {
    for (int i = 0; i < 40; ++i) pts.push_back({double(i), double(j), double(i * j % 7)});
  }
  cdt.insertPoints(pts);
  std::vector<std::vector<Point3>> lines{{{0, 0, 0}, {39, 39, 0}},
                                         {{0, 39, 0}, {26, 0, 0}},
                                         {{3.5, 10, 1}, {30.25, 10, 1}},
                                         {{10, 10, 1}, {10, 30.5, 1}}};
  for (const auto& l : lines) {
    cdt.insertConstraint(l, f);
    for (const auto& p : l) pts.push_back(p);
  }
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  runChecker("grid", cdt, pts, lines);
}

TEST(CdtIndependentCheck, RandomCrossingConstraints) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::River, "r");
  std::vector<Point3> pts = testing::randomPoints(1500, 77);
  cdt.insertPoints(pts);
  std::mt19937_64 rng(78);
  std::uniform_real_distribution<double> d(0, 1000);
  std::vector<std::vector<Point3>> lines;
  for (int i = 0; i < 40; ++i) {
    lines.push_back({{d(rng), d(rng), 0}, {d(rng), d(rng), 0}, {d(rng), d(rng), 0}});
    cdt.insertConstraint(lines.back(), f);
    for (const auto& p : lines.back()) pts.push_back(p);
  }
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  runChecker("random", cdt, pts, lines);
}

}  // namespace
}  // namespace tinsmith
