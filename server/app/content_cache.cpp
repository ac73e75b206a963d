#include "server/app/content_cache.hpp"

#include <functional>

#include "server/http/representation.hpp"

namespace tinsmith::server {

std::size_t Content::footprint() const {
  return sizeof(Content) + (bytes ? bytes->size() : 0) + (gzip ? gzip->size() : 0) +
         (brotli ? brotli->size() : 0) + etag.size() + gzipEtag.size() + brotliEtag.size();
}

std::shared_ptr<const Content> makeContent(std::string bytes, bool compressible) {
  return makeContent(std::move(bytes), compressible, compressible);
}

std::shared_ptr<const Content> makeContent(std::string bytes, bool gzip, bool brotli) {
  auto c = std::make_shared<Content>();
  c->etag = strongEtag(bytes);
  if (gzip) {
    c->gzip = std::make_shared<const std::string>(gzipCompress(bytes));
    c->gzipEtag = c->etag.substr(0, c->etag.size() - 1) + "-gz\"";
  }
  if (brotli) {
    c->brotli = std::make_shared<const std::string>(brotliCompress(bytes));
    c->brotliEtag = c->etag.substr(0, c->etag.size() - 1) + "-br\"";
  }
  c->bytes = std::make_shared<const std::string>(std::move(bytes));
  return c;
}

ContentCache::ContentCache(std::size_t capacityBytes) : shardCapacity_(capacityBytes / kShards) {}

ContentCache::Shard& ContentCache::shardFor(const std::string& key) {
  return shards_[std::hash<std::string>{}(key) % kShards];
}

std::shared_ptr<const Content> ContentCache::find(const std::string& key) {
  if (shardCapacity_ == 0) return nullptr;
  Shard& s = shardFor(key);
  std::lock_guard lock(s.mutex);
  const auto it = s.index.find(key);
  if (it == s.index.end()) return nullptr;
  s.lru.splice(s.lru.begin(), s.lru, it->second);
  return it->second->second;
}

void ContentCache::insert(const std::string& key, std::shared_ptr<const Content> content) {
  const std::size_t size = content->footprint() + key.size();
  if (size > shardCapacity_ / 8) return;
  Shard& s = shardFor(key);
  std::lock_guard lock(s.mutex);
  if (s.index.contains(key)) return;  // another thread read it first
  s.lru.emplace_front(key, std::move(content));
  s.index.emplace(key, s.lru.begin());
  s.bytes += size;
  while (s.bytes > shardCapacity_) {
    auto& [oldKey, old] = s.lru.back();
    s.bytes -= old->footprint() + oldKey.size();
    s.index.erase(oldKey);
    s.lru.pop_back();
  }
}

std::size_t ContentCache::sizeBytes() const {
  std::size_t total = 0;
  for (const auto& s : shards_) {
    std::lock_guard lock(s.mutex);
    total += s.bytes;
  }
  return total;
}

}  // namespace tinsmith::server
