// A memory cache of hot store content (tiles, tileset files) in front of the
// stores: least recently used out, bounded in bytes (--cache-mb), sharded by
// key hash so the io threads rarely meet on one lock. Entries are immutable
// and shared: a response holds its entry while it is written, so an eviction
// never frees bytes in flight.
#pragma once

#include <array>
#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace tinsmith::server {

/// Bytes as served: the content, its strong ETag and, for JSON, its gzip and
/// brotli forms, each with its own ETag (a different representation, RFC
/// 9110 8.8.3), compressed once when the content is made.
struct Content {
  std::shared_ptr<const std::string> bytes;
  std::string etag;
  std::shared_ptr<const std::string> gzip;  ///< null when not compressed
  std::string gzipEtag;
  std::shared_ptr<const std::string> brotli;  ///< null when not compressed
  std::string brotliEtag;
  [[nodiscard]] std::size_t footprint() const;
};

/// Content for `bytes`, gzipped and brotli-compressed too when `compressible`.
std::shared_ptr<const Content> makeContent(std::string bytes, bool compressible);
/// Content with only the compressed forms asked for (a response made once).
std::shared_ptr<const Content> makeContent(std::string bytes, bool gzip, bool brotli);

class ContentCache {
 public:
  /// capacityBytes 0 caches nothing. An entry over an eighth of a shard's
  /// share is not cached (one huge file must not flush every tile).
  explicit ContentCache(std::size_t capacityBytes);

  [[nodiscard]] std::shared_ptr<const Content> find(const std::string& key);
  void insert(const std::string& key, std::shared_ptr<const Content> content);
  [[nodiscard]] std::size_t sizeBytes() const;

 private:
  struct Shard {
    mutable std::mutex mutex;
    std::list<std::pair<std::string, std::shared_ptr<const Content>>> lru;  // front: newest
    std::unordered_map<std::string, decltype(lru)::iterator> index;
    std::size_t bytes = 0;
  };
  static constexpr std::size_t kShards = 16;
  Shard& shardFor(const std::string& key);
  std::size_t shardCapacity_;
  std::array<Shard, kShards> shards_;
};

}  // namespace tinsmith::server
