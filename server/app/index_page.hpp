// The page at "/" when the viewer's assets are not installed: what the server
// holds, with links, and what to install for the viewer.
#pragma once

#include <string>

#include "server/app/tileset_catalog.hpp"

namespace tinsmith::server {

/// A small self-contained HTML page listing every tileset (id, name, CRS,
/// tiles, zooms) with links to its tileset.json and the JSON routes, under
/// `basePath` ("" or "/prefix"); `notice`, when not empty, is a paragraph
/// (plain text) above the list.
std::string indexPageHtml(const std::vector<std::shared_ptr<const Tileset>>& tilesets,
                          const std::string& basePath = "", const std::string& notice = "");

}  // namespace tinsmith::server
