// The TIN a tile store carries (the server's elevations, profiles and
// on-demand rebuilds read it): one value under kTinKey, or, when its bytes
// exceed a piece, pieces of that size under kTinKey + ".0000", ".0001", …
// An archive's value holds at most 10⁹ bytes (SQLite's limit; a TIN of about
// 20 M vertices), and pieces let a merge copy a TIN of any size a piece at a
// time. Piece 0 is written last: a store that holds it holds every piece.
// The piece size is fixed (kTinPieceBytes; the build record does not name
// it): a resumed stage written with another would keep its higher pieces.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ingest/store/tile_store.hpp"

namespace tinsmith::store {

inline constexpr std::string_view kTinKey = "tinsmith/terrain.tin";
inline constexpr std::size_t kTinPieceBytes = std::size_t{256} << 20;

/// The key of piece `k` of a TIN stored in pieces.
[[nodiscard]] std::string tinPieceKey(std::size_t k);

/// Whether the store holds a TIN (whole, or its piece 0).
[[nodiscard]] bool holdsTin(const TileStore& store);

/// The keys of the store's TIN, in order: kTinKey, or its pieces; none when
/// it holds none.
[[nodiscard]] std::vector<std::string> storedTinKeys(const TileStore& store);

/// Whether the store's whole TIN is an empty value: what a tinsmith before
/// the pieces stored for a TIN over an archive's 10⁹ bytes (reads the value).
[[nodiscard]] bool holdsEmptyTin(const TileStore& store);

/// Writes `bytes` as the store's TIN: whole when they fit in `pieceBytes`,
/// else in pieces of `pieceBytes` (piece 0 last).
void putTin(TileStore& store, std::string_view bytes, std::size_t pieceBytes = kTinPieceBytes);

/// The store's TIN, its pieces joined; nullopt when it holds none.
[[nodiscard]] std::optional<std::string> getTin(const TileStore& store);

/// Copies the TIN of `from` into `to` as it is stored (whole or in the same
/// pieces), one value at a time (piece 0 last); false when `from` holds none.
/// Throws inputError naming `from` when its TIN is an empty value.
bool copyTin(const TileStore& from, TileStore& to);

}  // namespace tinsmith::store
