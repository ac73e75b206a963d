#include "server/app/elevation.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "core/base/error.hpp"

namespace tinsmith::server {

namespace {

using Json = nlohmann::ordered_json;

double requireNumber(const RequestTarget& query, const std::string& name) {
  const auto text = query.parameter(name);
  if (!text) throw ParameterError(name, "the parameter " + name + " is missing");
  const auto value = parseFiniteDouble(*text);
  if (!value) throw ParameterError(name, "the parameter " + name + " must be a finite number");
  return *value;
}

void checkLonLat(double lon, double lat, const std::string& where) {
  if (lon < -180 || lon > 180)
    throw ParameterError(where, where + ": longitude must be within [-180, 180] degrees");
  if (lat < -90 || lat > 90)
    throw ParameterError(where, where + ": latitude must be within [-90, 90] degrees");
}

/// A point asked for, in the project CRS, with the lon, lat it came from.
struct AskedPoint {
  Point2 xy;
  std::optional<Point2> lonlat;
};

Point2 project(const Tileset& tileset, double lon, double lat, const std::string& where) {
  checkLonLat(lon, lat, where);
  try {
    return tileset.fromLonLat(lon, lat);
  } catch (const std::exception& e) {
    throw ParameterError(where, where + ": " + e.what());
  }
}

Json zValue(const Tileset& tileset, Point2 p) {
  const auto s = tileset.surface().sample(p);
  return s ? Json(s->z) : Json(nullptr);
}

/// The direction the slope faces (downhill), degrees clockwise from the
/// project CRS's grid north in [0, 360); null where the plane is level.
Json aspectOf(const Point3& normal) {
  if (normal.x == 0 && normal.y == 0) return nullptr;
  // normal ∝ (−∂z/∂x, −∂z/∂y, 1): its x, y point downhill.
  double degrees = std::atan2(normal.x, normal.y) * 180 / std::numbers::pi;
  if (degrees < 0) degrees += 360;
  return degrees >= 360 ? 0.0 : degrees;
}

Json pointRecord(const Tileset& tileset, const AskedPoint& p) {
  Json j;
  j["x"] = p.xy.x;
  j["y"] = p.xy.y;
  if (p.lonlat) {
    j["lon"] = p.lonlat->x;
    j["lat"] = p.lonlat->y;
  }
  const auto s = tileset.surface().sample(p.xy);
  if (!s) {
    j["z"] = nullptr;
    return j;
  }
  j["z"] = s->z;
  j["slope"] = s->slopeDegrees;
  j["aspect"] = aspectOf(s->normal);
  // The height the tiles place this point at (geoid applied), for comparing
  // with what a 3-D viewer picks; left out when the store's CRS cannot be
  // converted.
  try {
    const Point3 point{p.xy.x, p.xy.y, s->z};
    encode::Geodetic g;
    tileset.toGeodetic({&point, 1}, {&g, 1});
    if (std::isfinite(g.height)) j["ellipsoidalHeight"] = g.height;
  } catch (const Error&) {
  }
  return j;
}

bool lonLatCrs(const nlohmann::json& body) {
  if (!body.contains("crs")) return false;
  if (body["crs"] == "lonlat") return true;
  if (body["crs"] == "project") return false;
  throw ParameterError("crs", "crs must be \"project\" or \"lonlat\"");
}

nlohmann::json parseBody(const std::string& body) {
  auto j = nlohmann::json::parse(body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw ParameterError("body", "the body must be a JSON object");
  return j;
}

/// [[a, b], …] of `name` in `body` into points (lon, lat when `lonlat`).
std::vector<AskedPoint> pointsOf(const Tileset& tileset, const nlohmann::json& body,
                                 const std::string& name, bool lonlat) {
  if (!body.contains(name) || !body[name].is_array())
    throw ParameterError(name, name + " must be an array of [x, y] pairs");
  const auto& list = body[name];
  if (list.size() > kMaxPoints)
    throw ParameterError(name, name + " has more than " + std::to_string(kMaxPoints) + " points");
  std::vector<AskedPoint> out;
  out.reserve(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    const auto& p = list[i];
    const std::string where = name + "[" + std::to_string(i) + "]";
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
      throw ParameterError(where, where + " must be [x, y], two numbers");
    const double a = p[0].get<double>(), b = p[1].get<double>();
    if (!std::isfinite(a) || !std::isfinite(b))
      throw ParameterError(where, where + " must be finite numbers");
    if (lonlat)
      out.push_back({project(tileset, a, b, where), Point2{a, b}});
    else
      out.push_back({{a, b}, std::nullopt});
  }
  return out;
}

/// "a,b;a,b;…" into points.
std::vector<AskedPoint> pointsOfText(const Tileset& tileset, std::string_view text,
                                     const std::string& name, bool lonlat) {
  nlohmann::json list = nlohmann::json::array();
  while (!text.empty()) {
    const std::size_t semi = text.find(';');
    const std::string_view pair = text.substr(0, semi);
    const std::size_t comma = pair.find(',');
    const auto a = parseFiniteDouble(pair.substr(0, comma));
    const auto b = comma == std::string_view::npos ? std::nullopt
                                                   : parseFiniteDouble(pair.substr(comma + 1));
    if (!a || !b)
      throw ParameterError(name, name + " must be \"a,b;a,b;…\": point " +
                                     std::to_string(list.size()) + " is not two numbers");
    list.push_back({*a, *b});
    if (list.size() > kMaxPoints) break;
    text = semi == std::string_view::npos ? std::string_view{} : text.substr(semi + 1);
  }
  return pointsOf(tileset, nlohmann::json{{name, list}}, name, lonlat);
}

Json profileOf(const Tileset& tileset, const std::vector<AskedPoint>& line,
               std::optional<double> spacing, const std::string& lineName) {
  if (line.size() < 2) throw ParameterError(lineName, lineName + " needs at least two points");
  double length = 0;
  for (std::size_t i = 1; i < line.size(); ++i)
    length += std::hypot(line[i].xy.x - line[i - 1].xy.x, line[i].xy.y - line[i - 1].xy.y);
  const double step = spacing.value_or(length / 256);
  if (spacing && !(*spacing > 0)) throw ParameterError("spacing", "spacing must be positive");
  const double estimate = step > 0 ? length / step + static_cast<double>(line.size()) : 0;
  if (estimate > static_cast<double>(kMaxPoints))
    throw ParameterError("spacing", "spacing gives more than " + std::to_string(kMaxPoints) +
                                        " samples; make it larger");
  Json samples = Json::array();
  const auto add = [&](double distance, Point2 p) {
    Json s;
    s["distance"] = distance;
    s["x"] = p.x;
    s["y"] = p.y;
    s["z"] = zValue(tileset, p);
    samples.push_back(std::move(s));
  };
  double start = 0;  // distance of the current segment's first vertex
  add(0, line[0].xy);
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Point2 a = line[i - 1].xy, b = line[i].xy;
    const double segment = std::hypot(b.x - a.x, b.y - a.y);
    if (step > 0) {
      for (double d = std::floor(start / step + 1) * step; d < start + segment; d += step) {
        const double t = (d - start) / segment;
        add(d, {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
      }
    }
    start += segment;
    add(start, b);
  }
  Json out;
  out["crs"] = tileset.crs();
  out["length"] = length;
  out["spacing"] = step;
  out["samples"] = std::move(samples);
  return out;
}

}  // namespace

Json elevationAt(const Tileset& tileset, const RequestTarget& query) {
  const bool xy = query.parameter("x") || query.parameter("y");
  const bool ll = query.parameter("lon") || query.parameter("lat");
  if (xy && ll) throw ParameterError("lon", "give x and y, or lon and lat, not both");
  if (!xy && !ll)
    throw ParameterError("x", "give x and y (project CRS) or lon and lat (WGS84 degrees)");
  if (xy) return pointRecord(tileset, {{requireNumber(query, "x"), requireNumber(query, "y")}, {}});
  const double lon = requireNumber(query, "lon"), lat = requireNumber(query, "lat");
  return pointRecord(tileset, {project(tileset, lon, lat, "lon"), Point2{lon, lat}});
}

Json elevationBatch(const Tileset& tileset, const std::string& text) {
  const auto body = parseBody(text);
  const bool lonlat = lonLatCrs(body);
  Json points = Json::array();
  for (const auto& p : pointsOf(tileset, body, "points", lonlat)) points.push_back(pointRecord(tileset, p));
  Json out;
  out["crs"] = tileset.crs();
  out["points"] = std::move(points);
  return out;
}

Json profileAlong(const Tileset& tileset, const RequestTarget& query) {
  const auto line = query.parameter("line");
  const auto lonlat = query.parameter("lonlat");
  if (line && lonlat) throw ParameterError("lonlat", "give line or lonlat, not both");
  if (!line && !lonlat)
    throw ParameterError("line", "give line=x,y;x,y;… (project CRS) or lonlat=lon,lat;…");
  std::optional<double> spacing;
  if (query.parameter("spacing")) spacing = requireNumber(query, "spacing");
  const std::string name = line ? "line" : "lonlat";
  return profileOf(tileset, pointsOfText(tileset, line ? *line : *lonlat, name, !line), spacing, name);
}

Json profileBatch(const Tileset& tileset, const std::string& text) {
  const auto body = parseBody(text);
  std::optional<double> spacing;
  if (body.contains("spacing")) {
    if (!body["spacing"].is_number()) throw ParameterError("spacing", "spacing must be a number");
    spacing = body["spacing"].get<double>();
  }
  return profileOf(tileset, pointsOf(tileset, body, "line", lonLatCrs(body)), spacing, "line");
}

}  // namespace tinsmith::server
