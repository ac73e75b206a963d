// The tiling plan file: what every shard of one tiling job (tinsmith slurm)
// takes from the whole TIN instead of finding it again — the TIN's identity,
// the options the plan was made with, and tiles::TilerPlan (the pyramid, the
// finest zoom, the fit sampling and the lines simplified for each zoom). A
// shard given the plan reads only its square of the TIN (readTinFilePart).
//
// Little-endian, no padding:
//   magic "\x89TSPLAN\n" (8 bytes), u32 version (kTilingPlanVersion)
//   TIN: u32 file CRC-32, u64 vertices, u64 triangles
//   options: f64 tolerance, u64 maxTriangles, i32 maxZoom (−1: none), f64 λ factor
//   pyramid: f64 origin x, f64 origin y, f64 size, the TIN's box f64 x0, y0,
//     x1, y1 (version 3 on), i32 finestZoom
//   fit: f64 spacing, u8 tile fits take all data
//   i32 mosaicZoom (version 4 on)
//   u32 zooms, per zoom u64 lines, per line u8 kind, u8 ring, u8 closed,
//     u64 n, n × (f64 x, y, z)
//   corners off the TIN: i32 cornerZoom (−1: none), u64 n,
//     n × (u8 zoom, u32 row, u32 column, f64 z), by zoom, row, column
//   u32 CRC-32 of everything before it
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "core/tiles/tiler.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

inline constexpr std::uint32_t kTilingPlanVersion = 4;

/// Which TIN a plan (or a tile store's build record) is of.
struct TinIdentity {
  std::uint32_t crc32 = 0;  ///< of the .tin file's bytes (encodeTin)
  std::uint64_t vertices = 0, triangles = 0;
  bool operator==(const TinIdentity&) const = default;
};

struct TilingPlan {
  TinIdentity tin;
  /// The options the plan depends on (tolerance, maxTriangles, maxZoom,
  /// lambdaFactor); the rest of the TilerOptions are left at their defaults.
  tiles::TilerOptions options;
  tiles::TilerPlan tiler;
};

/// The plan of `tin` (the whole of it) for tiles with these options: runs
/// the planning (tiles::Tiler::plan), with the corners off the TIN to
/// `cornerZoom` (−1: none; a shard of zoom s reads vertices around its
/// square as far as 4 tile widths of zoom cornerZoom + 1, if finer than s).
/// The TIN is named by crc32(encodeTin(tin)).
TilingPlan makeTilingPlan(const TinData& tin, const tiles::TilerOptions& options,
                          int cornerZoom = -1);
/// The plan `tiler` (made of the whole TIN `tin` names, with `options`,
/// and no plan) holds: what a run that plans and tiles at once writes for
/// the shards that follow it.
TilingPlan makeTilingPlan(const tiles::Tiler& tiler, const tiles::TilerOptions& options,
                          int cornerZoom, const TinIdentity& tin);

std::string encodeTilingPlan(const TilingPlan& plan);
/// Throws inputError naming `name` for bytes that are not a whole plan of
/// this version.
TilingPlan decodeTilingPlan(std::string_view bytes, const std::string& name);
/// Written atomically; throws ioError.
void writeTilingPlan(const std::filesystem::path& path, const TilingPlan& plan);
TilingPlan readTilingPlan(const std::filesystem::path& path);

/// Throws usageError naming the plan file unless `options` are those the
/// plan was made with.
void requirePlannedOptions(const TilingPlan& plan, const tiles::TilerOptions& options,
                           const std::string& planName);

}  // namespace tinsmith::ingest
