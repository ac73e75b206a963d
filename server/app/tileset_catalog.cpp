#include "server/app/tileset_catalog.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include "core/base/error.hpp"
#include "core/tiles/tileset_json.hpp"
#include "ingest/store/stored_tin.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "server/http/route.hpp"

namespace tinsmith::server {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kBuildKey = store::kStoreMarkerKey;

nlohmann::json parseStoredJson(const store::TileStore& s, std::string_view key) {
  const auto text = s.get(key);
  if (!text) return nlohmann::json();
  auto j = nlohmann::json::parse(*text, nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

bool isStoreDirectory(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec) && (fs::is_regular_file(p / "tileset.json", ec) ||
                                     fs::is_regular_file(p / "terrain/layer.json", ec));
}

bool isArchive(const fs::path& p) {
  std::error_code ec;
  return store::storeKindFor(p) == store::StoreKind::Archive && fs::is_regular_file(p, ec);
}

/// The length of the well-formed UTF-8 sequence at the start of `text`
/// (RFC 3629: no overlong forms, no surrogates, nothing past U+10FFFF), 0
/// when there is none.
std::size_t utf8SequenceAt(std::string_view text) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  if (byte(0) < 0x80) return 1;
  // Lead bytes, the sequence's length and the range of its second byte.
  struct Lead {
    unsigned char first, last;
    std::size_t length;
    unsigned char low, high;
  };
  static constexpr Lead kLeads[] = {{0xc2, 0xdf, 2, 0x80, 0xbf}, {0xe0, 0xe0, 3, 0xa0, 0xbf},
                                    {0xe1, 0xec, 3, 0x80, 0xbf}, {0xed, 0xed, 3, 0x80, 0x9f},
                                    {0xee, 0xef, 3, 0x80, 0xbf}, {0xf0, 0xf0, 4, 0x90, 0xbf},
                                    {0xf1, 0xf3, 4, 0x80, 0xbf}, {0xf4, 0xf4, 4, 0x80, 0x8f}};
  for (const Lead& lead : kLeads) {
    if (byte(0) < lead.first || byte(0) > lead.last) continue;
    if (text.size() < lead.length || byte(1) < lead.low || byte(1) > lead.high) return 0;
    for (std::size_t i = 2; i < lead.length; ++i)
      if (byte(i) < 0x80 || byte(i) > 0xbf) return 0;
    return lead.length;
  }
  return 0;
}

/// A file name as the list and the log show it: UTF-8 as it is, every byte
/// that is not part of well-formed UTF-8 (a name from a Latin-1 system, say)
/// written \xNN, so JSON can carry it and a reader can tell which file.
std::string displayName(std::string_view bytes) {
  std::string out;
  while (!bytes.empty()) {
    const std::size_t n = utf8SequenceAt(bytes);
    if (n > 0) {
      out.append(bytes.substr(0, n));
      bytes.remove_prefix(n);
      continue;
    }
    char hex[8];
    std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(bytes.front()));
    out += hex;
    bytes.remove_prefix(1);
  }
  return out;
}

std::string displayPath(const fs::path& p) {
  return displayName(p.native());
}

std::string idFor(const fs::path& p) {
  std::string name = p.filename().string();
  if (name.empty()) name = p.parent_path().filename().string();
  if (store::storeKindFor(p) == store::StoreKind::Archive) name = p.stem().string();
  for (char& c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
          c == '.'))
      c = '-';
  if (name.size() > 64) name.resize(64);
  if (name.empty() || name.front() == '.') name.insert(name.begin(), 't');
  return name;
}

/// What identifies a version of a store on disk: its archive file, or a
/// directory store's tileset.json (written last).
struct FileStamp {
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  std::int64_t mtimeNanos = 0;
  friend bool operator==(const FileStamp&, const FileStamp&) = default;
};

