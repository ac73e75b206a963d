// Read-only views of a TIN held as TinData or as a Mesh, with one interface,
// for code that reads either (the .tin writer, the summary, the flat-triangle
// analysis) without copying a Mesh into TinData. Vertex and triangle
// numbering are the same in both (Mesh::toTinData keeps them).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

struct TinDataView {
  const TinData& tin;
  [[nodiscard]] const std::string& crs() const { return tin.crs; }
  [[nodiscard]] const std::vector<Point3>& points() const { return tin.vertices; }
  [[nodiscard]] std::size_t triangleCount() const { return tin.triangles.size(); }
  [[nodiscard]] const TinData::Triangle& triangle(std::size_t t) const { return tin.triangles[t]; }
  /// All triangles' vertex indices, three per triangle.
  [[nodiscard]] std::span<const std::uint32_t> cornerIndices() const {
    static_assert(sizeof(TinData::Triangle) == 3 * sizeof(std::uint32_t));
    return {reinterpret_cast<const std::uint32_t*>(tin.triangles.data()), 3 * tin.triangles.size()};
  }
  [[nodiscard]] const std::vector<TinFeature>& features() const { return tin.features; }
};

struct MeshView {
  const Mesh& mesh;
  [[nodiscard]] const std::string& crs() const { return mesh.crs(); }
  [[nodiscard]] const std::vector<Point3>& points() const { return mesh.points(); }
  [[nodiscard]] std::size_t triangleCount() const { return mesh.triangleCount(); }
  [[nodiscard]] TinData::Triangle triangle(std::size_t t) const {
    const auto v = mesh.vertices(TriangleId(static_cast<std::uint32_t>(t)));
    return {v[0].value, v[1].value, v[2].value};
  }
  [[nodiscard]] std::span<const std::uint32_t> cornerIndices() const { return mesh.cornerIndices(); }
  [[nodiscard]] const std::vector<TinFeature>& features() const { return mesh.features(); }
};

}  // namespace tinsmith::ingest
