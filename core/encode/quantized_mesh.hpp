// Cesium's quantized-mesh-1.0 terrain tiles (github.com/CesiumGS/quantized-mesh):
// what CesiumJS's CesiumTerrainProvider, Cesium for Unreal/Unity and
// 3d-tiles-renderer stream as the globe's surface. A tile is little-endian
// binary, in this order:
//   - the header (88 bytes): the tile's centre in ECEF, its minimum and
//     maximum height (float), a bounding sphere, and the horizon occlusion
//     point in the ellipsoid-scaled frame;
//   - the vertices: a count and three arrays of u, v (0..32767 west→east,
//     south→north across the tile's longitude and latitude range) and height
//     (0..32767 from the minimum to the maximum height), each stored as the
//     zig-zag encoding of its delta from the previous vertex's;
//   - the triangles (counter-clockwise), 16-bit indices up to 65 536 vertices
//     and 32-bit past (padded to their own alignment), high-water-mark encoded;
//   - the indices of the vertices on the west, south, east and north edges,
//     plain, of the same width;
//   - extensions, each an id byte and a 32-bit length: oct-encoded vertex
//     normals (1), a water mask (2: one byte, or 256 × 256 from the north-west
//     corner row by row), metadata JSON (4).
// Encoding is plain serialisation: the caller quantizes (encodeQuantizedMesh
// checks the ranges), and the header's volumes come from the functions below.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/point.hpp"
#include "core/encode/frames.hpp"

namespace tinsmith::encode {

/// The largest quantized u, v or height.
inline constexpr std::uint16_t kQuantizedMax = 32767;

struct QuantizedMeshTile {
  Point3 centre;  ///< ECEF (m)
  float minHeight = 0, maxHeight = 0;
  Point3 sphereCentre;  ///< ECEF (m)
  double sphereRadius = 0;
  Point3 horizonOcclusion;  ///< ellipsoid-scaled ECEF
  std::vector<std::uint16_t> u, v, height;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise
  /// Vertices on the west, south, east and north edges.
  std::array<std::vector<std::uint32_t>, 4> edges;
  /// Per vertex, when not empty: the oct-encoded normal (octEncode).
  std::vector<std::array<std::uint8_t, 2>> octNormals;
  /// One byte (0 land, 255 water) or 256 × 256, when set.
  std::optional<std::vector<std::uint8_t>> waterMask;
  /// A JSON object (e.g. {"available": …}), when set.
  std::optional<std::string> metadata;
};

/// The tile as quantized-mesh-1.0 bytes (not gzipped). Throws internalError
/// for arrays of different lengths, a value above kQuantizedMax, an index
/// out of range, vertices not in first-use order (inFirstUseOrder), a water
/// mask that is neither 1 nor 65 536 bytes.
std::string encodeQuantizedMesh(const QuantizedMeshTile& tile);

/// Where a tile's extensions are: what a server needs to answer a client that
/// asks for some of them (Accept: application/vnd.quantized-mesh;extensions=…)
/// and to read a tile's metadata, without decoding the mesh.
struct QuantizedMeshExtension {
  std::uint8_t id = 0;                 ///< 1 normals, 2 water mask, 4 metadata
  std::size_t offset = 0, length = 0;  ///< of the payload, in the tile's bytes
};
struct QuantizedMeshLayout {
  std::size_t extensionsAt = 0;  ///< the end of the edge lists
  std::vector<QuantizedMeshExtension> extensions;
};
inline constexpr std::uint8_t kOctVertexNormals = 1, kWaterMask = 2, kMetadata = 4;

/// The layout of quantized-mesh-1.0 bytes. Throws inputError for bytes that
/// end early or run past their end.
QuantizedMeshLayout quantizedMeshLayout(std::string_view bytes);

/// The tile with only the extensions whose ids `keep` holds (in their order
/// in the tile).
std::string withExtensions(std::string_view bytes, std::span<const std::uint8_t> keep);

/// The tile's metadata JSON (extension 4), or nullopt when it has none.
std::optional<std::string> quantizedMeshMetadata(std::string_view bytes);

/// The tile with its metadata JSON replaced (or added, last).
std::string withMetadata(std::string_view bytes, std::string_view json);

/// Sets the header's volumes from the ECEF positions the tile draws: the
/// centre and the sphere's centre at the middle of their box, the radius to
/// the farthest, and the horizon occlusion point towards the centre. Throws
/// internalError for no positions.
void setBoundingVolumes(QuantizedMeshTile& tile, std::span<const Point3> ecef);

/// A terrain tile's mesh on the globe, to quantize: positions as longitude,
/// latitude (degrees) and height above the ellipsoid (m), counter-clockwise
/// triangles seen from above, and the tile's bounds.
struct GeodeticMesh {
  std::vector<Geodetic> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// The first this many triangles give the vertex normals; those after
  /// them (walls standing on the ground) are drawn but shade nothing.
  std::size_t shadingTriangles = static_cast<std::size_t>(-1);
  double west = 0, south = 0, east = 0, north = 0;  ///< degrees
};

/// A quantized tile and what quantizing did to it.
struct QuantizedTerrain {
  QuantizedMeshTile tile;  ///< in first-use order, with normals and volumes
  /// Per input vertex: its index in `tile`.
  std::vector<std::uint32_t> index;
  /// Per input vertex: its ECEF position as a client decodes it (u, v,
  /// height back to degrees and metres, then to ECEF).
  std::vector<Point3> decoded;
  /// The farthest quantization moved a vertex (m, ECEF).
  double maxMove = 0;
};

/// Quantizes a mesh to its tile: u, v across the bounds and heights across
/// their range to 0..32767 (rounded), the vertices on each side (u or v 0 or
/// 32767 after rounding) in the edge lists, area-weighted normals in ECEF
/// oct-encoded, the header's volumes from the decoded positions. Vertices
/// outside the bounds are clamped onto them. Throws internalError for no
/// vertices or empty bounds.
QuantizedTerrain quantizeTerrain(const GeodeticMesh& mesh);

/// The tile with its vertices renumbered in the order its triangles first
/// use them (what high-water-mark encoding needs), vertices no triangle uses
/// after those; edges and normals follow their vertices. With `renumbered`,
/// each old vertex's new index there.
QuantizedMeshTile inFirstUseOrder(const QuantizedMeshTile& tile,
                                  std::vector<std::uint32_t>* renumbered = nullptr);

/// Oct encoding of a unit vector in two bytes (Cigolle et al. 2014, "A Survey
/// of Efficient Representations of Independent Unit Vectors", as CesiumJS's
/// AttributeCompression does it with 8 bits a component), and its decoding.
std::array<std::uint8_t, 2> octEncode(const Point3& normal);
Point3 octDecode(std::array<std::uint8_t, 2> oct);

/// The horizon occlusion point of ECEF points (Cesium's
/// EllipsoidalOccluder.computeHorizonCullingPointFromPoints on WGS84): on the
/// ray from the Earth's centre through `direction` (the tile's centre), in
/// the ellipsoid-scaled frame, the nearest point from which every one of the
/// points is at or above the horizon; points below the ellipsoid count as on
/// it. If the point is below a viewer's horizon, so is the whole tile.
Point3 horizonOcclusionPoint(std::span<const Point3> ecef, const Point3& direction);

}  // namespace tinsmith::encode
