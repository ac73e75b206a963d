// `tinsmith info`: describe a .tin file (CRS, counts, extent, z range,
// features per kind). Tile stores are described once the tiler exists.
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "core/base/error.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"
#include "tools/cli/commands.hpp"

namespace tinsmith::cli {

namespace {
struct InfoOptions {
  std::string file;
  bool json = false;
};
}  // namespace

void addInfoCommand(CLI::App& app) {
  auto opt = std::make_shared<InfoOptions>();
  auto* cmd = app.add_subcommand("info", "Describe a .tin file or a tile store");
  cmd->add_option("file", opt->file, "A .tin file or a tile store")->required();
  cmd->add_flag("--json", opt->json, "Print JSON");
  cmd->callback([opt] {
    const std::filesystem::path path(opt->file);
    const std::string ext = path.extension().string();
    if (ext == ".3dtiles" || std::filesystem::is_directory(path))
      throw notImplemented("tinsmith info on a tile store (the tiler)");
    const TinData tin = ingest::readTinFile(path);
    auto summary = ingest::summariseTin(tin);
    summary.file = opt->file;
    summary.fileBytes = static_cast<std::size_t>(std::filesystem::file_size(path));
    std::cout << (opt->json ? summary.json() : summary.text());
  });
}

}  // namespace tinsmith::cli
