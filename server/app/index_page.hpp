// The page at "/": what the server holds, with links. The viewer replaces it.
#pragma once

#include <string>

#include "server/app/tileset_catalog.hpp"

namespace tinsmith::server {

/// A small self-contained HTML page listing every tileset (id, name, CRS,
/// tiles, zooms) with links to its tileset.json and the JSON routes.
std::string indexPageHtml(const std::vector<std::shared_ptr<const Tileset>>& tilesets);

}  // namespace tinsmith::server
