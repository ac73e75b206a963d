// A whole TIN as one glTF 2.0 binary (.glb): one mesh of its triangles with
// per-vertex normals and the tiles' matte material, Draco-compressed or
// plain, encoded as the tiles are (core/encode/mesh_buffers.hpp,
// core/encode/glb.hpp). Two frames:
//
//   ecef   georeferenced as a tile: positions in ECEF metres relative to the
//          centre of their bounding box, converted through the TIN's CRS
//          (and the EGM96 geoid when asked) as `tinsmith tile` does
//          (ingest/tiles/proj_georeference.hpp); the root node's matrix turns
//          glTF's y-up into ECEF's z-up and adds the centre
//          (core/encode/frames.hpp), so CesiumJS (Model.fromGltfAsync, no
//          model matrix) puts the terrain on the globe.
//   local  for Blender and other DCC tools: the TIN's own x, y, z minus an
//          offset (the TIN's bounding-box centre rounded to whole metres),
//          recorded in asset.extras.tinsmith.offset; the root node's matrix
//          is only the turn from the TIN's z-up to glTF's y-up (glTF x = east,
//          y = up, z = −north), so the file opens near the origin the right
//          way up. No CRS needed.
//
// asset.extras.tinsmith: {"frame", "crs", "geoid" (ecef), "offset" (local),
// "vertices", "triangles", "positionErrorBound"}. positionErrorBound (m) is
// the farthest any decoded position lies from its TIN vertex in the frame:
// plain, float32's rounding of positions relative to the origin; Draco, the
// requested bound, which holds that rounding, Draco's float arithmetic
// (encode::dracoArithmeticBound) and its quantization.
// Written atomically (ingest/base/atomic_file.hpp): a failed export leaves no
// file and whatever was at the path before. Output is deterministic.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "core/base/point.hpp"
#include "core/encode/glb.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

enum class GlbFrame { Ecef, Local };

/// "ecef" | "local"; nullopt for any other name.
std::optional<GlbFrame> parseGlbFrame(std::string_view name);

/// The default bound on how far a decoded position may lie from its vertex
/// (m): the tiles' loosest (their finest zoom's on Red Butte), which a TIN of
/// up to about 15 km holds with Draco's float32 arithmetic included.
inline constexpr double kDefaultGlbPositionError = 0.01;

struct GlbExportOptions {
  encode::Compression compression = encode::Compression::Draco;
  GlbFrame frame = GlbFrame::Ecef;
  /// Draco: the farthest a decoded position may lie from its vertex (m,
  /// Euclidean, float32 rounding and Draco's float arithmetic included).
  /// nullopt: kDefaultGlbPositionError, or float32's share + 1 mm on a TIN too
  /// wide for that (beyond about 15 km).
  std::optional<double> maxPositionError;
  std::string geoid;  ///< ecef: "" (z ellipsoidal) or "egm96" (z EGM96 heights)
};

struct GlbExport {
  std::string bytes;
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  int positionBits = 0;             ///< Draco's quantization bits (0 when plain)
  double positionErrorBound = 0.0;  ///< as in asset.extras (see the file comment)
  Point3 origin;                    ///< ecef: the ECEF centre; local: the offset taken off x, y, z
};

/// Checks the options alone (before any file is read or written): throws
/// usageError for an unknown geoid, a geoid with the local frame, or a
/// maxPositionError that is not a positive number of metres.
void checkGlbExportOptions(const GlbExportOptions& options);

/// The .glb of `tin`; `tinName` names it in errors. Throws inputError for a
/// TIN with no triangles, and (ecef) one with no CRS, a CRS that is not
/// projected metres or one PROJ cannot place; usageError when
/// maxPositionError is below what float32 positions alone can hold.
GlbExport exportGlb(const TinData& tin, const GlbExportOptions& options, std::string_view tinName);

/// exportGlb written to `path` atomically. Throws what exportGlb throws and
/// ioError naming `path` (a folder missing or not writable, disk full).
GlbExport writeGlb(const std::filesystem::path& path, const TinData& tin,
                   const GlbExportOptions& options, std::string_view tinName);

}  // namespace tinsmith::ingest
