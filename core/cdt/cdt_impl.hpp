// The state behind the Cdt facade: the constrained triangulation under
// construction, its domain, and the finished mesh with its input-vertex map.
// Internal to core/cdt (cdt.cpp, validator.cpp).
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <utility>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/constraints.hpp"
#include "core/cdt/domain.hpp"

namespace tinsmith {

struct Cdt::Impl : cdt::ConstrainedTriangulation {
  explicit Impl(CdtOptions opts) : ConstrainedTriangulation(std::move(opts)) {}

  cdt::Domain domain;
  // After buildMesh() the triangle arrays live in `mesh` (TriangleStore::pack).
  Mesh mesh;
  cdt::IdVector<VertexId, VertexId> meshOf;  // input vertex → mesh vertex (invalid if none)
  // finalize() has run and no input came after it: the mesh may be read.
  bool finalized = false;
  // Input (points, constraints, domain rings) came since the last finalize().
  bool changed = false;
  // The const readers (mesh(), report(), meshVertex()) build the mesh on first
  // use, possibly on several threads at once: one builds it under the lock,
  // the others wait for it (buildMesh).
  std::atomic<bool> meshBuilt = false;
  std::mutex meshMutex;

  /// New input: the mesh is out of date until the next finalize().
  void inputAdded() {
    finalized = false;
    changed = true;
  }
  /// Takes the triangles back from the mesh (TriangleStore::unpack): the
  /// working triangulation becomes exactly what it was before buildMesh().
  void unpackMesh();
};

}  // namespace tinsmith
