// `tinsmith fit` end to end: points in, .tin and statistics out, bad options
// rejected with usage errors. Skipped when the binary has not been built.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "tests/core/fit_test_data.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::fit {
namespace {

std::string binary() { return TINSMITH_BINARY; }

TEST(FitCli, FitsPointsAndWritesTinAndStats) {
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli");
  {
    std::ofstream out(dir / "franke.xyz");
    out.precision(17);
    for (const auto& p : testing::frankePoints(3000, 2006)) out << p.x << " " << p.y << " " << p.z << "\n";
  }
  const auto r = test::runCommand(binary() + " fit " + (dir / "franke.xyz").string() +
                                  " --tolerance 0.25% --lambda 1 --smoothing thin-plate --criterion error,count:2 -o " +
                                  (dir / "fit.tin").string() + " --stats " + (dir / "stats.json").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(std::filesystem::file_size(dir / "fit.tin") > 1000);
  const std::string stats = test::readFile(dir / "stats.json");
  EXPECT_NE(stats.find("\"levels\""), std::string::npos);
  EXPECT_NE(stats.find("\"solver\": \"gauss-seidel\""), std::string::npos);
  EXPECT_NE(r.err.find("wrote"), std::string::npos);
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(stats.find("\"stopped\": \"criterion met\""), std::string::npos);

  // Stopped by --max-level with cells still failing: a warning (also with
  // -q) and the stop reason in the statistics.
  const auto capped = test::runCommand(binary() + " fit " + (dir / "franke.xyz").string() +
                                       " --tolerance 0.25% --criterion error,count:2 --max-level 3 -q -o " +
                                       (dir / "capped.tin").string() + " --stats " + (dir / "capped.json").string());
  ASSERT_EQ(capped.exitCode, 0) << capped.err;
  EXPECT_NE(capped.err.find("warning: 64 cells of level 3 still fail"), std::string::npos) << capped.err;
  const auto cappedStats = nlohmann::json::parse(test::readFile(dir / "capped.json"));
  EXPECT_EQ(cappedStats["final"]["stopped"], "max level");
  EXPECT_EQ(cappedStats["final"]["cells_failing"], 64);

  const auto bad = test::runCommand(binary() + " fit " + (dir / "franke.xyz").string() + " --criterion error -o " +
                                    (dir / "x.tin").string());
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("--tolerance"), std::string::npos);
  const auto badSmoothing = test::runCommand(binary() + " fit " + (dir / "franke.xyz").string() +
                                             " --tolerance 1 --smoothing bumpy -o " + (dir / "x.tin").string());
  EXPECT_NE(badSmoothing.exitCode, 0);
  EXPECT_NE(badSmoothing.err.find("smoothing"), std::string::npos);
  const auto missing = test::runCommand(binary() + " fit " + (dir / "nope.xyz").string() + " --tolerance 1 -o " +
                                        (dir / "x.tin").string());
  EXPECT_NE(missing.exitCode, 0);
  EXPECT_NE(missing.err.find("nope.xyz"), std::string::npos);
}

TEST(FitCli, DomainSetsTheSquareAndQuietPrintsNothing) {
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli_domain");
  // 11 × 11 points on a plane, 10 m apart, over [100, 200] × [200, 300].
  const std::string input = "'synthetic:grid?nx=11&ny=11&spacing=10&x0=100&y0=200'";
  const std::string tin = (dir / "fit.tin").string();
  // A square larger than the data: the TIN covers all of it.
  auto r = test::runCommand(binary() + " fit " + input + " --tolerance 0.01 --domain 50,150,200 -q -o " + tin);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto info = test::runCommand(binary() + " info " + tin + " --json");
  ASSERT_EQ(info.exitCode, 0) << info.err;
  const auto extent = nlohmann::json::parse(info.out).at("extent");
  EXPECT_EQ(extent, nlohmann::json::parse("[50.0, 150.0, 250.0, 350.0]")) << info.out;
  // A square that leaves points out, and malformed values.
  r = test::runCommand(binary() + " fit " + input + " --tolerance 0.01 --domain 100,200,50 -o " + tin);
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("outside the square domain"), std::string::npos) << r.err;
  for (const char* bad : {"100,200", "100,200,0", "a,b,c", "1,2,3,4"}) {
    r = test::runCommand(binary() + " fit " + input + " --tolerance 0.01 --domain " + bad + " -o " + tin);
    EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--domain"), std::string::npos) << r.err;
  }
}

/// z of the .tin at (x, y) by `tinsmith query --json`.
double queryZ(const std::filesystem::path& tin, double x, double y) {
  const auto q = test::runCommand(binary() + " query " + tin.string() + " " + std::to_string(x) + " " +
                                  std::to_string(y) + " --json");
  EXPECT_EQ(q.exitCode, 0) << q.err;
  const auto at = q.out.find("\"z\": ");
  if (at == std::string::npos) {
    ADD_FAILURE() << q.out;
    return std::nan("");
  }
  return std::stod(q.out.substr(at + 5));
}

