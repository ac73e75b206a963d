// decodeGlb: reads back a .glb of one triangle mesh; see glb.hpp.
//
// The container and the JSON are parsed here rather than with tinygltf's
// loader: the Debian build of tinygltf has no Draco support and rejects the
// indices accessor of a Draco primitive, which has no bufferView by the
// KHR_draco_mesh_compression spec. Only what encodeGlb writes is needed, but
// any .glb whose first scene's first node holds a triangle mesh in the BIN
// chunk reads (a missing NORMAL gives no normals).
#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/mesh/mesh.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/encode/glb.hpp"
#include "core/encode/glb_format.hpp"

namespace tinsmith::encode {
namespace {

namespace gf = glb_format;
using Json = nlohmann::ordered_json;

class GlbReader {
 public:
  GlbReader(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}

  DecodedGlb read();
  /// asset.extras only: the container and the JSON chunk, nothing decoded.
  std::string readAssetExtras();

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw inputError(problem, SourceLocation{std::string(name_)},
                     "give a glTF 2.0 binary (.glb) with one triangle mesh");
  }
  std::uint32_t u32(std::size_t at) const {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes_.data() + at, 4);
    return v;
  }
  void readContainer();
  const Json& member(const Json& object, const char* key, const std::string& where) const;
  std::size_t index(const Json& object, const char* key, const std::string& where,
                    std::size_t limit) const;
  std::string_view bufferView(std::size_t view, const std::string& where) const;
  std::vector<std::array<float, 3>> readVec3(std::size_t accessor) const;
  std::vector<std::uint32_t> readIndices(std::size_t accessor) const;
  void readPlain(const Json& primitive, MeshBuffers& mesh) const;
  void readDraco(const Json& extension, MeshBuffers& mesh) const;
  static Matrix4 nodeMatrix(const Json& node);

  std::string_view bytes_;
  std::string_view name_;
  std::string_view bin_;
  Json doc_;
};

void GlbReader::readContainer() {
  if (bytes_.size() < gf::kHeaderBytes + gf::kChunkHeaderBytes) fail("too short for a .glb");
  if (u32(0) != gf::kMagic) fail("not a .glb (no 'glTF' magic)");
  if (u32(4) != gf::kVersion) fail("glb container version " + std::to_string(u32(4)) + ", not 2");
  const std::size_t length = u32(8);
  if (length < gf::kHeaderBytes + gf::kChunkHeaderBytes) {
    fail("the header says " + std::to_string(length) + " bytes, too few for a .glb");
  }
  if (length > bytes_.size()) {
    fail("the header says " + std::to_string(length) + " bytes, the file has " +
         std::to_string(bytes_.size()));
  }
  const std::size_t jsonBytes = u32(12);
  const std::size_t jsonStart = gf::kHeaderBytes + gf::kChunkHeaderBytes;
  if (u32(16) != gf::kChunkJson) fail("the first chunk is not JSON");
  if (jsonBytes > length - jsonStart) fail("the JSON chunk runs past the end");
  try {
    doc_ = Json::parse(bytes_.substr(jsonStart, jsonBytes));
  } catch (const Json::parse_error& e) {
    fail(std::string("the JSON chunk does not parse: ") + e.what());
  }
  const std::size_t binHeader = jsonStart + (jsonBytes + 3) / 4 * 4;
  if (binHeader + gf::kChunkHeaderBytes <= length && u32(binHeader + 4) == gf::kChunkBin) {
    const std::size_t binBytes = u32(binHeader);
    if (binBytes > length - binHeader - gf::kChunkHeaderBytes)
      fail("the BIN chunk runs past the end");
    bin_ = bytes_.substr(binHeader + gf::kChunkHeaderBytes, binBytes);
  }
}

const Json& GlbReader::member(const Json& object, const char* key, const std::string& where) const {
  if (!object.is_object() || !object.contains(key)) fail(where + " has no '" + key + "'");
  return object[key];
}

std::size_t GlbReader::index(const Json& object, const char* key, const std::string& where,
                             std::size_t limit) const {
  const Json& v = member(object, key, where);
  if (!v.is_number_unsigned() || v.get<std::size_t>() >= limit) {
    fail(where + " '" + key + "' is " + v.dump() + ", not an index below " + std::to_string(limit));
  }
  return v.get<std::size_t>();
}

