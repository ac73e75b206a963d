// A tile's surface as streamable content: skirts along its sides, positions
// in the output frame relative to the tile's centre, per-vertex normals, the
// glTF root-node matrix (core/encode/frames.hpp), then the .glb
// (core/encode/glb.hpp). Also the tile's record — what tileset.json needs to
// know of it — which travels inside the .glb as asset.extras, so a store's
// tiles describe themselves (resume and merge read them back).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/encode/frames.hpp"
#include "core/encode/glb.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

/// Project coordinates (x, y in the project CRS, z in its vertical datum) to
/// WGS84 geodetic with ellipsoidal heights. Implementations must be
/// thread-safe (tiles are encoded on several threads).
class GeoReference {
 public:
  virtual ~GeoReference() = default;
  virtual void toGeodetic(std::span<const Point3> in, std::span<encode::Geodetic> out) const = 0;
};

enum class ContentFrame {
  Ecef,   ///< ECEF relative to the tile centre; `region` bounding volumes (3D Tiles)
  Local,  ///< east-north-up metres at the pyramid's centre; `box` volumes (plain three.js)
};

struct ContentOptions {
  encode::Compression compression = encode::Compression::Draco;
  ContentFrame frame = ContentFrame::Ecef;
  const GeoReference* geo = nullptr;  ///< required
  encode::Geodetic localOrigin;       ///< the ENU origin for ContentFrame::Local
};

/// What tileset.json says of a tile.
struct TileRecord {
  TileId id;
  /// The tile's geometricError (m): a bound on the 3-D distance between what
  /// a client draws — the decoded positions, straight triangles between them
  /// — and the TIN, over the tile's part of it (encodeTile says how).
  double error = 0.0;
  /// The same bound over the triangles a refinement can reach (all but the
  /// refiner's outOfReach ones): what decides children from the planned
  /// finest zoom on (tileRefines). At most `error`.
  double reachableError = 0.0;
  std::array<double, 6> region{};  ///< west, south, east, north (rad), min, max height (m)
  std::array<double, 12> box{};    ///< local frame: centre, then three half-axes (m)
  bool local = false;              ///< which of region / box is meaningful
  std::size_t vertices = 0, triangles = 0, bytes = 0;
  std::size_t breakLineVertices = 0;
  int positionBits = 0;
  double positionErrorBound = 0.0;
};

/// The record as the JSON object stored in asset.extras ({"tinsmith": {...}}).
std::string recordToJson(const TileRecord& record);
/// Reads a record back from asset.extras; nullopt when there is none.
std::optional<TileRecord> recordFromExtras(std::string_view assetExtras);
/// The record inside a .glb (its JSON chunk only; nothing is decoded);
/// nullopt for bytes that are not a .glb with a record.
std::optional<TileRecord> recordFromGlb(std::string_view glb);

struct TileContent {
  std::string glb;  ///< the tile's bytes: a .glb (or a .terrain, terrain_content.hpp)
  TileRecord record;
};

/// Encodes a non-empty tile surface. `skirtDepth` (m) is how far the skirts
/// reach below the sides.
///
/// The record's error and bounds are those of what is shipped
/// (docs/tile-error.md): positions as a client decodes them
/// (encode::decodedPositions, Draco's rounding included) and triangles as it
/// draws them, straight in ECEF (or the local frame) between points on the
/// curved Earth. Per surface triangle, its vertical error measured before
/// encoding (TileSurface::triangleErrors; a vertical distance bounds the 3-D
/// one), plus the farthest encoding moved one of its corners, plus its
/// chord's sag below the ground (measured at its edges' middles through the
/// georeference, taken over the triangle as the quadratic it is): the
/// largest is the error, a bound on the 3-D distance both ways. On a
/// near-vertical wall, where a millimetre across moves the surface metres
/// vertically, the vertical distance means nothing and is not what it bounds.
/// The region holds the decoded positions, every edge's chord middle and
/// every triangle's centre, and reaches down to each triangle's sag.
TileContent encodeTile(const TileSurface& tile, double skirtDepth, const ContentOptions& options);

}  // namespace tinsmith::tiles
