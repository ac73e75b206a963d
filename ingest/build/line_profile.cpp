#include "ingest/build/line_profile.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/base/error.hpp"

namespace tinsmith::ingest {

namespace {

double dist2d(const Point3& a, const Point3& b) {
  return std::hypot(b.x - a.x, b.y - a.y);
}

std::vector<double> arcLength(const std::vector<Point3>& line) {
  std::vector<double> s(line.size(), 0.0);
  for (std::size_t i = 1; i < line.size(); ++i) s[i] = s[i - 1] + dist2d(line[i - 1], line[i]);
  return s;
}

}  // namespace

void densify(std::vector<Point3>& line, double maxSpacing) {
  if (!(maxSpacing > 0) || line.size() < 2) return;
  std::vector<Point3> out;
  out.reserve(line.size());
  out.push_back(line.front());
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Point3& a = line[i - 1];
    const Point3& b = line[i];
    const double len = dist2d(a, b);
    const auto pieces = static_cast<std::size_t>(std::ceil(len / maxSpacing));
    for (std::size_t k = 1; k < pieces; ++k) {
      const double t = static_cast<double>(k) / static_cast<double>(pieces);
      out.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)});
    }
    out.push_back(b);
  }
  line = std::move(out);
}

DrapeResult drape(std::vector<Point3>& line, const ZLookup& surface, const std::string& what) {
  DrapeResult result;
  std::vector<char> known(line.size(), 0);
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (const auto z = surface(line[i].x, line[i].y)) {
      line[i].z = *z;
      known[i] = 1;
      ++result.draped;
    }
  }
  result.outside = line.size() - result.draped;
  if (result.draped == 0 && !line.empty())
    throw geometryError(what + " lies entirely outside the surface built from the other layers", {},
                        "give it 3D coordinates or a 'z' attribute, or check its CRS");
  if (result.outside == 0) return result;
  const auto s = arcLength(line);
  std::size_t prev = line.size();  // last known index before i
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (known[i]) {
      prev = i;
      continue;
    }
    std::size_t next = i + 1;
    while (next < line.size() && !known[next]) ++next;
    if (prev == line.size()) {
      line[i].z = line[next].z;
    } else if (next == line.size()) {
      line[i].z = line[prev].z;
    } else {
      const double span = s[next] - s[prev];
      const double t = span > 0 ? (s[i] - s[prev]) / span : 0.5;
      line[i].z = line[prev].z + t * (line[next].z - line[prev].z);
    }
  }
  return result;
}

std::size_t reconcileConfluences(std::vector<std::vector<Point3>*> rivers,
                                 const std::vector<bool>& reversed) {
  std::size_t lowered = 0;
  for (bool changed = true; changed;) {
    changed = false;
    // The lowest z of the river ends at each x, y.
    std::map<std::pair<double, double>, double> lowest;
    for (const auto* line : rivers) {
      if (line->empty()) continue;
      for (const Point3* p : {&line->front(), &line->back()}) {
        auto [it, fresh] = lowest.try_emplace({p->x, p->y}, p->z);
        if (!fresh) it->second = std::min(it->second, p->z);
      }
    }
    for (std::size_t i = 0; i < rivers.size(); ++i) {
      auto& line = *rivers[i];
      const std::size_t n = line.size();
      if (n == 0) continue;
      auto at = [&](std::size_t k) -> Point3& { return reversed[i] ? line[n - 1 - k] : line[k]; };
      for (std::size_t k = 0; k < n; ++k) {
        double target = at(k).z;
        if (k > 0) target = std::min(target, at(k - 1).z);
        if (k == 0 || k == n - 1) target = std::min(target, lowest.at({at(k).x, at(k).y}));
        if (target < at(k).z) {
          at(k).z = target;
          ++lowered;
          changed = true;
        }
      }
    }
  }
  return lowered;
}

