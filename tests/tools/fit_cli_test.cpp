// `tinsmith fit` end to end: points in, .tin and statistics out, bad options
// rejected with usage errors. Skipped when the binary has not been built.
#include <gtest/gtest.h>

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


TEST(FitCli, FitsTheValidCellsOfARasterAndKeepsItsCrs) {
  if (!std::filesystem::exists(binary())) GTEST_SKIP() << "tinsmith binary not built";
  const auto dir = test::scratchDir("fit_cli_raster");
  const std::string dem = std::string(TINSMITH_SHARED_DATA) + "/red-butte/dem.tif";
  const auto r = test::runCommand(binary() + " fit " + dem + " --tolerance 5 --lambda 0.1 --criterion error -q -o " +
                                  (dir / "fit.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // "… level L, max error E, rms R": the error criterion holds at every DEM cell.
  const auto at = r.err.find("max error ");
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