FileStamp stampOf(const fs::path& store) {
  std::error_code ec;
  const fs::path file = isArchive(store)                                  ? store
                        : fs::is_regular_file(store / "tileset.json", ec) ? store / "tileset.json"
                                                                          : store / "terrain/layer.json";
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) return {};
  return {st.st_dev, st.st_ino, st.st_size,
          static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec};
}

std::atomic<std::uint64_t> nextGeneration{1};

/// Whether a name in a served folder is where a tile job (or a store's
/// write) stages a store before it takes its own name (ingest/tiles/
/// tile_job.cpp stagingPath, ingest/store's tempSibling): "X.partial.3dtiles",
/// a folder "X.partial", or "X.tmp-<pid>-<n>" (an archive being written
/// out, a folder being moved in, an old store moved aside). None is served:
/// it is not finished, or no longer current.
bool isStagingName(std::string_view name) {
  if (name.ends_with(".partial.3dtiles") || name.ends_with(".partial")) return true;
  const std::size_t marker = name.rfind(".tmp-");
  if (marker == std::string_view::npos || marker == 0) return false;
  const std::string_view numbers = name.substr(marker + 5);
  const std::size_t dash = numbers.find('-');
  const auto digits = [](std::string_view t) {
    return !t.empty() && t.find_first_not_of("0123456789") == std::string_view::npos;
  };
  return dash != std::string_view::npos && digits(numbers.substr(0, dash)) &&
         digits(numbers.substr(dash + 1));
}

/// The stores directly in `folder`, sorted (staging names left out).
std::vector<fs::path> storesIn(const fs::path& folder) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (!isStagingName(entry.path().filename().native()) &&
        (isArchive(entry.path()) || isStoreDirectory(entry.path())))
      found.push_back(entry.path());
  std::sort(found.begin(), found.end());
  return found;
}

}  // namespace

struct TilesetCatalog::Entry {
  std::string id;
  fs::path path;
  FileStamp stamp;
  std::atomic<std::shared_ptr<const Tileset>> current;
};

