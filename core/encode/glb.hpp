// glTF 2.0 binary (.glb) tile content: one mesh, one primitive of triangles
// with POSITION and NORMAL, written with nlohmann::json (glb.cpp says why not
// tinygltf); compressed with Draco (KHR_draco_mesh_compression, a required
// extension) or left plain. The encoder knows nothing of tiles or frames: the
// caller hands positions already in the content frame and the root node's
// matrix (core/encode/frames.hpp).
//
// Draco: positions are quantized on the bounding cube of the positions with
// the fewest bits (≤ 30) whose rounding moves no position farther than
// maxPositionError (the bound, √3 × the per-coordinate rounding, is reported); normals with
// normalBits (octahedral). Draco keeps the triangle set but may reorder vertices and triangles, and
// drops positions no triangle uses (the accessor counts say what it kept).
// Output is deterministic: the same mesh and options give the same bytes.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/encode/frames.hpp"

namespace tinsmith::encode {

enum class Compression { None, Draco };

/// A triangle mesh in the content frame (metres, relative to the root node's
/// origin). Triangles are counter-clockwise seen from outside (from above the
/// terrain); normals are unit length, one per position.
struct MeshBuffers {
  std::vector<std::array<float, 3>> positions;
  std::vector<std::array<float, 3>> normals;
  std::vector<std::uint32_t> indices;  ///< 3 per triangle
};

struct GlbOptions {
  Compression compression = Compression::Draco;
  /// Farthest Draco's rounding may move a position (m, Euclidean).
  double maxPositionError = 0.01;
  int normalBits = 10;
  /// A JSON object (text) stored as the glTF `asset.extras`; empty for none.
  std::string assetExtras;
};

struct GlbResult {
  std::string bytes;
  int positionBits = 0;             ///< Draco quantization bits (0 when plain)
  double positionErrorBound = 0.0;  ///< farthest its rounding moves a position (m)
};

/// How far Draco's own float32 arithmetic may move a decoded position (m), on
/// top of GlbResult::positionErrorBound: its quantizer subtracts each
/// coordinate's minimum and scales, its dequantizer scales and adds the
/// minimum back, all in float, over a range of at most 2c, c the mesh's
/// largest |coordinate|. Each operation rounds by at most 2⁻²⁴ of its result:
/// 13 · 2⁻²⁴ · c a coordinate, √3 times that a position. Only on wide meshes
/// does it matter (c = 3.5 km: 4.7 mm): quantization bits past about 21 buy
/// nothing there.
double dracoArithmeticBound(const MeshBuffers& mesh);

/// Encodes the mesh as a .glb whose single root node has `rootMatrix`.
/// Index width: unsigned short below 65 536 positions, else unsigned int.
/// Throws inputError for an empty mesh, an index out of range, an index count
/// not a multiple of 3, a normal count that differs from the position count, a
/// non-finite coordinate, or assetExtras that are not a JSON object;
/// usageError for a maxPositionError that is not positive or normalBits
/// outside [2, 30] (Draco only).
GlbResult encodeGlb(const MeshBuffers& mesh, const Matrix4& rootMatrix, const GlbOptions& options);

/// The positions a client decodes from encodeGlb(mesh, …, options), one per
/// position of `mesh`, in its order: the mesh's own when plain; with Draco,
/// its quantization — on the bits encodeGlb chooses, with Draco's own
/// quantizer and dequantizer, as its encoder and decoder compute them (the
/// decoded values are a deterministic function of the positions and the
/// bits). What tiles measure their error and bounds on. Throws as encodeGlb.
std::vector<std::array<float, 3>> decodedPositions(const MeshBuffers& mesh,
                                                   const GlbOptions& options);

/// A .glb read back: its mesh (Draco decoded with Draco's C++ decoder), the root
/// node's matrix (identity when absent) and asset.extras as JSON text (empty
/// when absent). For tests, `tinsmith info` and the store's resume. Throws
/// inputError naming `name` for bytes that are not such a .glb.
struct DecodedGlb {
  MeshBuffers mesh;
  Matrix4 rootMatrix{};
  std::string assetExtras;
  bool draco = false;
};
DecodedGlb decodeGlb(std::string_view bytes, std::string_view name);

/// asset.extras of a .glb as compact JSON text (empty when absent), from its
/// container and JSON chunk alone (no mesh is decoded). Throws inputError
/// naming `name` for bytes that are not a .glb.
std::string glbAssetExtras(std::string_view bytes, std::string_view name);

}  // namespace tinsmith::encode
