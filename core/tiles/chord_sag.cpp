#include "core/tiles/chord_sag.hpp"

#include <array>
#include <cmath>
#include <vector>

#include "core/encode/frames.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/tile_content.hpp"

namespace tinsmith::tiles {

double chordSagRadius(const GeoReference& geo, const Rect& square) {
  const double width = std::max(square.width(), square.height());
  const double length = std::clamp(width / 8, 1000.0, 20000.0);
  const double half = 0.5 * length;
  constexpr int kPlaces = 5;
  constexpr std::array<double, 4> kAngles{0.0, 0.25 * M_PI, 0.5 * M_PI, 0.75 * M_PI};
  // Each segment's two ends and middle, all taken to the globe at once.
  std::vector<Point3> at;
  at.reserve(3 * kPlaces * kPlaces * kAngles.size());
  for (int j = 0; j < kPlaces; ++j) {
    for (int i = 0; i < kPlaces; ++i) {
      // From a segment's half length inside the square's sides to the same
      // inside the opposite ones.
      const auto along = [&](double from, double to, int k) {
        const double inner = std::min(half, 0.5 * (to - from));
        return from + inner + (to - from - 2 * inner) * k / (kPlaces - 1);
      };
      const Point2 c{along(square.x0, square.x1, i), along(square.y0, square.y1, j)};
      for (const double angle : kAngles) {
        const double dx = half * std::cos(angle), dy = half * std::sin(angle);
        at.insert(at.end(), {Point3{c.x - dx, c.y - dy, 0.0}, Point3{c.x, c.y, 0.0},
                             Point3{c.x + dx, c.y + dy, 0.0}});
      }
    }
  }
  std::vector<encode::Geodetic> g(at.size());
  geo.toGeodetic(at, g);
  // A place off the CRS's domain (a square past a pole, a projection's edge)
  // has no ground to sag below: it is left out.
  const auto onGlobe = [](const encode::Geodetic& p) {
    return std::isfinite(p.lon) && std::isfinite(p.lat) && std::isfinite(p.height) &&
           std::abs(p.lat) <= 90.0;
  };
  double worst = 0.0;  // the largest gap ÷ L²/8R
  for (std::size_t k = 0; k + 2 < g.size(); k += 3) {
    if (!onGlobe(g[k]) || !onGlobe(g[k + 1]) || !onGlobe(g[k + 2])) continue;
    const Point3 a = encode::geodeticToEcef(g[k]), m = encode::geodeticToEcef(g[k + 1]),
                 b = encode::geodeticToEcef(g[k + 2]);
    const double gap =
        std::hypot(m.x - 0.5 * (a.x + b.x), m.y - 0.5 * (a.y + b.y), m.z - 0.5 * (a.z + b.z));
    if (std::isfinite(gap))
      worst = std::max(worst, gap * 8 * kEarthRadiusOfCurvature / (length * length));
  }
  if (worst > 1.01) return kEarthRadiusOfCurvature / (1.05 * worst);
  // A projection that stretches the ground (Mercator far from the equator)
  // draws its segments over shorter chords, which lie nearer the ground:
  // planned with what they do once that is under half the sphere's, with a
  // quarter to spare (the gap grows towards the square's side nearer the
  // equator, which the places stop short of).
  if (worst > 0 && worst < 0.5) return kEarthRadiusOfCurvature / (1.25 * worst);
  return kEarthRadiusOfCurvature;
}

}  // namespace tinsmith::tiles
