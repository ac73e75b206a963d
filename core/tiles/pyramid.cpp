#include "core/tiles/pyramid.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "core/base/error.hpp"

namespace tinsmith::tiles {

std::string TileId::name() const {
  return std::to_string(z) + "/" + std::to_string(x) + "/" + std::to_string(y);
}

TileId parseTileId(const std::string& text, const std::string& what) {
  TileId t;
  long long parts[3] = {0, 0, 0};
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 3; ++i) {
    auto [next, ec] = std::from_chars(p, end, parts[i]);
    if (ec != std::errc() || next == p || (i < 2 && (next == end || *next != '/'))) {
      throw usageError(what + " '" + text + "' is not a tile id", "write it as Z/X/Y, e.g. 3/2/5");
    }
    p = next + (i < 2 ? 1 : 0);
  }
  if (p != end)
    throw usageError(what + " '" + text + "' is not a tile id", "write it as Z/X/Y, e.g. 3/2/5");
  if (parts[0] < 0 || parts[0] > 30 || parts[1] < 0 || parts[2] < 0 ||
      parts[1] >= (1LL << parts[0]) || parts[2] >= (1LL << parts[0])) {
    throw usageError(what + " '" + text + "' is outside the pyramid",
                     "zoom z has tiles x, y in 0 .. 2^z - 1, z at most 30");
  }
  t.z = static_cast<int>(parts[0]);
  t.x = static_cast<std::uint32_t>(parts[1]);
  t.y = static_cast<std::uint32_t>(parts[2]);
  return t;
}

double PyramidGeometry::lineX(int z, std::uint64_t i) const {
  // i / 2^z is exact in binary floating point (i < 2^31), so the same line at
  // any zoom gives the same double.
  return origin_.x + std::ldexp(static_cast<double>(i), -z) * size_;
}

double PyramidGeometry::lineY(int z, std::uint64_t j) const {
  return origin_.y + std::ldexp(static_cast<double>(j), -z) * size_;
}

Point2 PyramidGeometry::snapToLines(int z, Point2 p, double near) const {
  const double n = std::ldexp(1.0, z);
  auto nearest = [&](double v, double origin) {
    return static_cast<std::uint64_t>(std::clamp(std::round((v - origin) / size_ * n), 0.0, n));
  };
  const double gx = lineX(z, nearest(p.x, origin_.x)), gy = lineY(z, nearest(p.y, origin_.y));
  return {std::abs(p.x - gx) <= near ? gx : p.x, std::abs(p.y - gy) <= near ? gy : p.y};
}

}  // namespace tinsmith::tiles
