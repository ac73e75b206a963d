// Tiles on a cliff: a contoured mesa (100 m walls 2 m wide, contours every
// 10 m, a vertex every 2 m along each) tiled at 0.2 m. Wall vertices lie
// centimetres from the zoom-1 tiles' sides; a new vertex kept 1e-4 of the
// tile's width off a side (0.1 m here) could not reach them, so two zoom-1
// tiles stayed at 0.5 m and the pyramid went on to zoom 3. With the margin at
// twice Draco's largest move (2 cm), zoom 1 meets the tolerance and is the
// last. (tests/bench/tiles/cliffs.py makes the benchmark's larger mesa the
// same way.)
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

constexpr double kX0 = 500000, kY0 = 4500000, kSide = 2500;
constexpr double kCx = kX0 + kSide / 2, kCy = kY0 + kSide / 2;
constexpr double kFoot = 1000, kRim = 1100, kStep = 10, kWall = 2;

double rimRadius(double theta) {
  return 500 + 40 * std::sin(5 * theta) + 15 * std::sin(13 * theta + 1);
}

double mesaZ(double x, double y) {
  const double r = std::hypot(x - kCx, y - kCy);
  const double rim = rimRadius(std::atan2(y - kCy, x - kCx));
  if (r <= rim) return kRim + 50 * (1 - (r / rim) * (r / rim));
  if (r >= rim + kWall) return kFoot - 0.02 * (r - rim - kWall);
  return kRim - (kRim - kFoot) * (r - rim) / kWall;
}

/// A closed contour `offset` metres outside the rim, as GeoJSON coordinates.
std::string ring(double offset, double z) {
  const int n = static_cast<int>(2 * M_PI * 560 / 2);  // a vertex about 2 m apart
  std::string out = "[";
  char point[96];
  for (int i = 0; i <= n; ++i) {
    const double t = 2 * M_PI * (i % n) / n;
    const double r = rimRadius(t) + offset;
    std::snprintf(point, sizeof point, "%s[%.3f,%.3f,%.1f]", i ? "," : "", kCx + r * std::cos(t),
                  kCy + r * std::sin(t), z);
    out += point;
  }
  return out + "]";
}

TEST(TileCliffs, AMesasWallBesideATileSideIsReachedAndTheZoomMeetsItsTolerance) {
  const fs::path dir = test::scratchDir("tile-cliffs");
  {
    std::ofstream lines(dir / "contours.geojson");
    lines << R"({"type":"FeatureCollection","features":[)";
    const int levels = static_cast<int>((kRim - kFoot) / kStep);
    for (int k = 0; k <= levels + 1; ++k) {
      const bool plain = k > levels;  // the 950 m contour on the plain
      const double z = plain ? 950 : kFoot + k * kStep;
      const double offset = plain ? kWall + 500 : kWall * (1 - static_cast<double>(k) / levels);
      lines << (k ? "," : "")
            << R"({"type":"Feature","properties":{},"geometry":{"type":"LineString","coordinates":)"
            << ring(offset, z) << "}}";
    }
    lines << "]}";
    std::ofstream spots(dir / "spots.xyz");
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, kSide);
    char line[96];
    for (int i = 0; i < 300; ++i) {
      const double x = kX0 + u(rng), y = kY0 + u(rng);
      std::snprintf(line, sizeof line, "%.3f %.3f %.3f\n", x, y, mesaZ(x, y));
      spots << line;
    }
  }
  auto r = test::runTinsmith("tin --points " + (dir / "spots.xyz").string() + " --breaklines " +
                             (dir / "contours.geojson").string() + " --crs EPSG:32612 -q -o " +
                             (dir / "mesa.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = test::runTinsmith("tile " + (dir / "mesa.tin").string() + " -o " +
                        (dir / "mesa.3dtiles").string() + " --tolerance 0.2 --json -q");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  const auto& zooms = summary["zooms"];
  ASSERT_GE(zooms.size(), 2u);
  // Zoom 0 holds the walls' lines alone beyond its triangle budget; zoom 1
  // is where the tolerance is met, in every tile, and nothing goes deeper.
  EXPECT_EQ(zooms[1]["overTolerance"], 0) << zooms[1].dump();
  EXPECT_LE(zooms[1]["maxError"].get<double>(), 0.2);
  EXPECT_EQ(zooms.size(), 2u) << zooms.dump();
}

}  // namespace
}  // namespace tinsmith::ingest
