// `tinsmith validate`: check a TIN: topology, orientation, constraints,
// Delaunay property. Exit 0 when valid; 1 with the problems listed when not;
// 3 when the file cannot be read (missing, damaged: see ingest/tinfile).
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>

#include "core/base/error.hpp"
#include "core/mesh/validate.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/exit_codes.hpp"

namespace tinsmith::cli {

namespace {
struct ValidateOptions {
  std::string tin;
  bool json = false;
  bool noDelaunay = false;
};
}  // namespace

void addValidateCommand(CLI::App& app) {
  auto opt = std::make_shared<ValidateOptions>();
  auto* cmd = app.add_subcommand("validate", "Check a TIN: topology, orientation, constraints, Delaunay property");
  cmd->add_option("tin", opt->tin, "The .tin file")->required();
  cmd->add_flag("--json", opt->json, "Print JSON");
  cmd->add_flag("--no-delaunay", opt->noDelaunay, "Skip the Delaunay check of unconstrained edges");
  cmd->callback([opt] {
    const TinData tin = ingest::readTinFile(opt->tin);
    ValidationOptions options;
    options.checkDelaunay = !opt->noDelaunay;
    const ValidationReport report = validate(tin, options);
    if (opt->json) {
      std::string out = "{\n  \"file\": " + ingest::jsonString(opt->tin) +
                        ",\n  \"valid\": " + (report.ok ? "true" : "false") +
                        ",\n  \"vertices\": " + std::to_string(report.vertices) +
                        ",\n  \"triangles\": " + std::to_string(report.triangles) +
                        ",\n  \"edges\": " + std::to_string(report.edges) +
                        ",\n  \"boundary_edges\": " + std::to_string(report.boundaryEdges) +
                        ",\n  \"constrained_edges\": " + std::to_string(report.constrainedEdges) +
                        ",\n  \"boundary_loops\": " + std::to_string(report.boundaryLoops) +
                        ",\n  \"delaunay_checked\": " + (options.checkDelaunay ? "true" : "false") +
                        ",\n  \"problem_count\": " + std::to_string(report.problemCount) +
                        ",\n  \"problems\": [";
      for (std::size_t i = 0; i < report.problems.size(); ++i)
        out += std::string(i ? "," : "") + "\n    " + ingest::jsonString(report.problems[i]);
      out += report.problems.empty() ? "]\n}\n" : "\n  ]\n}\n";
      std::cout << out;
    } else {
      std::cout << opt->tin << ": " << (report.ok ? "valid" : "INVALID") << "\n"
                << report.summary() << (report.summary().ends_with('\n') ? "" : "\n");
    }
    if (!report.ok) {
      std::cout.flush();
      std::fflush(stdout);
      std::exit(kExitCheckFailed);  // a completed check that failed: exit 1, not an error kind
    }
  });
}

}  // namespace tinsmith::cli
