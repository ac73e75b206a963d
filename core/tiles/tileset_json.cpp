#include "core/tiles/tileset_json.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/base/error.hpp"
#include "core/tiles/lon_range.hpp"

namespace tinsmith::tiles {

namespace {

using Json = nlohmann::ordered_json;

struct Node {
  TileRecord record;
  std::vector<TileId> children;
  double declaredError = 0;
};

std::string externalKey(const TileId& id) {
  return "tilesets/" + std::to_string(id.z) + "/" + std::to_string(id.x) + "/" +
         std::to_string(id.y) + ".json";
}

Json boundingVolume(const TileRecord& r) {
  Json v;
  if (r.local) {
    v["box"] = r.box;
  } else {
    v["region"] = r.region;
  }
  return v;
}

/// Grows a's volume to contain b's (regions: min/max; boxes: axis-aligned).
void grow(TileRecord& a, const TileRecord& b) {
  if (a.local) {
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min(a.box[k] - a.box[3 + 4 * k], b.box[k] - b.box[3 + 4 * k]);
      const double hi = std::max(a.box[k] + a.box[3 + 4 * k], b.box[k] + b.box[3 + 4 * k]);
      a.box[k] = 0.5 * (lo + hi);
      a.box[3 + 4 * k] = 0.5 * (hi - lo);
    }
    return;
  }
  const LonRange lon = lonUnion({a.region[0], a.region[2]}, {b.region[0], b.region[2]});
  a.region[0] = lon.west;
  a.region[1] = std::min(a.region[1], b.region[1]);
  a.region[2] = lon.east;
  a.region[3] = std::max(a.region[3], b.region[3]);
  a.region[4] = std::min(a.region[4], b.region[4]);
  a.region[5] = std::max(a.region[5], b.region[5]);
}

}  // namespace

std::string tileContentKey(const TileId& id) {
  return "tiles/" + std::to_string(id.z) + "/" + std::to_string(id.x) + "/" + std::to_string(id.y) +
         ".glb";
}

std::vector<std::pair<std::string, std::string>> tilesetFiles(std::span<const TileRecord> records,
                                                              const TilesetOptions& options) {
  if (records.empty()) throw internalError("tilesetFiles: no tiles");
  std::map<TileId, Node> nodes;
  for (const auto& r : records) nodes[r.id].record = r;
  const TileId root = nodes.begin()->first;  // the lowest zoom comes first
  for (auto& [id, node] : nodes) {
    if (id == root) continue;
    if (id.z <= root.z)
      throw internalError("tilesetFiles: two roots, " + root.name() + " and " + id.name());
    auto parent = nodes.find(id.parent());
    if (parent == nodes.end())
      throw internalError("tilesetFiles: tile " + id.name() + " has no parent");
    parent->second.children.push_back(id);
  }
  // Bottom-up: declared errors and volumes (the deepest zoom first).
  std::vector<TileId> order;
  for (const auto& [id, node] : nodes) order.push_back(id);
  std::stable_sort(order.begin(), order.end(),
                   [](const TileId& a, const TileId& b) { return a.z > b.z; });
  for (const TileId& id : order) {
    Node& node = nodes[id];
    node.declaredError = std::max(node.declaredError, node.record.error);
    if (id == root) continue;
    Node& parent = nodes[id.parent()];
    parent.declaredError = std::max(parent.declaredError, node.declaredError);
    grow(parent.record, node.record);
  }

  const bool split = nodes.size() > options.maxTilesPerFile && options.externalEvery > 0;
  std::vector<std::pair<std::string, std::string>> files;
  // Builds the JSON of `id`'s subtree; `prefix` leads from the file back to the root folder.
  std::function<Json(const TileId&, const std::string&, bool)> tileJson =
      [&](const TileId& id, const std::string& prefix, bool fileRoot) -> Json {
    const Node& node = nodes[id];
    Json t;
    t["boundingVolume"] = boundingVolume(node.record);
    t["geometricError"] = node.declaredError;
    if (fileRoot) t["refine"] = "REPLACE";
    t["content"] = {{"uri", prefix + tileContentKey(id)}};
    if (!node.children.empty()) {
      Json children = Json::array();
      for (const TileId& c : node.children) {
        if (split && c.z % options.externalEvery == 0) {
          const std::string key = externalKey(c);
          Json file;
          file["asset"] = {{"version", "1.1"}, {"generator", options.generator}};
          file["geometricError"] = nodes[c].declaredError;
          file["root"] = tileJson(c, "../../../", true);
          files.push_back({key, file.dump()});
          Json ref;
          ref["boundingVolume"] = boundingVolume(nodes[c].record);
          ref["geometricError"] = nodes[c].declaredError;
          ref["content"] = {{"uri", prefix + key}};
          children.push_back(ref);
        } else {
          children.push_back(tileJson(c, prefix, false));
        }
      }
      t["children"] = children;
    }
    return t;
  };
  Json tileset;
  tileset["asset"] = {{"version", "1.1"}, {"generator", options.generator}};
  // Not drawing the terrain at all is off by the terrain itself: at least its
  // extent's diagonal, so a viewer that sees the whole extent draws the root
  // (twice the root's error alone can project below a viewer's threshold from
  // the distance that frames the extent, and nothing would be drawn).
  const TileRecord& top = nodes[root].record;
  double diagonal = 0.0;
  if (top.local) {
    // The box's corner: centre + x half-axis + y half-axis.
    diagonal = 2.0 * std::hypot(top.box[3] + top.box[6], top.box[4] + top.box[7],
                                top.box[5] + top.box[8]);
  } else {
    constexpr double kEarthRadius = 6371000.0;
    const double south = top.region[1], north = top.region[3];
    const LonRange lon{top.region[0], top.region[2]};
    const double halfPi = 0.5 * std::numbers::pi;
    if (isEveryLongitude(lon) && (north >= halfPi || south <= -halfPi)) {
      // A cap around a pole: its diameter.
      diagonal = 2.0 * (north >= halfPi ? halfPi - south : north + halfPi) * kEarthRadius;
    } else {
      const double width = lonSpan(lon) * kEarthRadius * std::cos(0.5 * (south + north));
      diagonal = std::hypot(width, (north - south) * kEarthRadius);
    }
  }
  tileset["geometricError"] = std::max(2.0 * nodes[root].declaredError, diagonal);
  tileset["root"] = tileJson(root, "", true);
  if (!options.extras.empty()) {
    const auto extras = Json::parse(options.extras, nullptr, false);
    if (!extras.is_discarded()) tileset["extras"] = extras;
  }
  files.push_back({"tileset.json", tileset.dump()});
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace tinsmith::tiles
