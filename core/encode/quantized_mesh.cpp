#include "core/encode/quantized_mesh.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "core/base/error.hpp"
#include "core/encode/mesh_buffers.hpp"

namespace tinsmith::encode {

namespace {

static_assert(std::endian::native == std::endian::little,
              "quantized-mesh is little-endian; this writer copies native values");

/// Little-endian appends.
class Writer {
 public:
  template <class T>
  void put(T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out_.append(bytes, sizeof(T));
  }
  void pad(std::size_t alignment) {
    while (out_.size() % alignment != 0) out_.push_back('\0');
  }
  void append(std::string_view bytes) { out_.append(bytes); }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

std::uint16_t zigZag(int value) {
  return static_cast<std::uint16_t>((static_cast<unsigned>(value) << 1) ^
                                    static_cast<unsigned>(value >> 31));
}

void putPoint(Writer& w, const Point3& p) {
  w.put(p.x);
  w.put(p.y);
  w.put(p.z);
}

void check(bool ok, const std::string& what) {
  if (!ok) throw internalError("encodeQuantizedMesh: " + what);
}

constexpr double kWgs84A = 6378137.0, kWgs84B = 6356752.3142451793;

Point3 scaled(const Point3& p) {
  return {p.x / kWgs84A, p.y / kWgs84A, p.z / kWgs84B};
}
double dot(const Point3& a, const Point3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
double norm(const Point3& a) {
  return std::sqrt(dot(a, a));
}
Point3 cross(const Point3& a, const Point3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

}  // namespace

std::string encodeQuantizedMesh(const QuantizedMeshTile& tile) {
  const std::size_t n = tile.u.size();
  check(tile.v.size() == n && tile.height.size() == n, "u, v and height differ in length");
  check(tile.octNormals.empty() || tile.octNormals.size() == n, "one normal a vertex");
  check(n <= 0xffffffffU, "too many vertices");
  for (std::size_t i = 0; i < n; ++i)
    check(
        tile.u[i] <= kQuantizedMax && tile.v[i] <= kQuantizedMax && tile.height[i] <= kQuantizedMax,
        "a quantized value above 32767");
  for (const auto& t : tile.triangles)
    for (const std::uint32_t i : t) check(i < n, "a triangle index out of range");
  for (const auto& edge : tile.edges)
    for (const std::uint32_t i : edge) check(i < n, "an edge index out of range");
  check(!tile.waterMask || tile.waterMask->size() == 1 || tile.waterMask->size() == 256 * 256,
        "a water mask of neither 1 nor 65 536 bytes");

  Writer w;
  putPoint(w, tile.centre);
  w.put(tile.minHeight);
  w.put(tile.maxHeight);
  putPoint(w, tile.sphereCentre);
  w.put(tile.sphereRadius);
  putPoint(w, tile.horizonOcclusion);

  w.put(static_cast<std::uint32_t>(n));
  for (const auto* values : {&tile.u, &tile.v, &tile.height}) {
    int previous = 0;
    for (const std::uint16_t value : *values) {
      w.put(zigZag(static_cast<int>(value) - previous));
      previous = value;
    }
  }

  // CesiumJS reads 32-bit indices past 64 Ki vertices.
  const bool wide = n > 65536;
  auto putIndex = [&](std::uint32_t i) {
    if (wide)
      w.put(i);
    else
      w.put(static_cast<std::uint16_t>(i));
  };
  w.pad(wide ? 4 : 2);
  w.put(static_cast<std::uint32_t>(tile.triangles.size()));
  // High-water mark: each index as its distance below the highest index met
  // so far plus one (0 introduces the next new vertex). An index above that
  // is not encodable: the vertices must come in the order the triangles
  // first use them.
  std::uint32_t highest = 0;
  for (const auto& t : tile.triangles) {
    for (const std::uint32_t i : t) {
      check(i <= highest, "vertices not in the order the triangles first use them");
      putIndex(highest - i);
      if (i == highest) ++highest;
    }
  }
  for (const auto& edge : tile.edges) {
    w.put(static_cast<std::uint32_t>(edge.size()));
    for (const std::uint32_t i : edge) putIndex(i);
  }

  auto extension = [&](std::uint8_t id, std::string_view data) {
    w.put(id);
    w.put(static_cast<std::uint32_t>(data.size()));
    w.append(data);
  };
  if (!tile.octNormals.empty()) {
    std::string data;
    for (const auto& o : tile.octNormals)
      data.append({static_cast<char>(o[0]), static_cast<char>(o[1])});
    extension(1, data);
  }
  if (tile.waterMask)
    extension(2, std::string_view(reinterpret_cast<const char*>(tile.waterMask->data()),
                                  tile.waterMask->size()));
  if (tile.metadata) {
    Writer m;
    m.put(static_cast<std::uint32_t>(tile.metadata->size()));
    m.append(*tile.metadata);
    extension(4, m.take());
  }
  return w.take();
}

QuantizedMeshLayout quantizedMeshLayout(std::string_view bytes) {
  std::size_t at = 0;
  auto need = [&](std::size_t n) {
    if (at > bytes.size() || n > bytes.size() - at)
      throw inputError("a quantized-mesh tile ends early (" + std::to_string(bytes.size()) +
                       " bytes)");
  };
  auto u32 = [&] {
    need(4);
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);
    at += 4;
    return v;
  };
  constexpr std::size_t kHeader = 88;
  need(kHeader);
  at = kHeader;
  const std::uint32_t n = u32();
  need(std::size_t{6} * n);
  at += std::size_t{6} * n;
  const std::size_t width = n > 65536 ? 4 : 2;
  at = (at + width - 1) / width * width;
  const std::uint32_t triangles = u32();
  need(std::size_t{3} * triangles * width);
  at += std::size_t{3} * triangles * width;
  for (int e = 0; e < 4; ++e) {
    const std::uint32_t count = u32();
    need(std::size_t{count} * width);
    at += std::size_t{count} * width;
  }
  QuantizedMeshLayout layout;
  layout.extensionsAt = at;
  while (at < bytes.size()) {
    need(5);
    const auto id = static_cast<std::uint8_t>(bytes[at]);
    ++at;
    const std::uint32_t length = u32();
    need(length);
    layout.extensions.push_back({id, at, length});
    at += length;
  }
  return layout;
}

std::string withExtensions(std::string_view bytes, std::span<const std::uint8_t> keep) {
  const QuantizedMeshLayout layout = quantizedMeshLayout(bytes);
  std::string out(bytes.substr(0, layout.extensionsAt));
  for (const auto& e : layout.extensions)
    if (std::find(keep.begin(), keep.end(), e.id) != keep.end())
      out.append(bytes.substr(e.offset - 5, e.length + 5));
  return out;
}

std::optional<std::string> quantizedMeshMetadata(std::string_view bytes) {
  for (const auto& e : quantizedMeshLayout(bytes).extensions) {
    if (e.id != kMetadata || e.length < 4) continue;
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + e.offset, 4);
    if (length > e.length - 4)
      throw inputError("a quantized-mesh tile's metadata runs past its end");
    return std::string(bytes.substr(e.offset + 4, length));
  }
  return std::nullopt;
}

std::string withMetadata(std::string_view bytes, std::string_view json) {
  const QuantizedMeshLayout layout = quantizedMeshLayout(bytes);
  std::string out(bytes.substr(0, layout.extensionsAt));
  for (const auto& e : layout.extensions)
    if (e.id != kMetadata) out.append(bytes.substr(e.offset - 5, e.length + 5));
  Writer w;
  w.put(kMetadata);
  w.put(static_cast<std::uint32_t>(json.size() + 4));
  w.put(static_cast<std::uint32_t>(json.size()));
  w.append(json);
  out.append(w.take());
  return out;
}

void setBoundingVolumes(QuantizedMeshTile& tile, std::span<const Point3> ecef) {
  if (ecef.empty()) throw internalError("setBoundingVolumes: a tile with no positions");
  Point3 lo = ecef[0], hi = ecef[0];
  for (const Point3& p : ecef) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Point3 centre{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)};
  double radius = 0;
  for (const Point3& p : ecef)
    radius = std::max(radius, norm({p.x - centre.x, p.y - centre.y, p.z - centre.z}));
  tile.centre = centre;
  tile.sphereCentre = centre;
  tile.sphereRadius = radius;
  tile.horizonOcclusion = horizonOcclusionPoint(ecef, centre);
}

QuantizedTerrain quantizeTerrain(const GeodeticMesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  if (n == 0) throw internalError("quantizeTerrain: a tile with no vertices");
  if (!(mesh.east > mesh.west && mesh.north > mesh.south))
    throw internalError("quantizeTerrain: empty tile bounds");
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const Geodetic& g : mesh.vertices) {
    lo = std::min(lo, g.height);
    hi = std::max(hi, g.height);
  }
  // The header's range is float: take the floats around the range, so that
  // every height lies within it as a client reads it.
  auto minHeight = static_cast<float>(lo), maxHeight = static_cast<float>(hi);
  if (minHeight > lo) minHeight = std::nextafter(minHeight, -HUGE_VALF);
  if (maxHeight < hi) maxHeight = std::nextafter(maxHeight, HUGE_VALF);
  if (maxHeight == minHeight) maxHeight = std::nextafter(maxHeight, HUGE_VALF);
  const double h0 = minHeight, h1 = maxHeight;
  auto quantize = [](double value, double a, double b) {
    return static_cast<std::uint16_t>(
        std::lround(std::clamp((value - a) / (b - a), 0.0, 1.0) * kQuantizedMax));
  };
  auto expand = [](std::uint16_t q, double a, double b) { return a + (b - a) * q / kQuantizedMax; };
  QuantizedMeshTile raw;
  raw.minHeight = minHeight;
  raw.maxHeight = maxHeight;
  raw.triangles = mesh.triangles;
  QuantizedTerrain out;
  out.decoded.resize(n);
  std::vector<Point3> exact(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Geodetic& g = mesh.vertices[i];
    raw.u.push_back(quantize(g.lon, mesh.west, mesh.east));
    raw.v.push_back(quantize(g.lat, mesh.south, mesh.north));
    raw.height.push_back(quantize(g.height, h0, h1));
    exact[i] = geodeticToEcef(g);
    out.decoded[i] =
        geodeticToEcef({expand(raw.u[i], mesh.west, mesh.east),
                        expand(raw.v[i], mesh.south, mesh.north), expand(raw.height[i], h0, h1)});
    out.maxMove =
        std::max(out.maxMove, norm({out.decoded[i].x - exact[i].x, out.decoded[i].y - exact[i].y,
                                    out.decoded[i].z - exact[i].z}));
    const auto v = static_cast<std::uint32_t>(i);
    if (raw.u[i] == 0) raw.edges[0].push_back(v);
    if (raw.v[i] == 0) raw.edges[1].push_back(v);
    if (raw.u[i] == kQuantizedMax) raw.edges[2].push_back(v);
    if (raw.v[i] == kQuantizedMax) raw.edges[3].push_back(v);
  }
  const std::span<const std::array<std::uint32_t, 3>> shading(
      mesh.triangles.data(), std::min(mesh.shadingTriangles, mesh.triangles.size()));
  const auto normals = areaWeightedNormals(exact, shading);
  for (std::size_t i = 0; i < n; ++i) {
    // A vertex no triangle uses: the radial direction, about up.
    const bool none = normals[i].x == 0 && normals[i].y == 0 && normals[i].z == 0;
    raw.octNormals.push_back(octEncode(none ? exact[i] : normals[i]));
  }
  setBoundingVolumes(raw, out.decoded);
  out.tile = inFirstUseOrder(raw, &out.index);
  return out;
}

