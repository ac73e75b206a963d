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

}  // namespace
}  // namespace tinsmith::fit