Tileset::Tileset(std::string id, const fs::path& path)
    : id_(std::move(id)), generation_(nextGeneration++), store_(store::openStoreForReading(path)) {
  opened_ = store::fileIdentity(path);
  const auto tileset = parseStoredJson(*store_, "tileset.json");
  hasTerrain_ = parseStoredJson(*store_, "terrain/layer.json").is_object();
  hasTiles3D_ = tileset.is_object();
  if (!hasTiles3D_ && !hasTerrain_)
    throw inputError("has no readable tileset.json or terrain/layer.json", fileLocation(path),
                     "serve a finished store (tinsmith tile writes tileset.json last)");
  const auto build = parseStoredJson(*store_, kBuildKey);

  int minZoom = -1, maxStoredZoom = -1;
  std::size_t tiles = 0;
  for (const auto& key : store_->keys()) {
    int z = 0;
    if (!key.starts_with("tiles/") || std::sscanf(key.c_str(), "tiles/%d/", &z) != 1) continue;
    ++tiles;
    minZoom = minZoom < 0 ? z : std::min(minZoom, z);
    maxStoredZoom = std::max(maxStoredZoom, z);
  }
  // Stores are files from outside: every field is looked up, never assumed.
  const auto number = [](const nlohmann::json& j, const char* pointer) -> std::optional<double> {
    const nlohmann::json::json_pointer at(pointer);
    if (!j.is_object() || !j.contains(at) || !j.at(at).is_number()) return std::nullopt;
    return j.at(at).get<double>();
  };
  const nlohmann::json::json_pointer crsAt("/tin/crs");
  if (build.is_object() && build.contains(crsAt) && build.at(crsAt).is_string())
    crs_ = build.at(crsAt).get<std::string>();
  const nlohmann::json::json_pointer geoidAt("/options/geoid");
  if (build.is_object() && build.contains(geoidAt) && build.at(geoidAt).is_string())
    geoid_ = build.at(geoidAt).get<std::string>();
  maxZoom_ = static_cast<int>(std::clamp(number(build, "/options/maxZoom").value_or(kMaxZoom), 0.0,
                                         static_cast<double>(kMaxZoom)));

  summary_["id"] = id_;
  summary_["name"] = displayName(path.filename().native());
  summary_["crs"] = crs_;
  nlohmann::ordered_json bounds;
  const double deg = 180.0 / std::numbers::pi;
  std::array<std::optional<double>, 6> region;
  for (int i = 0; i < 6; ++i)
    region[static_cast<std::size_t>(i)] =
        number(tileset, ("/root/boundingVolume/region/" + std::to_string(i)).c_str());
  if (std::all_of(region.begin(), region.end(), [](const auto& v) { return v.has_value(); })) {
    bounds["lonlat"] = {*region[0] * deg, *region[1] * deg, *region[2] * deg, *region[3] * deg};
    summary_["heights"] = {*region[4], *region[5]};
  }
  const auto x0 = number(build, "/pyramid/origin/0"), y0 = number(build, "/pyramid/origin/1");
  const auto size = number(build, "/pyramid/size");
  if (x0 && y0 && size) bounds["project"] = {*x0, *y0, *x0 + *size, *y0 + *size};
  summary_["bounds"] = bounds;
  summary_["zooms"] = {{"min", std::max(minZoom, 0)}, {"max", std::max(maxStoredZoom, 0)},
                       {"pyramidMax", maxZoom_}};
  summary_["tileCount"] = tiles;
  if (const auto tolerance = number(build, "/options/tolerance")) summary_["tolerance"] = *tolerance;
  hasTin_ = store::holdsTin(*store_);
  summary_["elevation"] = hasTin_;
  auto& links = summary_["links"];
  if (hasTiles3D_) links["tileset"] = "/tilesets/" + id_ + "/tileset.json";
  links["elevation"] = "/tilesets/" + id_ + "/elevation";
  links["profile"] = "/tilesets/" + id_ + "/profile";
  links["lines"] = "/tilesets/" + id_ + "/lines.geojson";
  if (hasTerrain_) links["terrain"] = "/tilesets/" + id_ + "/terrain/layer.json";
}

Tileset::~Tileset() {
  // Readers first: an archive written on demand goes back to a rollback
  // journal when its writer closes last (see ingest/store/archive_store.cpp).
  store_.reset();
  writer_.reset();
}

const Surface& Tileset::surface() const {
  std::call_once(surfaceOnce_, [this] {
    const auto bytes = store::getTin(*store_);
    if (!bytes)
      throw inputError("tileset '" + id_ + "' carries no TIN, so it has no elevations", {},
                       "rebuild it with tinsmith tile, which stores the TIN");
    try {
      surface_ = std::make_unique<Surface>(
          ingest::decodeTin(*bytes, id_ + ":" + std::string(store::kTinKey)));
    } catch (const Error& e) {
      throw ioError("the TIN in tileset '" + id_ + "' cannot be read: " + e.what(), {},
                    "rebuild the store with tinsmith tile");
    }
  });
  return *surface_;
}

