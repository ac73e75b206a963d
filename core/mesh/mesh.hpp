// The triangle mesh of a TIN as a half-edge (dart) structure (book ch. 2.5, 9):
// topology apart from geometry, strongly typed ids.
//
// Storage is triangle-based: triangle t owns half-edges 3t, 3t+1, 3t+2; half-edge
// 3t+i runs from corner i to corner (i+1)%3 of t, with the triangle on its left
// (triangles are counter-clockwise in x, y). twin(h) is the oppositely directed
// half-edge of the neighbouring triangle, or invalid on the boundary of the mesh.
// In the book's dart terms: α0 = twin∘next∘… — here `next`, `prev`, `twin`.
//
// Vertices carry x, y (project CRS, metres) and z (metres) as payload. An edge
// may be constrained: it then records the ids of the input features it came from
// (indices into features()); both half-edges of an edge carry the same list.
#pragma once

#include <array>
#include <bit>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/base/point.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith {

/// A strongly typed 32-bit index. `Tag` keeps vertex, half-edge and triangle ids
/// apart; the default value is the explicit invalid id.
template <class Tag>
struct StrongId {
  static constexpr std::uint32_t kInvalid = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t value = kInvalid;

  constexpr StrongId() = default;
  constexpr explicit StrongId(std::uint32_t v) : value(v) {}
  static constexpr StrongId invalid() { return StrongId(); }
  [[nodiscard]] constexpr bool valid() const { return value != kInvalid; }
  constexpr explicit operator bool() const { return valid(); }
  friend constexpr auto operator<=>(StrongId, StrongId) = default;
};

struct VertexTag;
struct HalfedgeTag;
struct TriangleTag;
using VertexId = StrongId<VertexTag>;
using HalfedgeId = StrongId<HalfedgeTag>;
using TriangleId = StrongId<TriangleTag>;

/// The arrays of a Mesh, for a builder that lays them out itself (the CDT's
/// compaction) and hands them over whole with Mesh::adopt, and takes them back
/// with Mesh::release. Nothing is checked or re-linked on the way: the builder
/// guarantees what Mesh documents (CCW triangles, twins paired or invalid,
/// outgoing as Mesh::outgoing describes).
struct MeshStorage {
  std::vector<Point3> points;
  std::vector<std::uint32_t> corners;  ///< 3 per triangle
  std::vector<std::uint32_t> twins;    ///< per half-edge (HalfedgeId values)
  std::vector<HalfedgeId> outgoing;    ///< per vertex
  /// Constrained half-edges as a bitset over half-edge ids (64 a word; empty
  /// or all zero: none); the r-th constrained half-edge (ascending) has the
  /// features featureIds[featureBegin[r] .. featureBegin[r + 1]), ascending.
  std::vector<std::uint64_t> consBits;
  std::vector<std::uint32_t> featureBegin;
  std::vector<std::uint32_t> featureIds;
  std::vector<TinFeature> features;
  std::string crs;
};

/// A finished TIN mesh (possibly non-convex, with holes). Built by the CDT
/// (Cdt::mesh()) or from TinData (Mesh::fromTinData). Immutable once built.
class Mesh {
 public:
  Mesh() = default;

  /// Rebuilds a mesh from TinData (e.g. a loaded .tin file): links twins,
  /// attaches constrained-edge features. Never throws on bad topology: what
  /// cannot be represented (index out of range, an edge used by more than two
  /// triangles or twice in one direction, a constrained edge that is not a mesh
  /// edge) is listed in buildProblems() and left out, so validate() can report it.
  static Mesh fromTinData(const TinData& tin);

  /// The indexed form: vertices, triangles (CCW), constrained edges (one entry
  /// per edge and feature, a < b, sorted), features, crs.
  [[nodiscard]] TinData toTinData() const;
  /// The constrained-edge records of toTinData(): one per (edge, feature),
  /// a < b, sorted by (a, b, feature).
  [[nodiscard]] std::vector<TinData::ConstrainedEdge> constrainedEdges() const;

  // --- sizes -------------------------------------------------------------
  [[nodiscard]] std::size_t vertexCount() const { return points_.size(); }
  [[nodiscard]] std::size_t triangleCount() const { return corners_.size() / 3; }
  [[nodiscard]] std::size_t halfedgeCount() const { return corners_.size(); }

  // --- geometry ----------------------------------------------------------
  [[nodiscard]] const Point3& point(VertexId v) const { return points_[v.value]; }
  [[nodiscard]] Point2 xy(VertexId v) const { return points_[v.value].xy(); }
  [[nodiscard]] double z(VertexId v) const { return points_[v.value].z; }
  [[nodiscard]] const std::vector<Point3>& points() const { return points_; }
  /// The triangles' vertex indices, three per triangle (CCW), as stored.
  [[nodiscard]] std::span<const std::uint32_t> cornerIndices() const { return corners_; }
  /// The twin of every half-edge as stored (HalfedgeId values; kInvalid on the boundary).
  [[nodiscard]] std::span<const std::uint32_t> twinIndices() const { return twins_; }

