// encodeGlb: the glTF document and the .glb container; see glb.hpp.
//
// The JSON is written with nlohmann::ordered_json rather than tinygltf's
// writer: tinygltf's Value turns empty arrays and objects into null and holds
// no integer beyond 32 bits, and asset.extras is the caller's JSON, which must
// survive as given. Members come out in a fixed order, numbers in the shortest
// text that reads back to the same double, so the bytes are deterministic.
#include "core/encode/glb.hpp"

#include <draco/attributes/attribute_quantization_transform.h>
#include <draco/compression/config/compression_shared.h>
#include <draco/compression/encode.h>
#include <draco/core/quantization_utils.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/base/version.hpp"
#include "core/encode/glb_format.hpp"

namespace tinsmith::encode {
namespace {

namespace gf = glb_format;
using Json = nlohmann::ordered_json;

static_assert(std::endian::native == std::endian::little,
              "glb buffers are written as the machine's bytes, which glTF requires little-endian");

// Draco's speed settings (0 slowest, best compression; 10 fastest). 3/3 is
// what draco_encoder's default compression level 7 means. On a 100 × 100
// terrain grid it is 24 % smaller than 5/5 at about the same encoding time;
// 0/0 is a further 6 % smaller at twice the time.
constexpr int kDracoEncodingSpeed = 3;
constexpr int kDracoDecodingSpeed = 3;

constexpr std::size_t kMaxIndexedPositions = std::numeric_limits<std::uint32_t>::max();

void checkMesh(const MeshBuffers& mesh) {
  if (mesh.positions.empty() || mesh.indices.empty()) {
    throw inputError(
        "the mesh has no " + std::string(mesh.positions.empty() ? "positions" : "triangles"), {},
        "encode a mesh with at least one triangle");
  }
  if (mesh.positions.size() > kMaxIndexedPositions) {
    throw inputError("the mesh has " + std::to_string(mesh.positions.size()) +
                     " positions, more than 32-bit indices can address");
  }
  if (mesh.indices.size() % 3 != 0) {
    throw inputError("the mesh has " + std::to_string(mesh.indices.size()) +
                     " indices, not a multiple of 3");
  }
  if (mesh.normals.size() != mesh.positions.size()) {
    throw inputError("the mesh has " + std::to_string(mesh.normals.size()) + " normals for " +
                         std::to_string(mesh.positions.size()) + " positions",
                     {}, "give one normal per position");
  }
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= mesh.positions.size()) {
      throw inputError("triangle " + std::to_string(i / 3) + " uses position " +
                       std::to_string(mesh.indices[i]) + " of " +
                       std::to_string(mesh.positions.size()));
    }
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(mesh.positions[i][c]) || !std::isfinite(mesh.normals[i][c])) {
        throw inputError("position or normal " + std::to_string(i) + " is not finite");
      }
    }
  }
}

void checkOptions(const GlbOptions& options) {
  if (options.compression != Compression::Draco) return;
  if (!(options.maxPositionError > 0.0) || !std::isfinite(options.maxPositionError)) {
    throw usageError(
        "the largest position error for Draco must be a positive number of metres, not " +
            std::to_string(options.maxPositionError),
        "give e.g. 0.01");
  }
  if (options.normalBits < 2 || options.normalBits > 30) {
    throw usageError("Draco normal quantization takes 2 to 30 bits, not " +
                     std::to_string(options.normalBits));
  }
}

Json parseAssetExtras(const std::string& text) {
  Json extras;
  try {
    extras = Json::parse(text);
  } catch (const Json::parse_error& e) {
    throw inputError(std::string("asset extras are not JSON: ") + e.what());
  }
  if (!extras.is_object()) throw inputError("asset extras are JSON but not an object");
  return extras;
}

struct Bounds {
  std::array<float, 3> min{};
  std::array<float, 3> max{};
};

Bounds positionBounds(const std::vector<std::array<float, 3>>& positions) {
  Bounds b{positions.front(), positions.front()};
  for (const auto& p : positions) {
    for (int c = 0; c < 3; ++c) {
      b.min[c] = std::min(b.min[c], p[c]);
      b.max[c] = std::max(b.max[c], p[c]);
    }
  }
  return b;
}

struct PositionQuantization {
  int bits = 0;
  double errorBound = 0.0;
};

