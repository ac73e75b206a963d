// Float buffers from double triangles; see mesh_buffers.hpp.
#include "core/encode/mesh_buffers.hpp"

#include <algorithm>
#include <cmath>

namespace tinsmith::encode {
namespace {

Point3 sub(const Point3& a, const Point3& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Point3 cross(const Point3& a, const Point3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

}  // namespace

Box3 boundingBox(std::span<const Point3> points) {
  if (points.empty()) return {};
  Box3 b{points.front(), points.front()};
  for (const auto& p : points) {
    b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
    b.hi = {std::max(b.hi.x, p.x), std::max(b.hi.y, p.y), std::max(b.hi.z, p.z)};
  }
  return b;
}

std::vector<Point3> areaWeightedNormals(std::span<const Point3> points,
                                        std::span<const Triangle> triangles) {
  std::vector<Point3> normals(points.size(), Point3{0, 0, 0});
  for (const auto& t : triangles) {
    const Point3 n = cross(sub(points[t[1]], points[t[0]]), sub(points[t[2]], points[t[0]]));
    for (auto v : t) normals[v] = {normals[v].x + n.x, normals[v].y + n.y, normals[v].z + n.z};
  }
  return normals;
}

MeshBuffers meshBuffersAround(std::span<const Point3> points, std::span<const Point3> normals,
                              std::span<const Triangle> triangles, const Point3& origin) {
  MeshBuffers buffers;
  buffers.positions.reserve(points.size());
  buffers.normals.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    buffers.positions.push_back({static_cast<float>(points[i].x - origin.x),
                                 static_cast<float>(points[i].y - origin.y),
                                 static_cast<float>(points[i].z - origin.z)});
    const Point3& n = normals[i];
    const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (len > 0) {
      buffers.normals.push_back({static_cast<float>(n.x / len), static_cast<float>(n.y / len),
                                 static_cast<float>(n.z / len)});
    } else {
      buffers.normals.push_back({0.0f, 0.0f, 1.0f});
    }
  }
  buffers.indices.reserve(triangles.size() * 3);
  for (const auto& t : triangles) buffers.indices.insert(buffers.indices.end(), t.begin(), t.end());
  return buffers;
}

double floatRoundingBound(std::span<const Point3> points, const Point3& origin) {
  double farthest = 0.0;
  for (const auto& p : points) {
    const Point3 d = sub(p, origin);
    farthest = std::max(farthest, std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z));
  }
  return std::ldexp(farthest, -24);
}

}  // namespace tinsmith::encode