TEST(FitCli, WeightsColumnAndFixedPoints) {
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli_weights");
  const auto pts = testing::frankePoints(3000, 11);
  {
    // x, y, z, weight; one point far off the surface with a huge weight.
    std::ofstream out(dir / "weighted.csv");
    out.precision(17);
    out << "x,y,z,w\n";
    // Corners make the domain exactly [0, 1]², so the fixed points are grid
    // vertices (each is moved to the nearest vertex of the finest grid).
    out << "0,0," << frankeFunction(0, 0) << ",1\n1,1," << frankeFunction(1, 1) << ",1\n";
    for (const auto& p : pts) out << p.x << "," << p.y << "," << p.z << ",1\n";
    out << "0.3,0.3,5.0,1e9\n";
    std::ofstream fixed(dir / "fixed.xyz");
    fixed << "0.5 0.5 2.0\n0.25 0.75 -1.0\n";
  }
  const std::string common = " --tolerance 0.5% --criterion error,count:2 --max-level 7 -q ";
  const auto r = test::runCommand(binary() + " fit " + (dir / "weighted.csv").string() + common +
                                  "--weights-column w --fixed " + (dir / "fixed.xyz").string() + " -o " +
                                  (dir / "fit.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NEAR(queryZ(dir / "fit.tin", 0.5, 0.5), 2.0, 1e-9);
  EXPECT_NEAR(queryZ(dir / "fit.tin", 0.25, 0.75), -1.0, 1e-9);
  EXPECT_NEAR(queryZ(dir / "fit.tin", 0.3, 0.3), 5.0, 1e-3);

  // The same by column index; without the weights the heavy point is only one of many.
  const auto byIndex = test::runCommand(binary() + " fit " + (dir / "weighted.csv").string() + common +
                                        "--weights-column 3 -o " + (dir / "index.tin").string());
  ASSERT_EQ(byIndex.exitCode, 0) << byIndex.err;
  EXPECT_NEAR(queryZ(dir / "index.tin", 0.3, 0.3), 5.0, 1e-3);
  const auto plain = test::runCommand(binary() + " fit " + (dir / "weighted.csv").string() + common + "-o " +
                                      (dir / "plain.tin").string());
  ASSERT_EQ(plain.exitCode, 0) << plain.err;
  EXPECT_GT(std::abs(queryZ(dir / "plain.tin", 0.3, 0.3) - 5.0), 0.5);
  EXPECT_GT(std::abs(queryZ(dir / "plain.tin", 0.5, 0.5) - 2.0), 0.5);

  // Bad input: a weight that is not positive (file and line named), a fixed
  // point outside the domain, a column name without a header.
  {
    std::ofstream out(dir / "bad.xyz");
    for (int i = 0; i < 10; ++i) out << i * 0.1 << " " << (i % 3) * 0.3 << " 1 1\n";
    out << "0.5 0.5 1 0\n";
    std::ofstream far(dir / "far.xyz");
    far << "7 7 1\n";
  }
  const auto badWeight = test::runCommand(binary() + " fit " + (dir / "bad.xyz").string() +
                                          " --tolerance 1 --weights-column 3 -o " + (dir / "x.tin").string());
  EXPECT_EQ(badWeight.exitCode, 3) << badWeight.err;
  EXPECT_NE(badWeight.err.find("bad.xyz, line 11"), std::string::npos) << badWeight.err;
  const auto farFixed = test::runCommand(binary() + " fit " + (dir / "weighted.csv").string() + common + "--fixed " +
                                         (dir / "far.xyz").string() + " -o " + (dir / "x.tin").string());
  EXPECT_EQ(farFixed.exitCode, 3) << farFixed.err;
  EXPECT_NE(farFixed.err.find("outside"), std::string::npos) << farFixed.err;
  const auto noHeader = test::runCommand(binary() + " fit " + (dir / "bad.xyz").string() +
                                         " --tolerance 1 --weights-column w -o " + (dir / "x.tin").string());
  EXPECT_EQ(noHeader.exitCode, 2) << noHeader.err;
  EXPECT_NE(noHeader.err.find("header"), std::string::npos) << noHeader.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.tin"));
}

TEST(FitCli, OverlongWholeNumbersAreUsageErrorsNamingTheOption) {
  // Regression: --weights-column with a column index beyond int (std::stoi
  // threw std::out_of_range) came out as an internal error (exit 70), and a
  // count too large for its type was cast regardless.
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli_overlong");
  {
    std::ofstream out(dir / "points.xyz");
    for (int i = 0; i < 20; ++i)
      out << (i % 5) * 0.25 << " " << (i / 5) * 0.3 << " " << i * 0.1 << " 1\n";
  }
  const std::string fit = binary() + " fit " + (dir / "points.xyz").string() +
                          " --tolerance 1 -o " + (dir / "x.tin").string();
  const std::string column = "99999999999999999999";
  auto r = test::runCommand(fit + " --weights-column " + column);
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("--weights-column"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(column), std::string::npos) << r.err;
  r = test::runCommand(fit + " --criterion error,count:1e30");
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("--criterion count"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1e30"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.tin"));
  // In range they still work.
  r = test::runCommand(fit + " --weights-column 3 --criterion error,count:2 -q");
  EXPECT_EQ(r.exitCode, 0) << r.err;
}

TEST(FitCli, FitsTheValidCellsOfARasterAndKeepsItsCrs) {
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli_raster");
  const std::string dem = std::string(TINSMITH_SHARED_DATA) + "/red-butte/dem.tif";
  const auto r = test::runCommand(binary() + " fit " + dem + " --tolerance 5 --lambda 0.1 --criterion error -o " +
                                  (dir / "fit.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // "… level L, max error E, rms R": the error criterion holds at every DEM cell.
  const auto at = r.err.rfind("max error ");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_LE(std::stod(r.err.substr(at + 10)), 5.0) << r.err;
  const auto info = test::runCommand(binary() + " info " + (dir / "fit.tin").string());
  ASSERT_EQ(info.exitCode, 0) << info.err;
  EXPECT_NE(info.out.find("EPSG:26912"), std::string::npos) << info.out;

  const auto missing = test::runCommand(binary() + " fit " + (dir / "nope.tif").string() +
                                        " --tolerance 1 -o " + (dir / "x.tin").string());
  EXPECT_EQ(missing.exitCode, 3) << missing.err;
  EXPECT_NE(missing.err.find("nope.tif"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.tin"));
}

}  // namespace
}  // namespace tinsmith::fit