// Draco quantizes each coordinate on the bounding cube: its range is the
// largest extent, computed in float (1 when all positions coincide), split
// into 2^b − 1 steps, and values round to the nearest step, so the error is at
// most range / (2^b − 1) / 2 (attribute_quantization_transform.cc), plus the
// float rounding of the coordinates themselves. A position moves by at most
// √3 times that (each coordinate rounds on its own): that distance is the
// bound chosen and reported.
PositionQuantization choosePositionBits(const Bounds& b, double maxError) {
  float range = 0.0f;
  for (int c = 0; c < 3; ++c) range = std::max(range, b.max[c] - b.min[c]);
  if (range == 0.0f) range = 1.0f;
  PositionQuantization q;
  for (q.bits = 1; q.bits <= 30; ++q.bits) {
    q.errorBound = std::sqrt(3.0) * static_cast<double>(range) /
                   static_cast<double>((1u << q.bits) - 1u) / 2.0;
    if (q.errorBound <= maxError) return q;
  }
  q.bits = 30;
  q.errorBound =
      std::sqrt(3.0) * static_cast<double>(range) / static_cast<double>((1u << 30) - 1u) / 2.0;
  return q;
}

struct DracoPrimitive {
  std::string bytes;
  std::size_t points = 0;
  std::size_t faces = 0;
  std::uint32_t positionId = 0;
  std::uint32_t normalId = 0;
};

std::uint32_t addDracoAttribute(draco::Mesh& dm, draco::GeometryAttribute::Type type,
                                const std::vector<std::array<float, 3>>& values) {
  auto attribute = std::make_unique<draco::PointAttribute>();
  attribute->Init(type, 3, draco::DT_FLOAT32, false, values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    attribute->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)),
                                 values[i].data());
  }
  const int id = dm.AddAttribute(std::move(attribute));
  return dm.attribute(id)->unique_id();
}

DracoPrimitive encodeDraco(const MeshBuffers& mesh, int positionBits, int normalBits) {
  draco::Mesh dm;
  dm.set_num_points(static_cast<std::uint32_t>(mesh.positions.size()));
  DracoPrimitive out;
  out.positionId = addDracoAttribute(dm, draco::GeometryAttribute::POSITION, mesh.positions);
  out.normalId = addDracoAttribute(dm, draco::GeometryAttribute::NORMAL, mesh.normals);
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    dm.AddFace({draco::PointIndex(mesh.indices[t]), draco::PointIndex(mesh.indices[t + 1]),
                draco::PointIndex(mesh.indices[t + 2])});
  }

  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, positionBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, normalBits);
  encoder.SetSpeedOptions(kDracoEncodingSpeed, kDracoDecodingSpeed);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  // Edgebreaker may split non-manifold vertices and drops degenerate
  // triangles, so the accessor counts come from what was encoded.
  encoder.SetTrackEncodedProperties(true);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(dm, &buffer);
  if (!status.ok())
    throw internalError("Draco could not encode the mesh: " + status.error_msg_string());
  out.bytes.assign(buffer.data(), buffer.size());
  out.points = encoder.num_encoded_points();
  out.faces = encoder.num_encoded_faces();
  return out;
}

// What Draco's decoder returns for the POSITION attribute encodeDraco writes:
// SequentialQuantizationAttributeEncoder computes the quantization on the
// attribute (AttributeQuantizationTransform::ComputeParameters) and
// quantizes value − min with a Quantizer; the decoder adds min back to the
// Dequantizer's value, in float. The same calls, in the same order.
std::vector<std::array<float, 3>> dracoDecodedPositions(const MeshBuffers& mesh, int bits) {
  draco::PointAttribute attribute;
  attribute.Init(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, false,
                 mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    attribute.SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)),
                                mesh.positions[i].data());
  }
  draco::AttributeQuantizationTransform transform;
  if (!transform.ComputeParameters(attribute, bits))
    throw internalError("Draco could not quantize the positions");
  const auto maxQuantized = static_cast<std::int32_t>((1u << static_cast<unsigned>(bits)) - 1u);
  draco::Quantizer quantizer;
  quantizer.Init(transform.range(), maxQuantized);
  draco::Dequantizer dequantizer;
  if (!dequantizer.Init(transform.range(), maxQuantized))
    throw internalError("Draco could not dequantize the positions");
  std::vector<std::array<float, 3>> out(mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float min = transform.min_value(c);
      const std::int32_t q = quantizer.QuantizeFloat(mesh.positions[i][c] - min);
      out[i][c] = dequantizer.DequantizeFloat(q) + min;
    }
  }
  return out;
}

