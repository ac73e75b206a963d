// tinsmith — terrain TIN builder and 3D Tiles server. Entry point: parses the
// command line, runs one subcommand, maps errors to exit codes.
#include <GeographicLib/Config.h>
#include <draco/core/draco_version.h>

#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include "core/base/allocator.hpp"
#include "core/base/error.hpp"
#include "core/base/version.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/exit_codes.hpp"

namespace {

std::string versionText() {
  return std::string("tinsmith ") + tinsmith::kVersion + "\n" + "  " +
         tinsmith::ingest::gdalVersionString() + ", GeographicLib " + GEOGRAPHICLIB_VERSION_STRING +
         ", Draco " + draco::kDracoVersion;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace tinsmith;
  using namespace tinsmith::cli;
  returnLargeBlocksToSystem();
  // Past a file-size limit (ulimit -f) a write fails with EFBIG and is
  // reported, naming the file, instead of the process dying by signal.
  std::signal(SIGXFSZ, SIG_IGN);

  CLI::App app{
      "tinsmith — constrained Delaunay terrain TINs, multilevel least-squares\n"
      "level-of-detail tiles and a 3D Tiles 1.1 server.",
      "tinsmith"};
  app.set_version_flag("--version", versionText(), "Print the version and library versions");
  app.require_subcommand(1, 1);
  app.footer(
      "Exit codes: 0 ok, 1 check failed, 2 usage, 3 input, 4 geometry, 5 i/o,\n"
      "6 not implemented, 70 internal error. Run `tinsmith COMMAND --help` for a command.");

  addBuildCommand(app);
  addTinCommand(app);
  addFitCommand(app);
  addTileCommand(app);
  addSlurmCommand(app);
  addSlurmTinCommand(app);
  addServeCommand(app);
  addInfoCommand(app);
  addExportCommand(app);
  addQueryCommand(app);
  addValidateCommand(app);

  // CLI11 reads an unknown first word as a stray argument and says only that
  // "a subcommand is required"; name the word and the commands instead.
  std::string names;
  bool known = false;
  for (const auto* sub : app.get_subcommands({})) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
    known = known || (argc > 1 && sub->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::cerr << "ERROR: unknown command '" << argv[1] << "' — use one of " << names
              << " (tinsmith --help lists them)\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help, version or the parse error
    return rc == 0 ? kExitOk : kExitUsage;
  } catch (const CheckFailed&) {
    return kExitCheckFailed;
  } catch (const Error& e) {
    std::cerr << "ERROR: " << e.what() << "\n";
    return exitCodeFor(e.kind());
  } catch (const std::exception& e) {
    std::cerr << "ERROR: internal error: " << e.what()
              << " — this is a bug in tinsmith; please report it with the input that caused it\n";
    return kExitInternal;
  }
  return kExitOk;
}
