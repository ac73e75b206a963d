// `tinsmith info`: describe a .tin file (CRS, counts, extent, z range,
// features per kind), or a tile store (zooms, tiles, sizes, errors, break-line
// vertices per zoom).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "core/base/error.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/tile_summary.hpp"

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
  addJsonFlag(*cmd, opt->json);
  cmd->callback([opt] {
    const std::filesystem::path path(opt->file);
    const std::string ext = path.extension().string();
    if (ext == ".3dtiles" || std::filesystem::is_directory(path)) {
      const auto info = ingest::describeTileStore(path);
      if (opt->json) {
        std::cout << tileSummaryJson(info.summary, opt->file);
      } else {
        std::cout << opt->file
                  << (info.complete ? ""
                                    : " (incomplete: no " + info.missing +
                                          "; finish it with tinsmith tile --resume)")
                  << "\n"
                  << tileSummaryText(info.summary);
      }
      return;
    }
    const TinData tin = ingest::readTinFile(path);
    auto summary = ingest::summariseTin(tin);
    summary.file = opt->file;
    summary.fileBytes = static_cast<std::size_t>(std::filesystem::file_size(path));
    summary.formatVersion = ingest::readTinFileHeader(path).version;
    std::cout << (opt->json ? summary.json() : summary.text());
  });
}

}  // namespace tinsmith::cli
