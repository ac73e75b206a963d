// The tiling job: a TIN into a tile store (DESIGN.md "Tiles"). Runs the
// pyramid walk (core/tiles) and writes what it makes:
//   tinsmith/build.json   what was built from what (TIN checksum, options)
//   tinsmith/terrain.tin  the TIN itself (the server answers elevations from it;
//                         not in a shard of a subtree below the root, whose
//                         merge takes it from the top shard); in pieces
//                         terrain.tin.0000, … when it is larger than one
//                         (ingest/store/stored_tin.hpp)
//   tiles/{z}/{x}/{y}.glb one per tile; asset.extras carries the tile's record
//   tileset.json (+ tilesets/…) written last, from the records; its
//                         extras.tinsmith holds the CRS, the tolerance and,
//                         for the local frame, "enuOrigin": [lon°, lat°, h m]
//                         (WGS84, ellipsoidal), the origin of the tiles'
//                         east-north-up axes
// An output is built beside its name — an archive X.3dtiles in
// "X.partial.3dtiles", a folder X in the folder "X.partial" — and takes the
// name only when complete, atomically (an archive is written out in one
// canonical key order and renamed, so one run, a resumed run and merged
// shards give the same bytes; a folder is exchanged with the old one). A run
// killed at any moment leaves the old store or the new one, whole, under
// the name, and a failed run keeps the stage for --resume. What is at the
// name or the stage is replaced only when it is a tinsmith store
// (store::requireReplaceable), and every option is checked before either is
// touched. A shard's store also holds tinsmith/shard.json, the part of the
// pyramid it answers for, and once finished tinsmith/shard-finished.json
// (its tiles' count and each one's CRC-32, which merge checks). Over a
// mosaic zoom K (tiles::TilerOptions::mosaicPoints) a shard holds no tile
// above K and hands over instead, for each zoom-K tile it holds,
//   tinsmith/surfaces/{z}/{x}/{y}  the tile's surface (tile_surface_bytes.hpp;
//                         its CRC-32 in shard-finished.json too), of which
//                         merge builds the tiles above K.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/encode/glb.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/store/stored_tin.hpp"
#include "ingest/tiles/tiling_plan.hpp"

