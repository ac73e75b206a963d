// Typed ids of the CDT's working triangulation: the Mesh's VertexId,
// HalfedgeId and TriangleId (core/mesh/mesh.hpp), with the CDT's one extra
// vertex (at infinity) and the arithmetic between half-edges and triangles.
// In the working triangulation a VertexId is an input vertex id (as in Cdt's
// API); half-edge and triangle ids are working slots, which compaction into a
// Mesh renumbers. Internal to core/cdt.
//
// Triangle t owns half-edges 3t..3t+2; half-edge 3t+i runs from corner i to
// corner (i+1)%3 with the triangle on its left (as in a Mesh).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.hpp"

namespace tinsmith::cdt {

/// The vertex at infinity, third corner of every ghost triangle. Every finite
/// vertex id is below it (VertexId::invalid() is above).
inline constexpr VertexId kInfinite{0xfffffffeu};

/// Half-edge `corner` (0..2) of triangle t: from that corner to the next.
constexpr HalfedgeId halfedgeOf(TriangleId t, std::uint32_t corner) {
  return HalfedgeId(3 * t.value + corner);
}
/// The triangle that owns half-edge h.
constexpr TriangleId triangleOf(HalfedgeId h) {
  return TriangleId(h.value / 3);
}
/// The corner of its triangle that half-edge h starts from (0..2).
constexpr std::uint32_t cornerOf(HalfedgeId h) {
  return h.value % 3;
}
/// The next and previous half-edge of the same triangle.
constexpr HalfedgeId nxt(HalfedgeId h) {
  return HalfedgeId(h.value % 3 == 2 ? h.value - 2 : h.value + 1);
}
constexpr HalfedgeId prv(HalfedgeId h) {
  return HalfedgeId(h.value % 3 == 0 ? h.value + 2 : h.value - 1);
}

/// A std::vector indexed by a typed id only (an index of the wrong kind does
/// not compile). Sizes and iteration are those of the vector.
template <class Id, class T>
class IdVector : public std::vector<T> {
 public:
  using std::vector<T>::vector;
  using std::vector<T>::operator=;

  T& operator[](Id i) { return std::vector<T>::operator[](i.value); }
  const T& operator[](Id i) const { return std::vector<T>::operator[](i.value); }
  /// The id one past the last element (the id the next push_back gets).
  [[nodiscard]] Id endId() const { return Id(static_cast<std::uint32_t>(this->size())); }
};

}  // namespace tinsmith::cdt