template <typename T>
void appendRaw(std::string& bin, const T* data, std::size_t count) {
  bin.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

void appendU32(std::string& out, std::uint32_t v) {
  appendRaw(out, &v, 1);
}

Json vec3(const std::array<float, 3>& v) {
  return Json::array(
      {static_cast<double>(v[0]), static_cast<double>(v[1]), static_cast<double>(v[2])});
}

Json floatVec3Accessor(std::size_t count) {
  Json a = Json::object();
  a["componentType"] = gf::kFloat;
  a["count"] = count;
  a["type"] = "VEC3";
  return a;
}

int indexComponentType(std::size_t positions) {
  return positions < 65536 ? gf::kUnsignedShort : gf::kUnsignedInt;
}

bool isIdentity(const Matrix4& m) {
  for (int i = 0; i < 16; ++i) {
    if (m[i] != (i % 5 == 0 ? 1.0 : 0.0)) return false;
  }
  return true;
}

// The glb container: 12-byte header, the JSON chunk padded with spaces and
// the BIN chunk padded with zeros, each to 4 bytes.
std::string assembleGlb(const std::string& jsonText, const std::string& bin) {
  const auto padded = [](std::size_t n) { return (n + 3) / 4 * 4; };
  const std::size_t jsonBytes = padded(jsonText.size());
  const std::size_t binBytes = padded(bin.size());
  const std::size_t total = gf::kHeaderBytes + gf::kChunkHeaderBytes + jsonBytes +
                            (bin.empty() ? 0 : gf::kChunkHeaderBytes + binBytes);
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    throw inputError("the mesh makes a .glb of " + std::to_string(total) +
                         " bytes, more than the format's 4 GiB",
                     {}, "split it into smaller tiles");
  }
  std::string out;
  out.reserve(total);
  appendU32(out, gf::kMagic);
  appendU32(out, gf::kVersion);
  appendU32(out, static_cast<std::uint32_t>(total));
  appendU32(out, static_cast<std::uint32_t>(jsonBytes));
  appendU32(out, gf::kChunkJson);
  out += jsonText;
  out.append(jsonBytes - jsonText.size(), ' ');
  if (!bin.empty()) {
    appendU32(out, static_cast<std::uint32_t>(binBytes));
    appendU32(out, gf::kChunkBin);
    out += bin;
    out.append(binBytes - bin.size(), '\0');
  }
  return out;
}

}  // namespace

double dracoArithmeticBound(const MeshBuffers& mesh) {
  // Per coordinate, with R ≤ 2c the quantization range and u = 2⁻²⁴: value −
  // min (u·R), × 1/step with the reciprocal rounded (2u·R), + 0.5 before the
  // floor (u·R); then step rounded and × q (2u·R), + min (u·c): 13u·c
  // (draco/core/quantization_utils.h, attribute_quantization_transform.cc).
  float c = 0.0f;
  for (const auto& p : mesh.positions) {
    for (float v : p) c = std::max(c, std::abs(v));
  }
  return std::sqrt(3.0) * 13.0 * std::ldexp(static_cast<double>(c), -24);
}