DescentResult enforceDescent(std::vector<Point3>& line) {
  DescentResult result;
  const std::size_t n = line.size();
  if (n < 2) return result;
  result.reversed = line.back().z > line.front().z;
  // Work in flow order: index k is the k-th vertex downstream.
  auto at = [&](std::size_t k) -> Point3& { return result.reversed ? line[n - 1 - k] : line[k]; };
  // Weight of a vertex: half the length of its adjacent segments, so a
  // densely digitised stretch does not outvote a sparse one; a small floor
  // keeps coincident vertices from having no say.
  std::vector<double> w(n, 0.0);
  double total = 0.0;
  for (std::size_t k = 1; k < n; ++k) {
    const double half = 0.5 * dist2d(at(k - 1), at(k));
    w[k - 1] += half;
    w[k] += half;
    total += 2 * half;
  }
  const double floor = total > 0 ? total * 1e-9 : 1.0;
  for (auto& x : w) x = std::max(x, floor);

  // Pool adjacent violators for a non-increasing fit.
  struct Block {
    double mean;
    double weight;
    std::size_t count;
  };
  std::vector<Block> blocks;
  blocks.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    blocks.push_back({at(k).z, w[k], 1});
    while (blocks.size() > 1 && blocks[blocks.size() - 2].mean < blocks.back().mean) {
      Block b = blocks.back();
      blocks.pop_back();
      Block& a = blocks.back();
      const double weight = a.weight + b.weight;
      a.mean = (a.mean * a.weight + b.mean * b.weight) / weight;
      a.weight = weight;
      a.count += b.count;
    }
  }
  std::size_t k = 0;
  for (const Block& b : blocks) {
    for (std::size_t j = 0; j < b.count; ++j, ++k) {
      Point3& p = at(k);
      const double change = std::abs(p.z - b.mean);
      if (p.z != b.mean) {
        ++result.adjusted;
        if (change > result.maxAdjustment) {
          result.maxAdjustment = change;
          result.maxAt = p.xy();
          result.maxFrom = p.z;
          result.maxTo = b.mean;
        }
      }
      p.z = b.mean;
    }
  }
  // Averages of a non-increasing block sequence are non-increasing, but
  // rounding could leave a 1-ulp rise between blocks: clamp it away.
  for (std::size_t j = 1; j < n; ++j)
    if (at(j).z > at(j - 1).z) at(j).z = at(j - 1).z;
  return result;
}

bool descends(const std::vector<Point3>& line, double tolerance) {
  if (line.size() < 2) return true;
  const bool reversed = line.back().z > line.front().z;
  for (std::size_t i = 1; i < line.size(); ++i) {
    const double up = reversed ? line[i - 1].z - line[i].z : line[i].z - line[i - 1].z;
    if (up > tolerance) return false;
  }
  return true;
}

SmoothResult smoothAlongLength(std::vector<Point3>& line, double window, double spikeThreshold) {
  SmoothResult result;
  const std::size_t n = line.size();
  if (n < 3) return result;
  std::vector<double> original(n);
  for (std::size_t i = 0; i < n; ++i) original[i] = line[i].z;

  std::vector<double> z = original;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double a = original[i - 1], b = original[i], c = original[i + 1];
    const double lo = std::min(a, c), hi = std::max(a, c);
    if (b > hi + spikeThreshold || b < lo - spikeThreshold) {
      z[i] = std::clamp(b, lo, hi);  // the median of (a, b, c)
      ++result.spikesRemoved;
    }
  }
  if (window > 0) {
    const auto s = arcLength(line);
    const double half = 0.5 * window;
    std::vector<double> smoothed = z;
    std::size_t lo = 0, hi = 0;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      while (s[i] - s[lo] > half) ++lo;
      while (hi + 1 < n && s[hi + 1] - s[i] <= half) ++hi;
      double sum = 0, weight = 0;
      for (std::size_t j = lo; j <= hi; ++j) {
        const double wj = 1.0 - std::abs(s[j] - s[i]) / (half * 1.000001);
        sum += wj * z[j];
        weight += wj;
      }
      if (weight > 0) smoothed[i] = sum / weight;
    }
    z = std::move(smoothed);
  }
  for (std::size_t i = 0; i < n; ++i) {
    result.maxChange = std::max(result.maxChange, std::abs(z[i] - original[i]));
    line[i].z = z[i];
  }
  return result;
}

}  // namespace tinsmith::ingest