namespace tinsmith::ingest {

/// What a job writes: 3D Tiles (tileset.json and .glb tiles), Cesium
/// terrain (quantized-mesh-1.0, terrain_job.hpp), or both in one store.
enum class TileScheme { Tiles3D, QuantizedMesh, Both };

struct TileJobOptions {
  tiles::TilerOptions tiler;
  TileScheme scheme = TileScheme::Tiles3D;
  /// layer.json's attribution (Cesium terrain).
  std::string attribution;
  encode::Compression compression = encode::Compression::Draco;
  tiles::ContentFrame frame = tiles::ContentFrame::Ecef;
  std::string geoid;                     ///< "" (ellipsoidal) or "egm96"
  std::optional<tiles::TileId> subtree;  ///< only this tile and its descendants
  /// A subtree that is not in the pyramid (an ancestor holds no terrain or
  /// meets the tolerance) is no error: nothing is written and the summary
  /// says why (TileJobSummary::notInPyramid). For shard arrays whose
  /// subtrees are not known ahead (tinsmith slurm).
  bool subtreeMayBeEmpty = false;
  /// With subtree: its ancestors are not built to check that it is in the
  /// pyramid (they cover far more of the TIN than it does). The shard holds
  /// the subtree whatever they would say (no tile when its root holds no
  /// terrain), and merge leaves it out when an ancestor does not refine.
  bool uncheckedAncestors = false;
  std::optional<int> untilZoom;  ///< only tiles above this zoom
  /// With untilZoom and no plan (the top task of a sharded job): the plan
  /// this run makes of the whole TIN is written here (writeTilingPlan,
  /// atomically) before any tile, with the corners off the TIN to
  /// min(untilZoom + 4, tiles::kMaxCornerZoom) — the plan the job's subtree
  /// shards take (tinsmith slurm's tiler.plan), so the whole TIN is read and
  /// planned once, by the task that tiles what lies above the subtrees.
  std::optional<std::filesystem::path> writePlan;
  /// Tiles at this zoom and below are built (their records make
  /// tileset.json) but not stored: the server's --on-demand builds them
  /// again from the store's TIN when asked (ingest/tiles/tile_rebuild.hpp).
  /// The tiles above the mosaic zoom (tiles::TilerOptions::mosaicPoints)
  /// are stored whatever it says.
  std::optional<int> storeUntilZoom;
  bool resume = false;
  int threads = 0;
  /// The plan of this job's whole TIN (tinsmith slurm's tiler.plan): the
  /// tiler takes it instead of planning, and the TIN must be the one it was
  /// made of (with the options it was made with).
  std::shared_ptr<const TilingPlan> plan;
  /// `tin` is only the part around the subtree (readTinFilePart of
  /// tiles::tilerReadRegion and tiles::tilerVertexRegion of its square) of
  /// the TIN this names (TinPart's fileCrc and counts): for a subtree below
  /// the root whose ancestors are unchecked, with the plan of that TIN.
  std::optional<TinIdentity> partOf;
  /// The store's copy of the TIN goes in pieces of this size when larger
  /// (store::putTin; tests make it small).
  std::size_t tinPieceBytes = store::kTinPieceBytes;
};

/// The names `tinsmith tile` and the config's [tiles] use: "draco" | "none",
/// "ecef" | "local", "" | "egm96"; nullopt (false) for any other.
std::optional<encode::Compression> parseCompression(std::string_view name);
std::optional<tiles::ContentFrame> parseContentFrame(std::string_view name);
bool isKnownGeoid(std::string_view name);
std::string_view compressionName(encode::Compression compression);
std::string_view contentFrameName(tiles::ContentFrame frame);
/// "3d-tiles" | "quantized-mesh" | "both".
std::optional<TileScheme> parseTileScheme(std::string_view name);
std::string_view tileSchemeName(TileScheme scheme);
inline bool writesTiles3D(TileScheme s) {
  return s != TileScheme::QuantizedMesh;
}
inline bool writesTerrain(TileScheme s) {
  return s != TileScheme::Tiles3D;
}

/// Throws usageError (naming the option and the bad value) unless the
/// options can make a pyramid: tolerance > 0, max triangles ≥ 64, max zoom in
/// [0, 30], λ factor > 0, a known geoid, threads ≥ 0, until-zoom ≥ 1, not
/// both a subtree and an until-zoom, store-until-zoom ≥ 1 and only for a
/// whole pyramid. runTileJob checks the same; callers that
/// do long work first (tinsmith build) call it before.
void checkTileJobOptions(const TileJobOptions& options);

struct ZoomSummary {
  int z = 0;
  double tolerance = 0;
  std::size_t tiles = 0, triangles = 0, vertices = 0, bytes = 0, breakLineVertices = 0;
  double maxError = 0;
  std::size_t overTolerance = 0;  ///< tiles whose measured error is over the zoom's tolerance
};

/// A tile whose measured error (its geometricError) is over its zoom's
/// tolerance: a client that picks tiles by the zoom's error sees it coarser
/// than asked.
struct MissedTile {
  tiles::TileId id;
  double error = 0, tolerance = 0;
  /// Its error without the triangles no refinement reaches (TileRecord):
  /// within the tolerance, the tile misses only where its sides keep every
  /// descendant from reaching (a spot within 2 cm of a side).
  double reachableError = 0;
  [[nodiscard]] bool outOfReach() const { return reachableError <= tolerance; }
};

/// Cesium terrain's part of a job: per level (ZoomSummary::z is the grid's
/// level, its tolerance CesiumJS's error for the level).
struct TerrainSummary {
  std::vector<ZoomSummary> levels;
  std::vector<MissedTile> missed;  ///< tiles over their level's error
  std::size_t tiles = 0, built = 0, reused = 0, bytes = 0;
  int finestLevel = 0;
};

struct TileJobSummary {
  /// Why a subtree allowed to be empty was not built; empty when it was.
  std::string notInPyramid;
  std::optional<TerrainSummary> terrain;
  std::vector<ZoomSummary> zooms;
  std::vector<MissedTile> missed;  ///< in (z, y, x) order
  std::size_t tiles = 0, built = 0, reused = 0, bytes = 0;
  int finestZoom = 0;
  int levelsPerTile = 0;
  std::size_t dataPoints = 0;
  /// A shard over a mosaic zoom K ≥ 1: K (the tiles above it are the
  /// merge's) and how many zoom-K tiles' surfaces it hands over; 0 else.
  int leftAboveZoom = 0;
  std::size_t surfacesHandedOver = 0;
  double seconds = 0;
  /// The whole process's CPU time and peak resident memory, as the command
  /// that ran the job measured them (a shard's log and report tell its
  /// cost); 0 when not measured (a store described by tinsmith info).
  double cpuSeconds = 0;
  std::size_t peakMemoryBytes = 0;
};

/// The build records' format: raised whenever the tiles of one TIN and one
/// set of options change, so that a store of an older tinsmith is not
/// resumed, merged or rebuilt on demand with tiles that do not fit it (2:
/// positions quantized to the zoom's encoding share, not to 1 cm, and the
/// side margins with them; chord sag planned as the CRS bends it,
/// chordSagRadius; 3: the sag radius grown where the CRS stretches the
/// ground, a tile over its tolerance quantized to its own error, a shard's
/// tiles' CRC-32 in shard-finished.json; 4: the sag radius measured over
/// the part of a tile's square the TIN's box covers, and over 2^18 fit
/// points the planning fit over squares, which may choose another finest
/// zoom; 5: over 2^18 vertices the tiles above the mosaic zoom fitted to
/// the mosaic of its tiles, which the record names).
inline constexpr const char* kTileBuildFormat = "tinsmith-tiles/5";

/// Tiles `tin` (read from `tinName`, for messages and the build record) into
/// `output`. With `resume`, tiles are taken from the stage and from a
/// finished store at `output`. Throws usageError for bad options (a --resume
/// whose store was built from other input or options, a subtree not in the
/// pyramid), ioError when the output is not a tinsmith store or cannot be
/// written (nothing half-written is left under the output's name).
TileJobSummary runTileJob(const TinData& tin, const std::string& tinName,
                          const std::filesystem::path& output, const TileJobOptions& options,
                          const Progress* progress = nullptr);

/// Where a local frame's east-north-up axes stand: the pyramid's centre on
/// the ground (height 0 in the project CRS).
encode::Geodetic pyramidCentre(const tiles::PyramidGeometry& pyramid,
                               const tiles::GeoReference& geo);

/// Whether `path` is a shard's store that finished, as merge takes it: not a
/// stage left by a shard that was killed, failed or is still running, nor
/// one that lost tiles or surfaces, nor a damaged or missing store, nor an
/// older tinsmith's shard of a job with a mosaic zoom (it hands over no
/// surfaces); with `checkTileBytes`, nor one holding a tile or surface whose
/// bytes are not those it finished with (their CRC-32: every one is read,
/// the store's size).
bool isFinishedShard(const std::filesystem::path& path, bool checkTileBytes = false);

/// Joins stores built from the same TIN and options (shards: subtrees and the
/// tiles above them) into one, as one run would have written it. Throws
/// usageError, before the output is touched, when the output is one of the
/// inputs, they disagree (other input or options) or none is the top of the
/// pyramid, inputError when one is a shard that did not finish
/// (isFinishedShard) or holds a tile whose bytes are not those it finished
/// with (its CRC-32), and without leaving a
/// stage when a tile differs between them or a child of a refined tile is in
/// none of them (a shard that answers for the child and lacks it found it
/// empty). Over a mosaic zoom K ≥ 1, when every input is a shard (none
/// holds the tiles above K), it builds those tiles, on `threads` (0: all
/// cores), from the surfaces of zoom K's tiles the shards hand over, with
/// the options the build record names: the bytes of one run. The surfaces
/// are read and checked before the output is touched (inputError naming a
/// shard that lacks one or whose bytes are damaged, usageError when no
/// shard answers for a zoom-K tile).
TileJobSummary mergeTileStores(const std::vector<std::filesystem::path>& inputs,
                               const std::filesystem::path& output, int threads = 0,
                               const Progress* progress = nullptr);

/// What `tinsmith info` tells of a store: its build record (JSON text) and the
/// per-zoom summary from the tiles' records.
struct StoreInfo {
  std::string build;  ///< tinsmith/build.json, or empty
  /// Every scheme the build asked for has its index (tileset.json,
  /// terrain/layer.json); `missing` names those that are not there.
  bool complete = false;
  std::string missing;
  TileJobSummary summary;
};
StoreInfo describeTileStore(const std::filesystem::path& path);

}  // namespace tinsmith::ingest
