// Binary triangulations (Hjelle & Dæhlen 2.10, 8.10): longest-edge bisection
// of the four isosceles triangles around the centre of a square. The vertices
// of level k lie on the regular grid Ψk with 2^k + 1 vertices a side; a vertex
// is active only if its parents (the apexes of the two triangles sharing the
// edge it splits; one at the boundary) are active, so activation closes upward
// over all ancestors.
//
// Vertices are named by their row-major index ("key") in the finest grid
// Ψ_K, K = gridLevels(): key = j·(2^K + 1) + i. Because the index is linear in
// (i, j), a split vertex's key is the mean of the keys of its split edge's ends
// (i = (l + r)/2). Only active vertices are stored (an open-addressing hash
// map key → dense id), so memory grows with the active vertices, not with the
// 4^K grid.
//
// Depth: the corners have depth 0, the centre depth 1; a vertex of depth d
// splits the hypotenuse of a triangle of depth d − 1. Ψk holds the vertices of
// depth ≤ 2k; the centres of the cells of Ψk have depth 2k + 1.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "core/base/u64_map.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::fit {

/// A map from 64-bit keys to dense 32-bit ids (a U64Map at most 7/10 full);
/// the key ~0 (kEmpty) is reserved: it is never found, and inserting it
/// stores nothing. Deterministic (no hashing randomness).
class KeyIndexMap {
 public:
  static constexpr std::uint64_t kEmpty = U64Map<std::uint32_t>::kEmpty;
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  void reserve(std::size_t count) { table_.reserve(count); }
  /// The id of `key`, or kNone.
  [[nodiscard]] std::uint32_t find(std::uint64_t key) const {
    const std::uint32_t* id = table_.find(key);
    return id ? *id : kNone;
  }
  /// Inserts key → id unless present or kEmpty; returns true when inserted.
  bool insert(std::uint64_t key, std::uint32_t id) { return table_.insert(key, id).second; }
  [[nodiscard]] std::size_t size() const { return table_.size(); }
  void clear() { table_.clear(); }

 private:
  U64Map<std::uint32_t, 7, 10> table_;
};

/// A triangle of a binary triangulation by the keys of its hypotenuse ends l,
/// r and its apex a; (l, r, a) is counter-clockwise. `path` names the triangle
/// in the bisection tree (root and child choices) and is unique.
struct BinaryTriangle {
  std::uint64_t l = 0;
  std::uint64_t a = 0;
  std::uint64_t r = 0;
  std::uint64_t path = 0;
  int depth = 0;  ///< 0 for the four triangles around the centre
};

/// A located point: its triangle and barycentric coordinates with respect to
/// (l, r, a).
struct BinaryLocation {
  BinaryTriangle triangle;
  std::array<double, 3> barycentric{};
};

class BinaryTriangulation {
 public:
  static constexpr int kMaxGridLevels = 30;

  /// A square domain [origin.x, origin.x + size] × [origin.y, origin.y + size]
  /// with finest grid Ψ_K, K = gridLevels (1 ≤ K ≤ 30). The four corners and
  /// the centre start active. Throws inputError for a bad size or level.
  BinaryTriangulation(Point2 origin, double size, int gridLevels);

  [[nodiscard]] int gridLevels() const { return gridLevels_; }
  [[nodiscard]] std::uint64_t side() const { return side_; }  ///< 2^K cells a side
  [[nodiscard]] Point2 origin() const { return origin_; }
  [[nodiscard]] double size() const { return size_; }

  [[nodiscard]] std::uint64_t key(std::uint64_t i, std::uint64_t j) const { return j * (side_ + 1) + i; }
  [[nodiscard]] std::uint64_t column(std::uint64_t key) const { return key % (side_ + 1); }
  [[nodiscard]] std::uint64_t row(std::uint64_t key) const { return key / (side_ + 1); }
  /// Position in the domain's coordinates.
  [[nodiscard]] Point2 position(std::uint64_t key) const;
  /// Bisection depth (see the file comment).
  [[nodiscard]] int depth(std::uint64_t key) const;
  /// The parents of a vertex (0, 1 or 2 keys; the corners and centre have none).
  [[nodiscard]] std::vector<std::uint64_t> parents(std::uint64_t key) const;
  /// The ends of the edge a vertex splits (its value under nested refinement is
  /// the mean of theirs). Throws internalError for a corner or the centre.
  [[nodiscard]] std::array<std::uint64_t, 2> splitEdge(std::uint64_t key) const;
  /// Key of the centre of cell (ci, cj) of Ψ_level (a vertex of Ψ_level+1);
  /// level < K.
  [[nodiscard]] std::uint64_t cellCentre(int level, std::uint64_t ci, std::uint64_t cj) const;

  [[nodiscard]] bool isActive(std::uint64_t key) const { return ids_.find(key) != KeyIndexMap::kNone; }
  /// Dense id of an active vertex (order of activation), or KeyIndexMap::kNone.
  [[nodiscard]] std::uint32_t vertexId(std::uint64_t key) const { return ids_.find(key); }
  /// Keys of the active vertices by dense id.
  [[nodiscard]] std::span<const std::uint64_t> activeKeys() const { return keys_; }
  [[nodiscard]] std::size_t activeCount() const { return keys_.size(); }