GlbResult encodeGlb(const MeshBuffers& mesh, const Matrix4& rootMatrix, const GlbOptions& options) {
  checkMesh(mesh);
  checkOptions(options);
  const Json extras = options.assetExtras.empty() ? Json() : parseAssetExtras(options.assetExtras);
  const Bounds bounds = positionBounds(mesh.positions);

  Json doc = Json::object();
  doc["asset"] = {{"version", "2.0"}, {"generator", std::string("tinsmith ") + kVersion}};
  if (!extras.is_null()) doc["asset"]["extras"] = extras;
  const bool draco = options.compression == Compression::Draco;
  if (draco) {
    doc["extensionsUsed"] = Json::array({gf::kDracoExtension});
    doc["extensionsRequired"] = Json::array({gf::kDracoExtension});
  }
  doc["scene"] = 0;
  doc["scenes"] = Json::array({{{"nodes", Json::array({0})}}});
  Json node = {{"mesh", 0}};
  if (!isIdentity(rootMatrix)) node["matrix"] = rootMatrix;
  doc["nodes"] = Json::array({node});

  Json primitive = Json::object();
  primitive["attributes"] = {{"POSITION", 0}, {"NORMAL", 1}};
  primitive["indices"] = 2;
  primitive["mode"] = gf::kTriangles;
  // Matte ground: without a material a client draws glTF's default, metallic
  // 1 and roughness 1 (dark grey metal where no environment map is set).
  primitive["material"] = 0;
  doc["materials"] = Json::array(
      {{{"name", "terrain"},
        {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}}}});

  GlbResult result;
  std::string bin;
  Json positions = floatVec3Accessor(mesh.positions.size());
  Json normals = floatVec3Accessor(mesh.normals.size());
  Json indices = Json::object();
  if (draco) {
    const PositionQuantization q = choosePositionBits(bounds, options.maxPositionError);
    result.positionBits = q.bits;
    result.positionErrorBound = q.errorBound;
    const DracoPrimitive encoded = encodeDraco(mesh, q.bits, options.normalBits);
    bin = encoded.bytes;
    doc["bufferViews"] = Json::array({{{"buffer", 0}, {"byteLength", bin.size()}}});
    primitive["extensions"][gf::kDracoExtension] = {
        {"bufferView", 0},
        {"attributes", {{"POSITION", encoded.positionId}, {"NORMAL", encoded.normalId}}}};
    // No bufferView on the accessors (KHR_draco_mesh_compression); min/max
    // are those of the positions before quantization, as Draco's own glTF
    // writer does — decoded values lie within the error bound of them.
    positions["count"] = encoded.points;
    normals["count"] = encoded.points;
    indices["componentType"] = indexComponentType(encoded.points);
    indices["count"] = 3 * encoded.faces;
  } else {
    const std::size_t n = mesh.positions.size();
    const std::size_t vec3Bytes = n * sizeof(mesh.positions[0]);
    appendRaw(bin, mesh.positions.data(), n);
    appendRaw(bin, mesh.normals.data(), n);
    const int indexType = indexComponentType(n);
    if (indexType == gf::kUnsignedShort) {
      std::vector<std::uint16_t> narrow(mesh.indices.begin(), mesh.indices.end());
      appendRaw(bin, narrow.data(), narrow.size());
    } else {
      appendRaw(bin, mesh.indices.data(), mesh.indices.size());
    }
    const std::size_t indexBytes = bin.size() - 2 * vec3Bytes;
    doc["bufferViews"] =
        Json::array({{{"buffer", 0}, {"byteLength", vec3Bytes}, {"target", gf::kArrayBuffer}},
                     {{"buffer", 0},
                      {"byteOffset", vec3Bytes},
                      {"byteLength", vec3Bytes},
                      {"target", gf::kArrayBuffer}},
                     {{"buffer", 0},
                      {"byteOffset", 2 * vec3Bytes},
                      {"byteLength", indexBytes},
                      {"target", gf::kElementArrayBuffer}}});
    positions["bufferView"] = 0;
    normals["bufferView"] = 1;
    indices["bufferView"] = 2;
    indices["componentType"] = indexType;
    indices["count"] = mesh.indices.size();
  }
  positions["min"] = vec3(bounds.min);
  positions["max"] = vec3(bounds.max);
  indices["type"] = "SCALAR";
  doc["meshes"] = Json::array({{{"primitives", Json::array({primitive})}}});
  doc["accessors"] = Json::array({positions, normals, indices});
  doc["buffers"] = Json::array({{{"byteLength", bin.size()}}});

  result.bytes = assembleGlb(doc.dump(), bin);
  return result;
}

std::vector<std::array<float, 3>> decodedPositions(const MeshBuffers& mesh,
                                                   const GlbOptions& options) {
  checkMesh(mesh);
  checkOptions(options);
  if (options.compression != Compression::Draco) return mesh.positions;
  const PositionQuantization q =
      choosePositionBits(positionBounds(mesh.positions), options.maxPositionError);
  return dracoDecodedPositions(mesh, q.bits);
}

}  // namespace tinsmith::encode