std::string_view GlbReader::bufferView(std::size_t view, const std::string& where) const {
  const Json& views = member(doc_, "bufferViews", "the document");
  const std::string at = where + ", bufferView " + std::to_string(view);
  if (!views.is_array() || view >= views.size()) fail(at + " does not exist");
  const Json& v = views[view];
  const Json& buffers = member(doc_, "buffers", "the document");
  const std::size_t buffer = index(v, "buffer", at, buffers.is_array() ? buffers.size() : 0);
  if (buffer != 0 || buffers[0].contains("uri")) fail(at + " is not in the BIN chunk");
  const std::size_t offset = v.value("byteOffset", std::size_t{0});
  const std::size_t length = member(v, "byteLength", at).get<std::size_t>();
  if (offset > bin_.size() || length > bin_.size() - offset) fail(at + " runs past the BIN chunk");
  return bin_.substr(offset, length);
}

std::vector<std::array<float, 3>> GlbReader::readVec3(std::size_t accessor) const {
  const std::string at = "accessor " + std::to_string(accessor);
  const Json& a = doc_["accessors"][accessor];
  if (a.value("componentType", 0) != gf::kFloat || a.value("type", "") != "VEC3") {
    fail(at + " is not float VEC3");
  }
  const std::size_t count = member(a, "count", at).get<std::size_t>();
  const std::size_t viewIndex = index(a, "bufferView", at, member(doc_, "bufferViews", at).size());
  const std::string_view view = bufferView(viewIndex, at);
  const std::size_t stride = doc_["bufferViews"][viewIndex].value("byteStride", std::size_t{12});
  const std::size_t offset = a.value("byteOffset", std::size_t{0});
  if (stride < 12) fail(at + " has a byteStride below 12");
  if (count > 0 && (offset > view.size() || view.size() - offset < 12 ||
                    count - 1 > (view.size() - offset - 12) / stride)) {
    fail(at + " runs past its bufferView");
  }
  std::vector<std::array<float, 3>> out(count);
  for (std::size_t i = 0; i < count; ++i)
    std::memcpy(out[i].data(), view.data() + offset + i * stride, 12);
  return out;
}

std::vector<std::uint32_t> GlbReader::readIndices(std::size_t accessor) const {
  const std::string at = "accessor " + std::to_string(accessor);
  const Json& a = doc_["accessors"][accessor];
  const int type = a.value("componentType", 0);
  const std::size_t width = type == gf::kUnsignedByte    ? 1
                            : type == gf::kUnsignedShort ? 2
                            : type == gf::kUnsignedInt   ? 4
                                                         : 0;
  if (width == 0 || a.value("type", "") != "SCALAR") fail(at + " is not unsigned SCALAR indices");
  const std::size_t count = member(a, "count", at).get<std::size_t>();
  const std::string_view view =
      bufferView(index(a, "bufferView", at, member(doc_, "bufferViews", at).size()), at);
  const std::size_t offset = a.value("byteOffset", std::size_t{0});
  if (offset > view.size() || count > (view.size() - offset) / width)
    fail(at + " runs past its bufferView");
  std::vector<std::uint32_t> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    std::uint32_t v = 0;
    std::memcpy(&v, view.data() + offset + i * width, width);  // little-endian
    out[i] = v;
  }
  return out;
}

void GlbReader::readPlain(const Json& primitive, MeshBuffers& mesh) const {
  const Json& attributes = member(primitive, "attributes", "the primitive");
  const std::size_t accessors = member(doc_, "accessors", "the document").size();
  mesh.positions = readVec3(index(attributes, "POSITION", "the primitive's attributes", accessors));
  if (attributes.contains("NORMAL")) {
    mesh.normals = readVec3(index(attributes, "NORMAL", "the primitive's attributes", accessors));
  }
  if (primitive.contains("indices")) {
    mesh.indices = readIndices(index(primitive, "indices", "the primitive", accessors));
  } else {
    mesh.indices.resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.indices.size(); ++i)
      mesh.indices[i] = static_cast<std::uint32_t>(i);
  }
}

void GlbReader::readDraco(const Json& extension, MeshBuffers& mesh) const {
  const std::string at = std::string("the primitive's ") + gf::kDracoExtension;
  const std::string_view bytes =
      bufferView(index(extension, "bufferView", at, member(doc_, "bufferViews", at).size()), at);
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) fail("Draco cannot decode the mesh: " + decoded.status().error_msg_string());
  const std::unique_ptr<draco::Mesh> dm = std::move(decoded).value();

  const Json& attributes = member(extension, "attributes", at);
  const auto readAttribute = [&](const char* semantic, std::vector<std::array<float, 3>>& out) {
    const Json& id = member(attributes, semantic, at + " attributes");
    const draco::PointAttribute* att =
        id.is_number_unsigned() ? dm->GetAttributeByUniqueId(id.get<std::uint32_t>()) : nullptr;
    if (att == nullptr || att->num_components() != 3) {
      fail(at + " " + semantic + " is not a 3-component Draco attribute");
    }
    out.resize(dm->num_points());
    for (draco::PointIndex p(0); p < dm->num_points(); ++p) {
      if (!att->ConvertValue<float>(att->mapped_index(p), 3, out[p.value()].data())) {
        fail(at + " " + semantic + " does not convert to float");
      }
    }
  };
  readAttribute("POSITION", mesh.positions);
  if (attributes.contains("NORMAL")) readAttribute("NORMAL", mesh.normals);
  mesh.indices.resize(3 * static_cast<std::size_t>(dm->num_faces()));
  for (draco::FaceIndex f(0); f < dm->num_faces(); ++f) {
    const auto& face = dm->face(f);
    for (int k = 0; k < 3; ++k) mesh.indices[3 * f.value() + k] = face[k].value();
  }
}

