// The viewer's files, served under /viewer/: the hand-written pages of
// server/viewer (index.html at /, three.html at /three, their scripts and
// styles) and the parts of the npm packages beside them that the pages load
// (CesiumJS's Build/Cesium, three's build and examples/jsm with the Draco
// decoder, 3d-tiles-renderer's build).
//
// Safety: the files are found once, at start-up, by walking a fixed list of
// folders under the root; a request is answered by looking its decoded path
// up in that table, never by joining the URL into a path. Hidden files and
// folders (a name starting with '.'), symbolic links (to files or folders)
// and files whose extension has no Content-Type here are left out.
//
// URL paths (segments joined by '/', as RequestTarget decodes them):
//   viewer/NAME                          ROOT/NAME (top-level pages, scripts, styles; no .json)
//   viewer/lib/cesium/…                  ROOT/node_modules/cesium/Build/Cesium/…
//   viewer/lib/three/build/…             ROOT/node_modules/three/build/…
//   viewer/lib/three/examples/jsm/…      ROOT/node_modules/three/examples/jsm/…
//   viewer/lib/3d-tiles-renderer/build/… ROOT/node_modules/3d-tiles-renderer/build/…
#pragma once

#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "server/app/content_cache.hpp"

namespace tinsmith::server {

/// Cache-Control of the pinned libraries (a new version comes with a new
/// install; the ETag revalidates it after a week) and of the pages.
inline constexpr const char* kLibraryCacheControl = "public, max-age=604800";
inline constexpr const char* kPageCacheControl = "no-cache";

/// Content-Type for a file name's extension ("text/javascript; charset=utf-8"
/// for .js), or null when the viewer serves no such file.
const char* viewerContentType(std::string_view fileName);

class ViewerAssets {
 public:
  struct Asset {
    std::filesystem::path file;
    const char* contentType = nullptr;
    bool compressible = false;  ///< text: gzipped when the client accepts it
    bool library = false;       ///< from node_modules: kLibraryCacheControl
  };

  /// Walks `root`. Throws usageError, naming the root, when it has no
  /// index.html (not a viewer folder).
  explicit ViewerAssets(std::filesystem::path root);

  [[nodiscard]] const std::filesystem::path& root() const { return root_; }
  /// The asset a decoded URL path names ("viewer/lib/cesium/Cesium.js"), or
  /// null when the table has none.
  [[nodiscard]] const Asset* find(std::string_view urlPath) const;
  /// The asset's bytes (and gzip form for text), read on first use and kept
  /// (the table bounds what can be kept). Null when the file cannot be read
  /// any more. Thread-safe.
  [[nodiscard]] std::shared_ptr<const Content> content(const Asset& asset) const;
  [[nodiscard]] std::size_t size() const { return table_.size(); }
  /// Whether the libraries of `/` (CesiumJS) and of `/three` (three.js,
  /// 3d-tiles-renderer) are installed.
  [[nodiscard]] bool hasCesium() const;
  [[nodiscard]] bool hasThree() const;

 private:
  std::filesystem::path root_;
  std::unordered_map<std::string, Asset> table_;
  mutable std::mutex loadedMutex_;
  mutable std::unordered_map<const Asset*, std::shared_ptr<const Content>> loaded_;
};

/// The first of `candidates` holding a usable viewer (index.html and
/// CesiumJS's Cesium.js installed beside it), or nullopt.
std::optional<std::filesystem::path> findViewerRoot(
    const std::vector<std::filesystem::path>& candidates);

}  // namespace tinsmith::server