QuantizedMeshTile inFirstUseOrder(const QuantizedMeshTile& tile,
                                  std::vector<std::uint32_t>* renumbered) {
  const std::size_t n = tile.u.size();
  constexpr std::uint32_t kUnset = 0xffffffffU;
  std::vector<std::uint32_t> renumber(n, kUnset), order;
  order.reserve(n);
  for (const auto& t : tile.triangles)
    for (const std::uint32_t i : t)
      if (i < n && renumber[i] == kUnset) {
        renumber[i] = static_cast<std::uint32_t>(order.size());
        order.push_back(i);
      }
  for (std::uint32_t i = 0; i < n; ++i)
    if (renumber[i] == kUnset) {
      renumber[i] = static_cast<std::uint32_t>(order.size());
      order.push_back(i);
    }
  QuantizedMeshTile out = tile;
  for (std::size_t k = 0; k < n && k < tile.v.size() && k < tile.height.size(); ++k) {
    out.u[k] = tile.u[order[k]];
    out.v[k] = tile.v[order[k]];
    out.height[k] = tile.height[order[k]];
    if (tile.octNormals.size() == n) out.octNormals[k] = tile.octNormals[order[k]];
  }
  for (auto& t : out.triangles)
    for (auto& i : t) i = i < n ? renumber[i] : i;
  for (auto& edge : out.edges)
    for (auto& i : edge) i = i < n ? renumber[i] : i;
  if (renumbered) *renumbered = std::move(renumber);
  return out;
}