  /// Activates `key` and every inactive ancestor (2.10). Returns the number of
  /// vertices newly activated. Throws inputError for a key outside the grid.
  std::size_t activate(std::uint64_t key);

  /// The triangles by SubmeshRefine (2.10), in recursion order (each is CCW
  /// as (l, r, a)).
  [[nodiscard]] std::vector<BinaryTriangle> triangles() const;

  /// One triangle strip over all triangles (degenerate triangles join the
  /// pieces): triangle i of the strip is (s[i], s[i+1], s[i+2]), CCW for even
  /// i and CW for odd i; triangles with a repeated vertex are to be skipped.
  [[nodiscard]] std::vector<std::uint64_t> triangleStrip() const;

  /// The triangle containing p (domain coordinates). Throws inputError when
  /// p is outside the square.
  [[nodiscard]] BinaryLocation locate(Point2 p) const;
  /// The same, continuing downward from a triangle that is known to contain p
  /// (a coarser one, from an earlier location: nested refinement).
  [[nodiscard]] BinaryLocation locateFrom(Point2 p, std::uint64_t path) const;
  /// The same from the triangle itself (no rebuilding from the path).
  [[nodiscard]] BinaryLocation locateIn(Point2 p, const BinaryTriangle& start) const { return descend(toGrid(p), start); }

  /// The four triangles around the centre (depth 0), and which of them holds
  /// p (the one locate() starts from; p inside the square).
  [[nodiscard]] std::array<BinaryTriangle, 4> rootTriangles() const { return roots(); }
  [[nodiscard]] int rootIndex(Point2 p) const;
  /// Whether `t` is split in the current triangulation (its split vertex is active).
  [[nodiscard]] bool isSplit(const BinaryTriangle& t) const {
    return t.depth <= 2 * gridLevels_ - 2 && isActive((t.l + t.r) / 2);
  }
  /// Grid coordinates (units of the finest cell) of a vertex.
  [[nodiscard]] Point2 gridPosition(std::uint64_t key) const {
    return {static_cast<double>(column(key)), static_cast<double>(row(key))};
  }

  /// Rebuilds the triangle (l, a, r, depth) from its path.
  [[nodiscard]] BinaryTriangle triangleFromPath(std::uint64_t path) const;

  /// Grid coordinates (units of the finest cell) of a domain point. A point
  /// within rounding of the square (1e-9 of a finest cell, relative to the
  /// side) is put on it: origin + size need not round back to the data's
  /// largest coordinate, and (x − origin)·(side / size) may exceed the side by
  /// an ulp for a point on the square's edge. Points farther out stay out.
  [[nodiscard]] Point2 toGrid(Point2 p) const {
    const double scale = static_cast<double>(side_) / size_;
    const double n = static_cast<double>(side_);
    const double slack = 1e-9 * n;
    auto onto = [&](double g) {
      if (g < 0.0 && g >= -slack) return 0.0;
      if (g > n && g <= n + slack) return n;
      return g;
    };
    return {onto((p.x - origin_.x) * scale), onto((p.y - origin_.y) * scale)};
  }

 private:
  [[nodiscard]] std::array<BinaryTriangle, 4> roots() const;
  [[nodiscard]] BinaryLocation descend(Point2 grid, BinaryTriangle t) const;
  void activateOne(std::uint64_t key);

  Point2 origin_;
  double size_;
  int gridLevels_;
  std::uint64_t side_;
  KeyIndexMap ids_;
  std::vector<std::uint64_t> keys_;
};

/// Point location in the current triangulation below the triangles of an
/// earlier one (the triangulations are nested, 8.10). The bisection subtree
/// under each earlier triangle is laid out once as nodes holding the
/// splitting line; a point walks it with one orientation test a step and no
/// hash lookups, taking the decisions of BinaryTriangulation::descend.
class NestedLocator {
 public:
  /// Lays out the subtree of `mesh`'s current triangulation under `t`, whose
  /// leaves are looked up in `leafIndex` (current triangle path → index), and
  /// returns the handle locate() starts from. Throws internalError when a leaf
  /// is missing from `leafIndex`.
  std::int32_t add(const BinaryTriangulation& mesh, const KeyIndexMap& leafIndex, const BinaryTriangle& t);
  /// The leaf-index of the current triangle holding grid point `grid`
  /// (BinaryTriangulation::toGrid), starting from a handle add() returned for
  /// a triangle that holds the point.
  [[nodiscard]] std::uint32_t locate(std::int32_t handle, Point2 grid) const {
    while (handle >= 0) {
      const Node& nd = nodes_[static_cast<std::size_t>(handle)];
      handle = nd.child[geometry::orient2dInexact(nd.a, nd.j, grid) * nd.lSide >= 0.0 ? 0 : 1];
    }
    return static_cast<std::uint32_t>(-1 - handle);
  }

 private:
  struct Node {
    Point2 a, j;              ///< the splitting line a–j, grid coordinates
    double lSide = 0.0;       ///< orient2dInexact(a, j, l): the side of the l child
    std::int32_t child[2]{};  ///< l child, r child: ≥ 0 a node, < 0 the leaf −1 − index
  };
  std::vector<Node> nodes_;
};

}  // namespace tinsmith::fit
