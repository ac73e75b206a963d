// The options several subcommands have — -o, --threads, -q, --crs, --json —
// declared once, so their names, checks and help read the same everywhere.
// Each returns the CLI11 option for the caller to refine (->required(), …).
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace tinsmith::cli {

/// -o/--output: the file (or store) the command writes; `what` says what it is.
template <class T>
CLI::Option* addOutputOption(CLI::App& cmd, T& output, const std::string& what) {
  return cmd.add_option("-o,--output", output, what);
}

/// --threads, 0 meaning every core (resolveThreads in core/base/parallel.hpp).
/// `what` names the threads' work, `after` (optional) follows the default.
template <class T>
CLI::Option* addThreadsOption(CLI::App& cmd, T& threads, const std::string& what, const std::string& after = {},
                              int most = 1024) {
  return cmd.add_option("--threads", threads, what + " (0: every core)" + (after.empty() ? "" : "; " + after))
      ->check(CLI::Range(0, most))
      ->capture_default_str();
}

/// -q/--quiet: `what` says what is left out.
inline CLI::Option* addQuietFlag(CLI::App& cmd, bool& quiet, const std::string& what) {
  return cmd.add_flag("-q,--quiet", quiet, what);
}

/// --json: the command's result as JSON on stdout.
inline CLI::Option* addJsonFlag(CLI::App& cmd, bool& json, const std::string& what = "Print JSON on stdout") {
  return cmd.add_flag("--json", json, what);
}

/// --crs: the CRS recorded in what is written ("EPSG:n" or WKT).
template <class T>
CLI::Option* addCrsOption(CLI::App& cmd, T& crs, const std::string& what) {
  return cmd.add_option("--crs", crs, what + " (e.g. EPSG:26912)");
}

}  // namespace tinsmith::cli
