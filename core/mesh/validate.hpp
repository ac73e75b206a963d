// The mesh validator: the invariant checker every test (and `tinsmith validate`)
// runs. It never throws on a bad mesh; it lists what is wrong.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/mesh.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith {

struct ValidationOptions {
  /// Check the (constrained) Delaunay property on every interior unconstrained edge.
  bool checkDelaunay = true;
  /// Stop listing problems after this many (counting continues).
  std::size_t maxProblems = 50;
  /// Threads for the passes over triangles and half-edges (0: every core).
  /// The report is the same for any count.
  unsigned threads = 1;
};

struct ValidationReport {
  bool ok = true;
  std::size_t problemCount = 0;        ///< all problems, even those not listed
  std::vector<std::string> problems;   ///< human-readable, at most maxProblems
  // What was checked, for the report.
  std::size_t vertices = 0, triangles = 0, edges = 0, boundaryEdges = 0, constrainedEdges = 0;
  std::size_t boundaryLoops = 0;

  /// "ok: V vertices, T triangles, …" or the problems, one per line.
  [[nodiscard]] std::string summary() const;
};

/// Checks a mesh: twin symmetry (twin(twin(h)) == h, opposite directions), no
/// edge used twice in one direction, every triangle strictly counter-clockwise
/// (exact orient2d), finite coordinates, Euler characteristic consistent with
/// the boundary loops (V − E + F = Σ loops ±1 − pinch corrections), constraint
/// flags identical on both half-edges of an edge and feature ids in range, and
/// (if asked) every interior unconstrained edge locally Delaunay (exact incircle,
/// cocircular allowed). Also lists Mesh::buildProblems().
ValidationReport validate(const Mesh& mesh, const ValidationOptions& options = {});

/// Validates TinData (e.g. a loaded .tin): index ranges, degenerate triangles,
/// constrained edges that are not mesh edges or name unknown features, then the
/// mesh checks above.
ValidationReport validate(const TinData& tin, const ValidationOptions& options = {});

}  // namespace tinsmith
