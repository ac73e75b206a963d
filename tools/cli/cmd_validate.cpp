// `tinsmith validate`: check a TIN: topology, orientation, constraints,
// Delaunay property. Exit 0 when valid; 1 with the problems listed when not;
// 3 when the file cannot be read (missing, damaged: see ingest/tinfile).
#include <iostream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/mesh/validate.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/exit_codes.hpp"

namespace tinsmith::cli {

namespace {
struct ValidateOptions {
  std::string tin;
  bool json = false;
  bool noDelaunay = false;
  unsigned threads = 0;
};
}  // namespace

void addValidateCommand(CLI::App& app) {
  auto opt = std::make_shared<ValidateOptions>();
  auto* cmd = app.add_subcommand("validate", "Check a TIN: topology, orientation, constraints, Delaunay property");
  cmd->add_option("tin", opt->tin, "The .tin file")->required();
  addJsonFlag(*cmd, opt->json);
  cmd->add_flag("--no-delaunay", opt->noDelaunay, "Skip the Delaunay check of unconstrained edges");
  addThreadsOption(*cmd, opt->threads, "Threads for the checks", "the same report for any count");
  cmd->callback([opt] {
    const TinData tin = ingest::readTinFile(opt->tin);
    ValidationOptions options;
    options.checkDelaunay = !opt->noDelaunay;
    options.threads = opt->threads;
    const ValidationReport report = validate(tin, options);
    if (opt->json) {
      const nlohmann::ordered_json out = {
          {"file", opt->tin},
          {"valid", report.ok},
          {"vertices", report.vertices},
          {"triangles", report.triangles},
          {"edges", report.edges},
          {"boundary_edges", report.boundaryEdges},
          {"constrained_edges", report.constrainedEdges},
          {"boundary_loops", report.boundaryLoops},
          {"delaunay_checked", options.checkDelaunay},
          {"problem_count", report.problemCount},
          {"problems", report.problems},
      };
      std::cout << out.dump(2) << "\n";
    } else {
      std::cout << opt->tin << ": " << (report.ok ? "valid" : "INVALID") << "\n"
                << report.summary() << (report.summary().ends_with('\n') ? "" : "\n");
    }
    if (!report.ok) throw CheckFailed{};
  });
}

}  // namespace tinsmith::cli