std::array<std::uint8_t, 2> octEncode(const Point3& normal) {
  const double l1 = std::abs(normal.x) + std::abs(normal.y) + std::abs(normal.z);
  double x = l1 > 0 ? normal.x / l1 : 0.0, y = l1 > 0 ? normal.y / l1 : 0.0;
  if (l1 > 0 && normal.z < 0) {
    const double ox = x;
    x = (1.0 - std::abs(y)) * (ox >= 0 ? 1.0 : -1.0);
    y = (1.0 - std::abs(ox)) * (y >= 0 ? 1.0 : -1.0);
  }
  auto snorm = [](double value) {
    return static_cast<std::uint8_t>(
        std::lround((std::clamp(value, -1.0, 1.0) * 0.5 + 0.5) * 255.0));
  };
  return {snorm(x), snorm(y)};
}

Point3 octDecode(std::array<std::uint8_t, 2> oct) {
  double x = oct[0] / 255.0 * 2.0 - 1.0, y = oct[1] / 255.0 * 2.0 - 1.0;
  const double z = 1.0 - (std::abs(x) + std::abs(y));
  if (z < 0) {
    const double ox = x;
    x = (1.0 - std::abs(y)) * (ox >= 0 ? 1.0 : -1.0);
    y = (1.0 - std::abs(ox)) * (y >= 0 ? 1.0 : -1.0);
  }
  const double length = std::sqrt(x * x + y * y + z * z);
  return {x / length, y / length, z / length};
}

