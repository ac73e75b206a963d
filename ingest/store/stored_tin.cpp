#include "ingest/store/stored_tin.hpp"

#include <algorithm>
#include <cstdio>

#include "core/base/error.hpp"

namespace tinsmith::store {

std::string tinPieceKey(std::size_t k) {
  char suffix[24];
  std::snprintf(suffix, sizeof suffix, ".%04zu", k);
  return std::string(kTinKey) + suffix;
}

bool holdsTin(const TileStore& store) {
  return store.contains(kTinKey) || store.contains(tinPieceKey(0));
}

std::vector<std::string> storedTinKeys(const TileStore& store) {
  if (store.contains(kTinKey)) return {std::string(kTinKey)};
  std::vector<std::string> keys;
  for (std::size_t k = 0; store.contains(tinPieceKey(k)); ++k) keys.push_back(tinPieceKey(k));
  return keys;
}

bool holdsEmptyTin(const TileStore& store) {
  const auto whole = store.get(kTinKey);
  return whole && whole->empty();
}

namespace {

// put, or for a value over kCopyPieceBytes putInPieces: an archive's SQLite
// would otherwise build its row with a copy of the whole value.
void putValue(TileStore& store, std::string_view key, std::string_view bytes) {
  if (bytes.size() <= kCopyPieceBytes) {
    store.put(key, bytes);
    return;
  }
  store.putInPieces(key, bytes.size(), [&](std::uint64_t offset, std::span<char> piece) {
    bytes.copy(piece.data(), piece.size(), static_cast<std::size_t>(offset));
  });
}

}  // namespace

void putTin(TileStore& store, std::string_view bytes, std::size_t pieceBytes) {
  if (pieceBytes == 0) throw internalError("putTin: a piece of 0 bytes");
  if (bytes.size() <= pieceBytes) {
    putValue(store, kTinKey, bytes);
    return;
  }
  const std::size_t pieces = (bytes.size() + pieceBytes - 1) / pieceBytes;
  for (std::size_t k = pieces; k-- > 0;) {
    const std::size_t begin = k * pieceBytes;
    putValue(store, tinPieceKey(k),
             bytes.substr(begin, std::min(pieceBytes, bytes.size() - begin)));
  }
}

std::optional<std::string> getTin(const TileStore& store) {
  if (auto whole = store.get(kTinKey)) return whole;
  std::optional<std::string> joined;
  for (std::size_t k = 0;; ++k) {
    auto piece = store.get(tinPieceKey(k));
    if (!piece) break;
    if (!joined) joined.emplace();
    joined->append(*piece);
  }
  return joined;
}

bool copyTin(const TileStore& from, TileStore& to) {
  const std::vector<std::string> keys = storedTinKeys(from);
  for (auto key = keys.rbegin(); key != keys.rend(); ++key) {
    const auto size = from.size(*key);
    if (!size)
      throw ioError("'" + *key + "' went missing from " + from.path().string() +
                    " while it was copied");
    if (*size == 0)
      throw inputError("the TIN in '" + from.path().string() + "' is empty",
                       fileLocation(from.path().string()),
                       "tile that store again with this tinsmith (an older one stored a TIN "
                       "over 10^9 bytes as nothing)");
    copyValue(from, *key, to);  // a piece of up to 256 MiB, a few MiB at a time
  }
  return !keys.empty();
}

}  // namespace tinsmith::store
