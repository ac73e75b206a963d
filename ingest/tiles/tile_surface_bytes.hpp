// The bytes of a tile's surface, as a shard hands its zoom-K tiles to the
// merge that builds the pyramid's top from their mosaic (tile_mosaic.hpp,
// TilerOptions::mosaicPoints): exactly what mosaicOf reads — the vertices'
// doubles bit for bit, the triangles, their held and river edges, the
// vertices' flags, the tile's error — so the merge's mosaic is the one a
// single run joins, and its top the same bytes.
//
// Little-endian whatever the host: "TSURFv01", the id (z, x, y: u32), the
// bounds (x0 y0 x1 y1), error and tolerance (f64), the vertex and triangle
// counts (u64), then per vertex x y z (f64), per triangle three corners
// (u32), per triangle its held then its river edge bits (u8), per vertex
// its flags (u8).
#pragma once

#include <string>
#include <string_view>

#include "core/tiles/tiler.hpp"

namespace tinsmith::ingest {

/// Where a shard's store keeps a tile's surface: "tinsmith/surfaces/Z/X/Y".
std::string tileSurfaceKey(const tiles::TileId& id);

std::string encodeTileSurface(const tiles::TileSurface& surface);

/// The surface encodeTileSurface wrote. Throws inputError naming `where`
/// (the store and key) when the bytes are not one: another format, ending
/// early or with more after them, a tile outside its zoom, an error or vertex
/// that is not finite (or a negative error), a corner that is no vertex,
/// edge or flag bits no tile has.
tiles::TileSurface decodeTileSurface(std::string_view bytes, const std::string& where);

}  // namespace tinsmith::ingest