Point3 horizonOcclusionPoint(std::span<const Point3> ecef, const Point3& direction) {
  Point3 d = scaled(direction);
  const double dn = norm(d);
  if (!(dn > 0)) return {0, 0, 0};
  d = {d.x / dn, d.y / dn, d.z / dn};
  double farthest = 0.0;
  for (const Point3& p : ecef) {
    const Point3 s = scaled(p);
    const double m2 = dot(s, s);
    const double m = std::sqrt(m2);
    if (!(m > 0)) continue;
    const Point3 toPoint{s.x / m, s.y / m, s.z / m};
    // Below the ellipsoid counts as on it.
    const double magnitude = std::max(1.0, m);
    const double cosAlpha = dot(toPoint, d);
    const double sinAlpha = norm(cross(toPoint, d));
    const double cosBeta = 1.0 / magnitude;
    const double sinBeta = std::sqrt(std::max(1.0, m2) - 1.0) * cosBeta;
    const double denominator = cosAlpha * cosBeta - sinAlpha * sinBeta;
    // No point on the ray sees this one over the horizon (a tile of a
    // hemisphere): far out, where nothing is culled.
    if (!(denominator > 0)) return {d.x * 1e6, d.y * 1e6, d.z * 1e6};
    farthest = std::max(farthest, 1.0 / denominator);
  }
  return {d.x * farthest, d.y * farthest, d.z * farthest};
}

}  // namespace tinsmith::encode