// A node's local matrix: `matrix`, else translation · rotation · scale.
Matrix4 GlbReader::nodeMatrix(const Json& node) {
  Matrix4 m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (node.contains("matrix")) return node["matrix"].get<Matrix4>();
  const auto t = node.value("translation", std::array<double, 3>{0, 0, 0});
  const auto q = node.value("rotation", std::array<double, 4>{0, 0, 0, 1});  // x, y, z, w
  const auto s = node.value("scale", std::array<double, 3>{1, 1, 1});
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) m[4 * col + row] = r[row][col] * s[col];
    m[12 + col] = t[col];
  }
  return m;
}

std::string GlbReader::readAssetExtras() {
  readContainer();
  const Json& asset = member(doc_, "asset", "the document");
  return asset.contains("extras") ? asset["extras"].dump() : std::string();
}

DecodedGlb GlbReader::read() {
  readContainer();
  DecodedGlb out;
  try {
    const Json& asset = member(doc_, "asset", "the document");
    const std::string version = member(asset, "version", "asset").get<std::string>();
    if (version.rfind("2.", 0) != 0) fail("glTF version " + version + ", not 2.x");
    if (asset.contains("extras")) out.assetExtras = asset["extras"].dump();

    const Json& scenes = member(doc_, "scenes", "the document");
    const std::size_t scene =
        doc_.contains("scene") ? index(doc_, "scene", "the document", scenes.size()) : 0;
    if (scenes.empty()) fail("the document has no scene");
    const Json& roots = member(scenes[scene], "nodes", "scene " + std::to_string(scene));
    if (!roots.is_array() || roots.empty()) fail("scene " + std::to_string(scene) + " has no node");
    const Json& nodes = member(doc_, "nodes", "the document");
    const std::size_t root =
        roots[0].is_number_unsigned() ? roots[0].get<std::size_t>() : nodes.size();
    if (root >= nodes.size()) fail("scene " + std::to_string(scene) + " names a missing node");
    const Json& node = nodes[root];
    out.rootMatrix = nodeMatrix(node);

    const std::string nodeName = "node " + std::to_string(root);
    const Json& meshes = member(doc_, "meshes", "the document");
    const Json& gltfMesh = meshes[index(node, "mesh", nodeName, meshes.size())];
    const Json& primitives = member(gltfMesh, "primitives", "the mesh");
    if (!primitives.is_array() || primitives.empty()) fail("the mesh has no primitive");
    const Json& primitive = primitives[0];
    if (primitive.value("mode", gf::kTriangles) != gf::kTriangles)
      fail("the primitive is not TRIANGLES");

    const Json* draco = nullptr;
    if (primitive.contains("extensions") && primitive["extensions"].contains(gf::kDracoExtension)) {
      draco = &primitive["extensions"][gf::kDracoExtension];
    }
    out.draco = draco != nullptr;
    if (draco) {
      readDraco(*draco, out.mesh);
    } else {
      readPlain(primitive, out.mesh);
    }
  } catch (const Json::exception& e) {
    fail(std::string("the glTF JSON is malformed: ") + e.what());
  }

  const MeshBuffers& m = out.mesh;
  if (m.indices.size() % 3 != 0)
    fail(std::to_string(m.indices.size()) + " indices, not whole triangles");
  for (std::uint32_t i : m.indices) {
    if (i >= m.positions.size()) {
      fail("an index (" + std::to_string(i) + ") is past the " +
           std::to_string(m.positions.size()) + " positions");
    }
  }
  if (!m.normals.empty() && m.normals.size() != m.positions.size()) {
    fail(std::to_string(m.normals.size()) + " normals for " + std::to_string(m.positions.size()) +
         " positions");
  }
  return out;
}

}  // namespace

DecodedGlb decodeGlb(std::string_view bytes, std::string_view name) {
  return GlbReader(bytes, name).read();
}

std::string glbAssetExtras(std::string_view bytes, std::string_view name) {
  return GlbReader(bytes, name).readAssetExtras();
}

}  // namespace tinsmith::encode
