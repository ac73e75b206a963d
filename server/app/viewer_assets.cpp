#include "server/app/viewer_assets.hpp"

#include <array>
#include <fstream>
#include <iterator>

#include "core/base/error.hpp"

namespace tinsmith::server {

namespace fs = std::filesystem;

namespace {

struct TypeEntry {
  std::string_view extension;
  const char* contentType;
  bool text;
};

constexpr std::array<TypeEntry, 17> kTypes{{
    {".html", "text/html; charset=utf-8", true},
    {".js", "text/javascript; charset=utf-8", true},
    {".mjs", "text/javascript; charset=utf-8", true},
    {".css", "text/css; charset=utf-8", true},
    {".json", "application/json", true},
    {".svg", "image/svg+xml", true},
    {".xml", "application/xml", true},
    {".txt", "text/plain; charset=utf-8", true},
    {".wasm", "application/wasm", false},
    {".png", "image/png", false},
    {".jpg", "image/jpeg", false},
    {".jpeg", "image/jpeg", false},
    {".gif", "image/gif", false},
    {".ktx2", "image/ktx2", false},
    {".glb", "model/gltf-binary", false},
    {".woff", "font/woff", false},
    {".woff2", "font/woff2", false},
}};

const TypeEntry* typeFor(std::string_view name) {
  const std::size_t dot = name.rfind('.');
  if (dot == std::string_view::npos) return nullptr;
  const std::string_view ext = name.substr(dot);
  for (const auto& t : kTypes)
    if (t.extension == ext) return &t;
  return nullptr;
}

/// The library folders: where they sit under the root, their URL prefix.
struct Mount {
  const char* folder;
  const char* url;
};
constexpr std::array<Mount, 4> kLibraries{{
    {"node_modules/cesium/Build/Cesium", "viewer/lib/cesium"},
    {"node_modules/three/build", "viewer/lib/three/build"},
    {"node_modules/three/examples/jsm", "viewer/lib/three/examples/jsm"},
    {"node_modules/3d-tiles-renderer/build", "viewer/lib/3d-tiles-renderer/build"},
}};

bool hidden(const fs::path& p) {
  return p.filename().string().starts_with('.');
}

}  // namespace

const char* viewerContentType(std::string_view fileName) {
  const auto* t = typeFor(fileName);
  return t ? t->contentType : nullptr;
}

ViewerAssets::ViewerAssets(fs::path root) : root_(std::move(root)) {
  std::error_code ec;
  if (!fs::is_regular_file(root_ / "index.html", ec))
    throw usageError(
        "'" + root_.string() + "' is not a viewer folder (it has no index.html)",
        "give --viewer the folder server/viewer of the source tree (after tools/setup.sh) "
        "or /usr/share/tinsmith/viewer");
  const auto add = [&](const fs::path& file, std::string url, bool library) {
    const auto* type = typeFor(file.filename().string());
    if (!type) return;
    table_.emplace(std::move(url), Asset{file, type->contentType, type->text, library});
  };
  // The pages: files directly in the root only, not its npm manifests.
  for (const auto& entry : fs::directory_iterator(root_, ec))
    if (!hidden(entry.path()) && !entry.is_symlink(ec) && entry.is_regular_file(ec) &&
        entry.path().extension() != ".json")
      add(entry.path(), "viewer/" + entry.path().filename().string(), false);
  for (const auto& mount : kLibraries) {
    const fs::path folder = root_ / mount.folder;
    if (!fs::is_directory(folder, ec)) continue;
    fs::recursive_directory_iterator it(folder, fs::directory_options::none, ec), end;
    for (; !ec && it != end; it.increment(ec)) {
      if (hidden(it->path())) {
        if (it->is_directory(ec)) it.disable_recursion_pending();
        continue;
      }
      if (it->is_symlink(ec) || !it->is_regular_file(ec)) continue;
      add(it->path(),
          std::string(mount.url) + "/" + it->path().lexically_relative(folder).generic_string(),
          true);
    }
  }
}

const ViewerAssets::Asset* ViewerAssets::find(std::string_view urlPath) const {
  const auto it = table_.find(std::string(urlPath));
  return it == table_.end() ? nullptr : &it->second;
}

std::shared_ptr<const Content> ViewerAssets::content(const Asset& asset) const {
  {
    std::lock_guard lock(loadedMutex_);
    if (const auto it = loaded_.find(&asset); it != loaded_.end()) return it->second;
  }
  std::ifstream in(asset.file, std::ios::binary);
  if (!in) return nullptr;
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return nullptr;
  auto content = makeContent(std::move(bytes), asset.compressible);
  std::lock_guard lock(loadedMutex_);
  return loaded_.try_emplace(&asset, std::move(content)).first->second;  // the first one read wins
}

bool ViewerAssets::hasCesium() const {
  return find("viewer/lib/cesium/Cesium.js") != nullptr;
}

bool ViewerAssets::hasThree() const {
  return find("viewer/lib/three/build/three.module.js") != nullptr &&
         find("viewer/lib/3d-tiles-renderer/build/index.three.js") != nullptr;
}

std::optional<fs::path> findViewerRoot(const std::vector<fs::path>& candidates) {
  std::error_code ec;
  for (const auto& c : candidates)
    if (fs::is_regular_file(c / "index.html", ec) &&
        fs::is_regular_file(c / kLibraries[0].folder / "Cesium.js", ec))
      return c;
  return std::nullopt;
}

}  // namespace tinsmith::server