bool Tileset::references(const tiles::TileId& id) const {
  std::call_once(referencesOnce_, [this] {
    // Content URIs in tileset.json and the external tilesets it reaches,
    // relative to the file ("tiles/…" at the top, "../../../tiles/…" below).
    std::vector<std::string> files{"tileset.json"}, seen;
    auto uriKey = [](std::string uri) {
      while (uri.starts_with("../")) uri.erase(0, 3);
      if (uri.starts_with("./")) uri.erase(0, 2);
      return uri;
    };
    while (!files.empty() && seen.size() < 100000) {
      const std::string key = files.back();
      files.pop_back();
      seen.push_back(key);
      const auto json = parseStoredJson(*store_, key);
      std::vector<const nlohmann::json*> stack;
      if (json.is_object() && json.contains("root")) stack.push_back(&json["root"]);
      while (!stack.empty()) {
        const nlohmann::json& tile = *stack.back();
        stack.pop_back();
        if (!tile.is_object()) continue;
        const nlohmann::json::json_pointer uriAt("/content/uri");
        if (tile.contains(uriAt) && tile.at(uriAt).is_string()) {
          const std::string uri = uriKey(tile.at(uriAt).get<std::string>());
          if (uri.starts_with("tiles/")) referenced_.insert(uri);
          if (uri.starts_with("tilesets/") && store::isValidKey(uri) &&
              std::find(seen.begin(), seen.end(), uri) == seen.end())
            files.push_back(uri);
        }
        if (tile.contains("children") && tile["children"].is_array())
          for (const auto& child : tile["children"]) stack.push_back(&child);
      }
    }
  });
  return referenced_.contains(tiles::tileContentKey(id));
}

const ingest::TileRebuilder& Tileset::rebuilder() const {
  std::call_once(rebuilderOnce_, [this] {
    try {
      const auto build = store_->get(kBuildKey);
      const auto tin = store::getTin(*store_);
      if (!build || !tin) {
        rebuilderError_ = "the store has no " + std::string(build ? store::kTinKey : kBuildKey);
        return;
      }
      rebuilder_ = std::make_unique<ingest::TileRebuilder>(*build, *tin, store_->path().string());
    } catch (const std::exception& e) {
      rebuilderError_ = e.what();
    }
  });
  if (!rebuilder_)
    throw ioError("tileset '" + id_ + "' cannot build its missing tiles: " + rebuilderError_, {},
                  "rebuild the store with tinsmith tile");
  return *rebuilder_;
}

bool Tileset::keep(const std::string& key, std::string_view bytes, std::string& why) const {
  std::lock_guard lock(writerMutex_);
  // Writing was tried (writesInPlace_) and the writer is gone: it failed.
  if (writesInPlace_ && !writer_) return false;
  try {
    if (!writer_) {
      // Said before the opening, which already changes the file (an archive
      // goes to WAL mode): a refresh in between must not take it for a
      // replacement.
      writesInPlace_ = true;
      // A store replaced under its name is not this one: a tile built from
      // this one's TIN must not land in the next version.
      const auto replaced = [&] { return store::fileIdentity(store_->path()) != opened_; };
      if (!replaced()) writer_ = store::openStoreForWriting(store_->path(), true);
      if (replaced()) {
        writer_.reset();
        why = "the store was replaced on disk since it was opened";
        return false;
      }
    }
    writer_->put(key, bytes);
    return true;
  } catch (const std::exception& e) {
    // A read-only store (or disk): serve from memory, and say so once.
    writer_.reset();
    why = e.what();
    return false;
  }
}

Point2 Tileset::fromLonLat(double lon, double lat) const {
  Point3 p{lon, lat, 0};
  std::lock_guard lock(transformMutex_);
  if (!fromLonLat_)
    fromLonLat_ = std::make_unique<ingest::CrsTransform>("EPSG:4326", crs_, fileLocation(id_));
  if (fromLonLat_->transform(&p, 1) >= 0 || !std::isfinite(p.x) || !std::isfinite(p.y))
    throw inputError("lon, lat cannot be transformed into " + crs_, {}, "check lon and lat");
  return {p.x, p.y};
}

void Tileset::toGeodetic(std::span<const Point3> in, std::span<encode::Geodetic> out) const {
  const ingest::ProjGeoReference* reference = nullptr;
  {
    std::lock_guard lock(geodeticMutex_);
    if (!geodetic_) geodetic_ = std::make_unique<ingest::ProjGeoReference>(crs_, geoid_);
    reference = geodetic_.get();
  }
  reference->toGeodetic(in, out);  // thread-safe: a PROJ transformation per thread
}

