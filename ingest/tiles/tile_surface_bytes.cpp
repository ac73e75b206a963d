#include "ingest/tiles/tile_surface_bytes.hpp"

#include <cmath>
#include <cstdint>

#include "core/base/error.hpp"
#include "ingest/base/le_bytes.hpp"

namespace tinsmith::ingest {

namespace {

constexpr std::string_view kMagic = "TSURFv01";

}  // namespace

std::string tileSurfaceKey(const tiles::TileId& id) {
  return "tinsmith/surfaces/" + id.name();
}

std::string encodeTileSurface(const tiles::TileSurface& s) {
  if (s.heldEdges.size() != s.triangles.size() || s.riverEdges.size() != s.triangles.size() ||
      s.flags.size() != s.vertices.size())
    throw internalError("encodeTileSurface: tile " + s.id.name() + " lacks its flags or edges");
  LeWriter w;
  w.bytes.reserve(kMagic.size() + 72 + 26 * s.vertices.size() + 14 * s.triangles.size());
  w.bytes += kMagic;
  w.put(static_cast<std::uint32_t>(s.id.z));
  w.put(s.id.x);
  w.put(s.id.y);
  for (const double v : {s.bounds.x0, s.bounds.y0, s.bounds.x1, s.bounds.y1, s.error, s.tolerance})
    w.put(v);
  w.put(static_cast<std::uint64_t>(s.vertices.size()));
  w.put(static_cast<std::uint64_t>(s.triangles.size()));
  for (const Point3& p : s.vertices) {
    w.put(p.x);
    w.put(p.y);
    w.put(p.z);
  }
  for (const auto& t : s.triangles)
    for (const std::uint32_t c : t) w.put(c);
  for (const auto bits : s.heldEdges) w.put(bits);
  for (const auto bits : s.riverEdges) w.put(bits);
  for (const auto bits : s.flags) w.put(bits);
  return std::move(w.bytes);
}

tiles::TileSurface decodeTileSurface(std::string_view bytes, const std::string& where) {
  const LeReader::Fail fail = [&where](const std::string& why) {
    throw inputError("the tile surface " + where + " is not one tinsmith writes: " + why, {},
                     "build its shard again");
  };
  LeReader r(bytes, fail);
  if (r.take(kMagic.size()) != kMagic) r.fail("it does not start with " + std::string(kMagic));
  tiles::TileSurface s;
  const auto z = r.get<std::uint32_t>();
  if (z > 30) r.fail("its zoom is " + std::to_string(z));
  s.id = {static_cast<int>(z), r.get<std::uint32_t>(), r.get<std::uint32_t>()};
  if (s.id.x >> z || s.id.y >> z) r.fail("its tile " + s.id.name() + " is outside its zoom");
  s.bounds.x0 = r.get<double>();
  s.bounds.y0 = r.get<double>();
  s.bounds.x1 = r.get<double>();
  s.bounds.y1 = r.get<double>();
  s.error = r.get<double>();
  s.tolerance = r.get<double>();
  if (!(s.error >= 0) || !std::isfinite(s.error) || !(s.tolerance >= 0) ||
      !std::isfinite(s.tolerance))
    r.fail("its error is " + std::to_string(s.error) + " and tolerance " +
           std::to_string(s.tolerance) + " m");
  const std::size_t nv = r.get<std::uint64_t>();
  const std::size_t nt = r.get<std::uint64_t>();
  // 25 bytes a vertex (x y z, flags), 14 a triangle (corners, held, river).
  if (nv > bytes.size() / 25 || nt > bytes.size() / 14) r.fail("it ends early");
  r.need(25 * nv + 14 * nt);
  s.vertices.resize(nv);
  for (Point3& p : s.vertices) {
    p = {r.get<double>(), r.get<double>(), r.get<double>()};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      r.fail("a vertex is not finite");
  }
  s.triangles.resize(nt);
  for (auto& t : s.triangles) {
    for (auto& c : t) {
      c = r.get<std::uint32_t>();
      if (c >= nv) r.fail("a triangle's corner " + std::to_string(c) + " is no vertex");
    }
  }
  // Three edge bits a triangle, a river's among its held ones; six flag
  // bits a vertex.
  s.heldEdges.resize(nt);
  for (auto& bits : s.heldEdges)
    if ((bits = r.get<std::uint8_t>()) > 7)
      r.fail("a triangle's held edges are " + std::to_string(bits));
  s.riverEdges.resize(nt);
  for (std::size_t t = 0; t < nt; ++t)
    if ((s.riverEdges[t] = r.get<std::uint8_t>()) & ~s.heldEdges[t])
      r.fail("a triangle's river edges are not among its held ones");
  s.flags.resize(nv);
  for (auto& bits : s.flags)
    if ((bits = r.get<std::uint8_t>()) > 0x3f)
      r.fail("a vertex's flags are " + std::to_string(bits));
  if (!r.atEnd()) r.fail("more bytes follow it");
  return s;
}

}  // namespace tinsmith::ingest
