// Mesh construction from indexed triangles (twin linking, constraint features)
// and back to TinData. See mesh.hpp.
#include "core/mesh/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace tinsmith {
namespace {

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

}  // namespace

Mesh Mesh::fromTinData(const TinData& tin) {
  std::vector<std::uint32_t> corners;
  corners.reserve(tin.triangles.size() * 3);
  for (const auto& t : tin.triangles) corners.insert(corners.end(), t.begin(), t.end());
  return build(tin.vertices, std::move(corners), tin.constrainedEdges, tin.features, tin.crs);
}

Mesh Mesh::build(std::vector<Point3> points, std::vector<std::uint32_t> corners,
                 const std::vector<TinData::ConstrainedEdge>& edgeFeatures,
                 std::vector<TinFeature> features, std::string crs) {
  Mesh m;
  m.points_ = std::move(points);
  m.features_ = std::move(features);
  m.crs_ = std::move(crs);
  const auto nv = static_cast<std::uint32_t>(m.points_.size());

  // Keep only triangles with valid, distinct corners.
  std::size_t badTriangles = 0;
  m.corners_.reserve(corners.size());
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    const std::uint32_t a = corners[t], b = corners[t + 1], c = corners[t + 2];
    if (a >= nv || b >= nv || c >= nv || a == b || b == c || a == c) {
      if (badTriangles++ < 10) {
        m.buildProblems_.push_back("triangle " + std::to_string(t / 3) +
                                   " has a vertex index out of range or repeated (" +
                                   std::to_string(a) + ", " + std::to_string(b) + ", " +
                                   std::to_string(c) + ")");
      }
      continue;
    }
    m.corners_.insert(m.corners_.end(), {a, b, c});
  }
  if (badTriangles > 10) {
    m.buildProblems_.push_back(std::to_string(badTriangles) + " triangles dropped in total");
  }

  // Link twins: sort half-edges by undirected edge.
  const auto nh = static_cast<std::uint32_t>(m.corners_.size());
  m.twins_.assign(nh, HalfedgeId::kInvalid);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(nh);
  for (std::uint32_t h = 0; h < nh; ++h) {
    keyed[h] = {edgeKey(m.corners_[h], m.corners_[next(HalfedgeId(h)).value]), h};
  }
  std::sort(keyed.begin(), keyed.end());
  std::size_t nonManifold = 0;
  for (std::size_t i = 0; i < keyed.size();) {
    std::size_t j = i;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    if (j - i == 2) {
      const HalfedgeId h0(keyed[i].second), h1(keyed[i + 1].second);
      if (m.corners_[h0.value] != m.corners_[h1.value]) {
        m.twins_[h0.value] = h1.value;
        m.twins_[h1.value] = h0.value;
      } else if (nonManifold++ < 10) {
        m.buildProblems_.push_back("edge " + std::to_string(m.corners_[h0.value]) + "-" +
                                   std::to_string(m.corners_[next(h0).value]) +
                                   " is used twice in the same direction (overlapping or "
                                   "inconsistently oriented triangles)");
      }
    } else if (j - i > 2 && nonManifold++ < 10) {
      m.buildProblems_.push_back("edge " + std::to_string(keyed[i].first >> 32) + "-" +
                                 std::to_string(keyed[i].first & 0xffffffffu) + " is shared by " +
                                 std::to_string(j - i) + " triangles (non-manifold)");
    }
    i = j;
  }

  // Outgoing half-edge per vertex, preferring boundary ones (fan start).
  m.outgoing_.assign(nv, HalfedgeId());
  for (std::uint32_t h = 0; h < nh; ++h) {
    HalfedgeId& o = m.outgoing_[m.corners_[h]];
    if (!o.valid() || (m.isBoundary(HalfedgeId(h)) && !m.isBoundary(o))) o = HalfedgeId(h);
  }

  // Constraint features as CSR per half-edge.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> hf;  // (half-edge, feature)
  hf.reserve(edgeFeatures.size() * 2);
  std::size_t missing = 0;
  for (const auto& e : edgeFeatures) {
    if (e.feature >= m.features_.size()) {
      if (missing++ < 10) {
        m.buildProblems_.push_back("constrained edge " + std::to_string(e.a) + "-" +
                                   std::to_string(e.b) + " names unknown feature " +
                                   std::to_string(e.feature));
      }
      continue;
    }
    const std::uint64_t key = edgeKey(e.a, e.b);
    auto it = std::lower_bound(keyed.begin(), keyed.end(), std::make_pair(key, 0u));
    if (it == keyed.end() || it->first != key || e.a == e.b) {
      if (missing++ < 10) {
        m.buildProblems_.push_back("constrained edge " + std::to_string(e.a) + "-" +
                                   std::to_string(e.b) + " (feature " + std::to_string(e.feature) +
                                   ") is not an edge of the mesh");
      }
      continue;
    }
    for (; it != keyed.end() && it->first == key; ++it) hf.emplace_back(it->second, e.feature);
  }
  std::sort(hf.begin(), hf.end());
  hf.erase(std::unique(hf.begin(), hf.end()), hf.end());
  m.setEdgeFeatures(hf);
  return m;
}

