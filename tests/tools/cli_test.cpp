// Drives the real `tinsmith` binary: arguments, help, version and exit codes.
#include <gtest/gtest.h>

#include "core/base/version.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith {
namespace {

using test::runTinsmith;

TEST(Cli, VersionNamesTinsmithAndItsLibraries) {
  const auto r = runTinsmith("--version");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out.rfind(std::string("tinsmith ") + kVersion, 0), 0u) << r.out;
  EXPECT_NE(r.out.find("GDAL 3."), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("GeographicLib 2."), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Draco 1."), std::string::npos) << r.out;
}

TEST(Cli, HelpListsEverySubcommandAndTheExitCodes) {
  const auto r = runTinsmith("--help");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  for (const char* sub : {"build", "tin", "fit", "tile", "serve", "info", "export", "query", "validate"})
    EXPECT_NE(r.out.find(sub), std::string::npos) << "missing subcommand " << sub;
  EXPECT_NE(r.out.find("Exit codes"), std::string::npos);
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"build", "tin", "fit", "tile", "serve", "info", "export", "query", "validate"}) {
    const auto r = runTinsmith(std::string(sub) + " --help");
    EXPECT_EQ(r.exitCode, 0) << sub << ": " << r.err;
    EXPECT_NE(r.out.find(std::string("tinsmith ") + sub), std::string::npos) << r.out;
  }
}

TEST(Cli, NoSubcommandIsAUsageError) {
  const auto r = runTinsmith("");
  EXPECT_EQ(r.exitCode, 2);
}

TEST(Cli, UnknownSubcommandOrOptionIsAUsageError) {
  const auto unknown = runTinsmith("frobnicate");
  EXPECT_EQ(unknown.exitCode, 2);
  EXPECT_NE(unknown.err.find("unknown command 'frobnicate'"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("tin, fit"), std::string::npos) << unknown.err;
  EXPECT_EQ(runTinsmith("--no-such-flag").exitCode, 2);
}

TEST(Cli, MissingRequiredArgumentIsAUsageErrorThatNamesIt) {
  const auto r = runTinsmith("tile");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("tin"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace tinsmith