TilesetCatalog::TilesetCatalog(const std::vector<fs::path>& paths) {
  std::vector<fs::path> stores;
  for (const auto& path : paths) {
    if (isArchive(path) || isStoreDirectory(path)) {
      stores.push_back(path);
      continue;
    }
    std::error_code ec;
    if (!fs::is_directory(path, ec))
      throw usageError("'" + path.string() + "' is neither a tile store nor a folder of them",
                       "give .3dtiles files, store directories or folders holding them");
    folders_.push_back(path);
    const auto found = storesIn(path);
    stores.insert(stores.end(), found.begin(), found.end());
  }
  auto entries = std::make_shared<Entries>();
  for (const auto& path : stores) {
    auto entry = makeEntry(path, *entries);
    if (!entry)
      throw usageError("two stores would be served as '" + idFor(path) + "' (" + path.string() + ")",
                       "rename one of them");
    entries->push_back(std::move(entry));
  }
  entries_ = std::move(entries);
}

std::shared_ptr<TilesetCatalog::Entry> TilesetCatalog::makeEntry(const fs::path& path,
                                                                 const Entries& existing) {
  auto entry = std::make_shared<Entry>();
  entry->id = idFor(path);
  entry->path = path;
  for (const auto& e : existing)
    if (e->id == entry->id) return nullptr;
  entry->stamp = stampOf(path);
  entry->current = std::make_shared<const Tileset>(entry->id, path);
  return entry;
}

TilesetCatalog::~TilesetCatalog() = default;

std::shared_ptr<const Tileset> TilesetCatalog::find(std::string_view id) const {
  for (const auto& e : *entries_.load())
    if (e->id == id) return e->current.load();
  return nullptr;
}

std::vector<std::shared_ptr<const Tileset>> TilesetCatalog::tilesets() const {
  std::vector<std::shared_ptr<const Tileset>> out;
  for (const auto& e : *entries_.load()) out.push_back(e->current.load());
  return out;
}

std::vector<std::string> TilesetCatalog::refresh() {
  std::vector<std::string> log;
  const auto entries = entries_.load();
  for (const auto& e : *entries) {
    const FileStamp now = stampOf(e->path);
    if (now == e->stamp || now == FileStamp{}) continue;  // unchanged, or gone for the moment
    // The server's own writes (--on-demand) into the archive it serves: the
    // same file, grown. A replacement is a new file (a new inode).
    if (now.device == e->stamp.device && now.inode == e->stamp.inode &&
        e->current.load()->writesInPlace()) {
      e->stamp = now;
      continue;
    }
    try {
      e->current = std::make_shared<const Tileset>(e->id, e->path);
      e->stamp = now;
      ++version_;
      log.push_back("reloaded " + displayPath(e->path) + " as '" + e->id + "'");
    } catch (const std::exception& ex) {
      e->stamp = now;  // not retried until it changes again
      log.push_back("kept the old '" + e->id + "': " + ex.what());
    }
  }
  // Stores new in the folders served: added under a new list, swapped in.
  auto grown = std::make_shared<Entries>(*entries);
  for (const auto& folder : folders_) {
    for (const auto& path : storesIn(folder)) {
      if (refused_.contains(path.string())) continue;
      bool known = false;
      for (const auto& e : *grown) known = known || e->path == path;
      if (known) continue;
      try {
        auto entry = makeEntry(path, *grown);
        if (!entry) {
          refused_.insert(path.string());
          log.push_back("not serving " + displayPath(path) + ": its id '" + idFor(path) +
                        "' is taken");
          continue;
        }
        log.push_back("added " + displayPath(path) + " as '" + entry->id + "'");
        grown->push_back(std::move(entry));
      } catch (const std::exception& ex) {  // half-copied, say: tried again next time
        log.push_back("cannot serve " + displayPath(path) + " yet: " + ex.what());
      }
    }
  }
  if (grown->size() != entries->size()) {
    entries_ = std::move(grown);
    ++version_;
  }
  return log;
}

}  // namespace tinsmith::server