TinData Mesh::toTinData() const {
  TinData tin;
  tin.crs = crs_;
  tin.vertices = points_;
  tin.features = features_;
  tin.triangles.resize(triangleCount());
  for (std::size_t t = 0; t < triangleCount(); ++t) {
    tin.triangles[t] = {corners_[3 * t], corners_[3 * t + 1], corners_[3 * t + 2]};
  }
  tin.constrainedEdges = constrainedEdges();
  return tin;
}

std::vector<TinData::ConstrainedEdge> Mesh::constrainedEdges() const {
  std::vector<TinData::ConstrainedEdge> edges;
  forEachConstrained([&](HalfedgeId h) {
    const HalfedgeId tw(twins_[h.value]);
    if (tw.valid() && tw.value < h.value) return;  // each edge once
    std::uint32_t a = corners_[h.value], b = corners_[next(h).value];
    if (a > b) std::swap(a, b);
    for (std::uint32_t f : edgeFeatures(h)) edges.push_back({a, b, f});
  });
  std::sort(edges.begin(), edges.end(), [](const auto& l, const auto& r) {
    return std::tie(l.a, l.b, l.feature) < std::tie(r.a, r.b, r.feature);
  });
  return edges;
}

void Mesh::setEdgeFeatures(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& hf) {
  consBits_.clear();
  consRank_.clear();
  featureBegin_.clear();
  featureIds_.clear();
  if (hf.empty()) return;
  const std::size_t words = corners_.size() / 64 + 1;
  consBits_.assign(words, 0);
  featureIds_.reserve(hf.size());
  featureBegin_.push_back(0);
  for (std::size_t i = 0; i < hf.size(); ++i) {
    const std::uint32_t h = hf[i].first;
    if (i > 0 && hf[i - 1].first != h) featureBegin_.push_back(static_cast<std::uint32_t>(i));
    consBits_[h / 64] |= std::uint64_t{1} << (h % 64);
    featureIds_.push_back(hf[i].second);
  }
  featureBegin_.push_back(static_cast<std::uint32_t>(hf.size()));
  finishEdgeFeatures();
}

Mesh Mesh::adopt(MeshStorage&& storage) {
  Mesh m;
  m.points_ = std::move(storage.points);
  m.corners_ = std::move(storage.corners);
  m.twins_ = std::move(storage.twins);
  m.outgoing_ = std::move(storage.outgoing);
  m.consBits_ = std::move(storage.consBits);
  m.featureBegin_ = std::move(storage.featureBegin);
  m.featureIds_ = std::move(storage.featureIds);
  m.features_ = std::move(storage.features);
  m.crs_ = std::move(storage.crs);
  m.finishEdgeFeatures();
  return m;
}

MeshStorage Mesh::release() && {
  MeshStorage s;
  s.points = std::move(points_);
  s.corners = std::move(corners_);
  s.twins = std::move(twins_);
  s.outgoing = std::move(outgoing_);
  s.consBits = std::move(consBits_);
  s.featureBegin = std::move(featureBegin_);
  s.featureIds = std::move(featureIds_);
  s.features = std::move(features_);
  s.crs = std::move(crs_);
  *this = Mesh();
  return s;
}

void Mesh::finishEdgeFeatures() {
  if (featureIds_.empty()) {
    consBits_.clear();
    consRank_.clear();
    featureBegin_.clear();
    return;
  }
  consRank_.assign(consBits_.size() + 1, 0);
  for (std::size_t w = 0; w < consBits_.size(); ++w) {
    consRank_[w + 1] = consRank_[w] + static_cast<std::uint32_t>(std::popcount(consBits_[w]));
  }
}

void Mesh::forEachOutgoing(VertexId v, const std::function<void(HalfedgeId)>& f) const {
  const HalfedgeId start = outgoing(v);
  if (!start.valid()) return;
  HalfedgeId h = start;
  for (std::size_t guard = 0; guard <= corners_.size(); ++guard) {
    f(h);
    const HalfedgeId t = twin(prev(h));
    if (!t.valid() || t == start) return;
    h = t;
  }
}

std::vector<HalfedgeId> Mesh::boundaryHalfedges() const {
  std::vector<HalfedgeId> out;
  for (std::uint32_t h = 0; h < twins_.size(); ++h) {
    if (twins_[h] == HalfedgeId::kInvalid) out.push_back(HalfedgeId(h));
  }
  return out;
}

}  // namespace tinsmith