  // --- topology ----------------------------------------------------------
  [[nodiscard]] static HalfedgeId halfedge(TriangleId t, int corner) {
    return HalfedgeId(t.value * 3 + static_cast<std::uint32_t>(corner));
  }
  [[nodiscard]] static TriangleId triangle(HalfedgeId h) { return TriangleId(h.value / 3); }
  [[nodiscard]] static HalfedgeId next(HalfedgeId h) {
    return HalfedgeId(h.value % 3 == 2 ? h.value - 2 : h.value + 1);
  }
  [[nodiscard]] static HalfedgeId prev(HalfedgeId h) {
    return HalfedgeId(h.value % 3 == 0 ? h.value + 2 : h.value - 1);
  }
  /// The opposite half-edge, invalid on the mesh boundary.
  [[nodiscard]] HalfedgeId twin(HalfedgeId h) const { return HalfedgeId(twins_[h.value]); }
  [[nodiscard]] VertexId origin(HalfedgeId h) const { return VertexId(corners_[h.value]); }
  [[nodiscard]] VertexId target(HalfedgeId h) const { return origin(next(h)); }
  [[nodiscard]] std::array<VertexId, 3> vertices(TriangleId t) const {
    return {VertexId(corners_[3 * t.value]), VertexId(corners_[3 * t.value + 1]),
            VertexId(corners_[3 * t.value + 2])};
  }
  [[nodiscard]] bool isBoundary(HalfedgeId h) const { return twins_[h.value] == HalfedgeId::kInvalid; }

  /// One half-edge leaving v; for a boundary vertex the one whose clockwise
  /// neighbour is missing, so that star iteration (CCW) covers the whole fan.
  /// Invalid for a vertex no triangle uses.
  [[nodiscard]] HalfedgeId outgoing(VertexId v) const { return outgoing_[v.value]; }

  /// Calls f(h) for every half-edge leaving v, counter-clockwise, starting at
  /// outgoing(v). Covers one fan (a vertex where several fans touch is listed
  /// by validate()).
  void forEachOutgoing(VertexId v, const std::function<void(HalfedgeId)>& f) const;

  /// Boundary half-edges (twin invalid), in increasing id order.
  [[nodiscard]] std::vector<HalfedgeId> boundaryHalfedges() const;

  // --- constraints -------------------------------------------------------
  [[nodiscard]] bool isConstrained(HalfedgeId h) const {
    return !consBits_.empty() && ((consBits_[h.value / 64] >> (h.value % 64)) & 1u);
  }
  /// Feature ids (into features()) of the edge of h, ascending; empty if unconstrained.
  [[nodiscard]] std::span<const std::uint32_t> edgeFeatures(HalfedgeId h) const {
    if (!isConstrained(h)) return {};
    const std::uint64_t below = (std::uint64_t{1} << (h.value % 64)) - 1;
    const std::uint32_t r =
        consRank_[h.value / 64] +
        static_cast<std::uint32_t>(std::popcount(consBits_[h.value / 64] & below));
    return {featureIds_.data() + featureBegin_[r], featureIds_.data() + featureBegin_[r + 1]};
  }
  /// Calls f(h) for every constrained half-edge, in increasing id order
  /// (reads only the constraint bitset, not every half-edge).
  template <class F>
  void forEachConstrained(F&& f) const {
    for (std::size_t w = 0; w < consBits_.size(); ++w)
      for (std::uint64_t bits = consBits_[w]; bits != 0; bits &= bits - 1)
        f(HalfedgeId(static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(std::countr_zero(bits)))));
  }
  [[nodiscard]] const std::vector<TinFeature>& features() const { return features_; }
  [[nodiscard]] const std::string& crs() const { return crs_; }

  /// Problems found while building from TinData (empty for CDT output).
  [[nodiscard]] const std::vector<std::string>& buildProblems() const { return buildProblems_; }

  // --- construction (used by the CDT and fromTinData) ---------------------
  /// Builds from raw arrays: `corners` has 3 vertex indices per triangle (CCW),
  /// `edgeFeatures` lists (a, b, feature) with a, b vertex indices. Twins are
  /// linked here. Same tolerance for bad input as fromTinData.
  static Mesh build(std::vector<Point3> points, std::vector<std::uint32_t> corners,
                    const std::vector<TinData::ConstrainedEdge>& edgeFeatures,
                    std::vector<TinFeature> features, std::string crs);
  /// Takes over arrays laid out by the caller (see MeshStorage), unchecked.
  static Mesh adopt(MeshStorage&& storage);
  /// Gives the arrays back (the inverse of adopt); the mesh is left empty.
  [[nodiscard]] MeshStorage release() &&;

 private:
  std::vector<Point3> points_;
  std::vector<std::uint32_t> corners_;       // 3 per triangle
  std::vector<std::uint32_t> twins_;         // per half-edge (HalfedgeId values)
  std::vector<HalfedgeId> outgoing_;         // per vertex
  /// Sets the per-half-edge features from (half-edge, feature) pairs sorted
  /// and without duplicates.
  void setEdgeFeatures(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& hf);
  /// After consBits_, featureBegin_ and featureIds_ were filled: the ranks,
  /// or nothing at all when no half-edge carries a feature.
  void finishEdgeFeatures();
  // Constrained half-edges as a bitset (empty: none) with per-word ranks; the
  // features of the r-th constrained half-edge are featureIds_[featureBegin_[r]
  // .. featureBegin_[r + 1]) (CSR over constrained half-edges only).
  std::vector<std::uint64_t> consBits_;
  std::vector<std::uint32_t> consRank_;
  std::vector<std::uint32_t> featureBegin_;
  std::vector<std::uint32_t> featureIds_;
  std::vector<TinFeature> features_;
  std::string crs_;
  std::vector<std::string> buildProblems_;
};

}  // namespace tinsmith
