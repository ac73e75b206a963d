// Each subcommand lives in its own cmd_<name>.cpp and registers itself on the
// root CLI11 app. A command's callback does its work or throws tinsmith::Error;
// main() turns errors into messages and exit codes.
#pragma once

#include <CLI/CLI.hpp>

namespace tinsmith::cli {

void addBuildCommand(CLI::App& app);
void addTinCommand(CLI::App& app);
void addFitCommand(CLI::App& app);
void addTileCommand(CLI::App& app);
void addServeCommand(CLI::App& app);
void addInfoCommand(CLI::App& app);
void addExportCommand(CLI::App& app);
void addQueryCommand(CLI::App& app);
void addValidateCommand(CLI::App& app);
void addSlurmCommand(CLI::App& app);
void addSlurmTinCommand(CLI::App& app);

}  // namespace tinsmith::cli
