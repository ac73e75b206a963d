// Penalized least squares over a triangulation (Hjelle & Dæhlen 8.2–8.9).
#include "core/fit/least_squares.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/SparseCholesky>

#include "core/base/error.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::fit {

namespace {

using Triplet = Eigen::Triplet<double, SparseMatrix::StorageIndex>;

SparseMatrix fromTriplets(std::size_t n, const std::vector<Triplet>& triplets) {
  SparseMatrix m(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  m.setFromTriplets(triplets.begin(), triplets.end());
  m.makeCompressed();
  return m;
}

void checkTriangles(std::size_t vertexCount, std::span<const Triangle> triangles) {
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (auto v : triangles[t]) {
      if (v >= vertexCount) {
        throw inputError("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                             " but there are only " + std::to_string(vertexCount) + " vertices",
                         {}, "give triangles as indices into the vertex list");
      }
    }
  }
}

}  // namespace

void TriangleMoments::merge(const TriangleMoments& other) {
  for (int i = 0; i < 6; ++i) bb[i] += other.bb[i];
  for (int i = 0; i < 3; ++i) bz[i] += other.bz[i];
}

std::array<double, 3> barycentric(const Point2& p, const Point2& a, const Point2& b, const Point2& c) {
  const double area = geometry::orient2dInexact(a, b, c);
  const double ba = geometry::orient2dInexact(p, b, c) / area;
  const double bb = geometry::orient2dInexact(a, p, c) / area;
  return {ba, bb, 1.0 - ba - bb};
}

std::vector<MeshEdge> meshEdges(std::size_t vertexCount, std::span<const Triangle> triangles) {
  checkTriangles(vertexCount, triangles);
  // Half-edges (from, to, opposite) bucketed by their lower end (a counting
  // sort), then ordered by (higher end, from) within each small bucket: twins
  // are neighbours, and edges come out ordered by (lo, hi).
  struct HalfEdge {
    std::uint32_t hi, from, opposite;
  };
  std::vector<std::uint32_t> start(vertexCount + 1, 0);
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) ++start[std::min(t[k], t[(k + 1) % 3]) + 1];
  }
  for (std::size_t v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
  std::vector<HalfEdge> half(triangles.size() * 3);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& t : triangles) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        half[fill[std::min(a, b)]++] = {std::max(a, b), a, c};
      }
    }
  }
  std::vector<MeshEdge> edges;
  edges.reserve(half.size() / 2 + 1);
  for (std::size_t lo = 0; lo < vertexCount; ++lo) {
    const auto first = half.begin() + start[lo], last = half.begin() + start[lo + 1];
    std::sort(first, last, [](const HalfEdge& x, const HalfEdge& y) {
      return x.hi != y.hi ? x.hi < y.hi : x.from < y.from;
    });
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && j->hi == i->hi) ++j;
      auto where = [&] { return "edge (" + std::to_string(lo) + ", " + std::to_string(i->hi) + ")"; };
      if (j - i > 2) throw geometryError(where() + " belongs to more than two triangles", {}, "give a manifold triangulation");
      MeshEdge e;
      e.s = i->from;
      e.t = i->from == lo ? i->hi : static_cast<std::uint32_t>(lo);
      e.left = i->opposite;
      if (j - i == 2) {
        const HalfEdge& g = *(i + 1);
        if (g.from == i->from) throw geometryError(where() + ": its two triangles have the same orientation", {}, "orient every triangle counter-clockwise");
        e.right = g.opposite;
      }
      edges.push_back(e);
      i = j;
    }
  }
  return edges;
}

namespace {

// Scatters each data-holding triangle's local 3×3 block of BᵀB (stored as the
// upper triangle in TriangleMoments::bb) and its 3 entries of Bᵀz into global
// indices: addMatrix(i, j, value), addRhs(i, value). Triangles without data
// are skipped.
template <class AddMatrix, class AddRhs>
void scatterTriangleMoments(std::span<const Triangle> triangles, std::span<const TriangleMoments> moments,
                            AddMatrix&& addMatrix, AddRhs&& addRhs) {
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& m = moments[t];
    const auto& tri = triangles[t];
    bool empty = true;
    for (double v : m.bb) empty = empty && v == 0.0;
    if (empty) continue;
    for (int a = 0; a < 3; ++a) {
      addRhs(tri[a], m.bz[a]);
      for (int b = 0; b < 3; ++b) addMatrix(tri[a], tri[b], m.bb[kIndex[a][b]]);
    }
  }
}

}  // namespace

NormalEquations scatterMoments(std::size_t vertexCount, std::span<const Triangle> triangles,
                               std::span<const TriangleMoments> moments) {
  std::vector<Triplet> triplets;
  triplets.reserve(triangles.size() * 9);
  NormalEquations eq;
  eq.btz = Vector::Zero(static_cast<Eigen::Index>(vertexCount));
  scatterTriangleMoments(
      triangles, moments,
      [&](std::uint32_t i, std::uint32_t j, double v) {
        triplets.emplace_back(static_cast<int>(i), static_cast<int>(j), v);
      },
      [&](std::uint32_t i, double v) { eq.btz[i] += v; });
  eq.btb = fromTriplets(vertexCount, triplets);
  return eq;
}

std::vector<TriangleMoments> triangleMoments(std::size_t vertexCount, std::span<const Triangle> triangles,
                                             std::span<const Sample> samples) {
  checkTriangles(vertexCount, triangles);
  std::vector<TriangleMoments> moments(triangles.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto& s = samples[k];
    if (s.triangle >= triangles.size()) {
      throw inputError("data point " + std::to_string(k) + " lies in triangle " + std::to_string(s.triangle) +
                           " of " + std::to_string(triangles.size()),
                       {}, "locate every data point in the triangulation before fitting");
    }
    moments[s.triangle].add(s.barycentric, s.z, s.weight);
  }
  return moments;
}

NormalEquations assembleNormalEquations(std::size_t vertexCount, std::span<const Triangle> triangles,
                                        std::span<const Sample> samples) {
  return scatterMoments(vertexCount, triangles, triangleMoments(vertexCount, triangles, samples));
}

namespace {

// assemblePenalized into `sys` (a fresh one): the callers' systems are
// filled in place, not copied (see assembleSystem).
void assemblePenalizedInto(PenalizedSystem& sys, std::span<const Triangle> triangles,
                           std::span<const TriangleMoments> moments, const SparseMatrix& energy,
                           double lambdaFactor, std::optional<double> lambdaAbsolute) {
  SparseMatrix btb = energy;
  std::fill(btb.valuePtr(), btb.valuePtr() + btb.nonZeros(), 0.0);
  sys.b = Vector::Zero(energy.rows());
  scatterTriangleMoments(
      triangles, moments, [&](std::uint32_t i, std::uint32_t j, double v) { btb.coeffRef(i, j) += v; },
      [&](std::uint32_t i, double v) { sys.b[i] += v; });
  btb.makeCompressed();
  sys.lambdaDefault = defaultLambda(btb, energy);
  sys.lambda = lambdaAbsolute ? *lambdaAbsolute : lambdaFactor * sys.lambdaDefault;
  if (btb.nonZeros() == energy.nonZeros()) {  // no entry was inserted: same pattern
    sys.a.swap(btb);  // (Eigen 3.4's SparseMatrix has no move: std::move copies)
    double* v = sys.a.valuePtr();
    const double* e = energy.valuePtr();
    for (Eigen::Index k = 0; k < sys.a.nonZeros(); ++k) v[k] += sys.lambda * e[k];
  } else {
    sys.a = btb + sys.lambda * energy;
    sys.a.makeCompressed();
  }
}

}  // namespace

PenalizedSystem assemblePenalized(std::span<const Triangle> triangles,
                                  std::span<const TriangleMoments> moments,
                                  const SparseMatrix& energy, double lambdaFactor,
                                  std::optional<double> lambdaAbsolute) {
  PenalizedSystem sys;
  assemblePenalizedInto(sys, triangles, moments, energy, lambdaFactor, lambdaAbsolute);
  return sys;
}

PenalizedSystem assembleSystem(std::size_t vertexCount, std::span<const Triangle> triangles,
                               std::span<const TriangleMoments> moments,
                               std::optional<SparseMatrix>&& energy, double lambdaFactor,
                               std::optional<double> lambdaAbsolute) {
  PenalizedSystem sys;
  if (energy) {
    assemblePenalizedInto(sys, triangles, moments, *energy, lambdaFactor, lambdaAbsolute);
    energy.reset();
  } else {
    NormalEquations eq = scatterMoments(vertexCount, triangles, moments);
    sys.a.swap(eq.btb);
    sys.b = std::move(eq.btz);
  }
  return sys;
}

SparseMatrix membraneEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles) {
  checkTriangles(vertices.size(), triangles);
  // E = GᵀG with two rows per triangle, √A_t ∇g_t = (Σ η_i c_i, Σ μ_i c_i) / (2√A_t):
  // Σ_t A_t |∇g_t|² = Σ_t (η_i η_j + μ_i μ_j) / 4A_t. A product of sparse
  // matrices needs far less memory than 9 triplets per triangle.
  std::vector<Triplet> triplets;
  triplets.reserve(triangles.size() * 6);
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    const auto& t = triangles[k];
    const Point2 &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    const double area2 = std::abs(geometry::orient2dInexact(a, b, c));  // 2A
    if (area2 == 0.0) throw geometryError("degenerate triangle " + std::to_string(k) + " in the membrane energy");
    const double eta[3] = {b.y - c.y, c.y - a.y, a.y - b.y};
    const double mu[3] = {c.x - b.x, a.x - c.x, b.x - a.x};
    const double scale = 1.0 / std::sqrt(2.0 * area2);  // 1 / (2√A)
    for (int i = 0; i < 3; ++i) {
      triplets.emplace_back(static_cast<int>(2 * k), static_cast<int>(t[i]), eta[i] * scale);
      triplets.emplace_back(static_cast<int>(2 * k + 1), static_cast<int>(t[i]), mu[i] * scale);
    }
  }
  SparseMatrix g(static_cast<Eigen::Index>(2 * triangles.size()), static_cast<Eigen::Index>(vertices.size()));
  g.setFromTriplets(triplets.begin(), triplets.end());
  std::vector<Triplet>().swap(triplets);  // frees (assigning {} keeps the capacity)
  SparseMatrix e = SparseMatrix(g.transpose()) * g;
  e.makeCompressed();
  return e;
}

SparseMatrix umbrellaEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles, bool weighted) {
  const auto edges = meshEdges(vertices.size(), triangles);
  const std::size_t n = vertices.size();
  std::vector<double> total(n, 0.0);
  auto weightOf = [&](const MeshEdge& e) {
    if (!weighted) return 1.0;
    const double len = std::hypot(vertices[e.s].x - vertices[e.t].x, vertices[e.s].y - vertices[e.t].y);
    if (len == 0.0) throw geometryError("zero-length edge in the weighted umbrella operator");
    return 1.0 / len;
  };
  for (const auto& e : edges) {
    const double w = weightOf(e);
    total[e.s] += w;
    total[e.t] += w;
  }
  // Rows of M: (M f)_k = Σ_l (ω_kl / W_k) c_l − c_k; vertices without edges have no row.
  std::vector<Triplet> triplets;
  triplets.reserve(edges.size() * 2 + n);
  for (std::size_t k = 0; k < n; ++k) {
    if (total[k] > 0.0) triplets.emplace_back(static_cast<int>(k), static_cast<int>(k), -1.0);
  }
  for (const auto& e : edges) {
    const double w = weightOf(e);
    triplets.emplace_back(static_cast<int>(e.s), static_cast<int>(e.t), w / total[e.s]);
    triplets.emplace_back(static_cast<int>(e.t), static_cast<int>(e.s), w / total[e.t]);
  }
  const SparseMatrix m = fromTriplets(n, triplets);
  SparseMatrix e = SparseMatrix(m.transpose()) * m;
  e.makeCompressed();
  return e;
}

std::array<double, 4> thinPlateBetas(const Point2& s, const Point2& t, const Point2& l, const Point2& r) {
  const double length = std::hypot(t.x - s.x, t.y - s.y);
  const double aLst = 0.5 * geometry::orient2dInexact(l, s, t);
  const double aRts = 0.5 * geometry::orient2dInexact(r, t, s);
  const double aTlr = 0.5 * geometry::orient2dInexact(t, l, r);
  const double aSrl = 0.5 * geometry::orient2dInexact(s, r, l);
  if (aLst <= 0.0 || aRts <= 0.0) throw geometryError("degenerate or clockwise triangle in the thin-plate energy");
  const double denom = 2.0 * aLst * aRts;
  return {length * aTlr / denom, length * aSrl / denom, -length / (2.0 * aLst), -length / (2.0 * aRts)};
}

SparseMatrix thinPlateEnergy(std::span<const Point2> vertices, std::span<const Triangle> triangles) {
  // E = DᵀD with one row d_e = √L_e β_e per interior edge e (4 entries, on the
  // stencil {s, t, l, r}), so that cᵀEc = Σ_e L_e (T_e f)². At the finest
  // levels of a fit this is the peak of its memory, so no row of D is
  // stored: first the pattern of E (row i's columns are the vertices of the
  // stencils that hold i, found through a vertex → edge index), written
  // straight into the matrix's own arrays, sized by a bound on its entries;
  // then each edge's row d_e, computed once in edge order, adds d_e,a · d_e,b
  // to its 16 entries. Each entry thus sums its terms in edge order from
  // 0, as a row-by-row product would: the same bits.
  const std::size_t n = vertices.size();
  std::vector<MeshEdge> edges = meshEdges(n, triangles);
  const std::size_t edgeCount = edges.size();
  std::erase_if(edges, [](const MeshEdge& e) { return e.right == MeshEdge::kNone; });
  const auto stencil = [](const MeshEdge& e) { return std::array{e.s, e.t, e.left, e.right}; };
  // Row i's columns are i, its neighbours (a stencil of an edge at i lies
  // in i's two triangles) and, per triangle at i, the vertex across its
  // opposite edge: at most 1 + deg(i) + (triangles at i), which sums to
  // n + 2·edges + 3·triangles. The room past the last entry is never written.
  const std::size_t bound = n + 2 * edgeCount + 3 * triangles.size();
  SparseMatrix energy(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  energy.resizeNonZeros(static_cast<Eigen::Index>(bound));
  SparseMatrix::StorageIndex* outer = energy.outerIndexPtr();
  SparseMatrix::StorageIndex* inner = energy.innerIndexPtr();
  double* value = energy.valuePtr();
  std::size_t entries = 0;
  {
    // edgesAt[start[i] .. start[i+1]) = the edges whose stencils hold i.
    std::vector<std::uint32_t> start(n + 1, 0);
    for (const MeshEdge& e : edges) {
      for (const std::uint32_t v : stencil(e)) ++start[v + 1];
    }
    for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    std::vector<std::uint32_t> edgesAt(start[n]);
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t k = 0; k < edges.size(); ++k) {
        for (const std::uint32_t v : stencil(edges[k]))
          edgesAt[fill[v]++] = static_cast<std::uint32_t>(k);
      }
    }
    std::vector<std::uint32_t> seenIn(n, std::numeric_limits<std::uint32_t>::max()), columns;
    for (std::size_t i = 0; i < n; ++i) {
      columns.clear();
      for (std::uint32_t q = start[i]; q < start[i + 1]; ++q) {
        for (const std::uint32_t j : stencil(edges[edgesAt[q]])) {
          if (seenIn[j] == i) continue;
          seenIn[j] = static_cast<std::uint32_t>(i);
          columns.push_back(j);
        }
      }
      if (entries + columns.size() > bound)
        throw internalError("thinPlateEnergy: more entries than the bound");
      std::sort(columns.begin(), columns.end());
      for (const std::uint32_t j : columns)
        inner[entries++] = static_cast<SparseMatrix::StorageIndex>(j);
      outer[i + 1] = static_cast<SparseMatrix::StorageIndex>(entries);
    }
  }
  std::fill(value, value + entries, 0.0);
  for (const MeshEdge& e : edges) {
    const auto beta =
        thinPlateBetas(vertices[e.s], vertices[e.t], vertices[e.left], vertices[e.right]);
    const double w =
        std::sqrt(std::hypot(vertices[e.t].x - vertices[e.s].x, vertices[e.t].y - vertices[e.s].y));
    // The stencil by vertex, each with its d: a row's four columns are then
    // found in one walk along it (its columns are sorted).
    std::array<std::pair<std::uint32_t, double>, 4> stencilD{
        {{e.s, w * beta[0]}, {e.t, w * beta[1]}, {e.left, w * beta[2]}, {e.right, w * beta[3]}}};
    std::sort(stencilD.begin(), stencilD.end());
    for (const auto& [i, di] : stencilD) {
      const SparseMatrix::StorageIndex* at = inner + outer[i];
      for (const auto& [j, dj] : stencilD) {
        while (static_cast<std::uint32_t>(*at) < j) ++at;
        value[at - inner] += di * dj;
      }
    }
  }
  energy.data().resize(static_cast<Eigen::Index>(entries));  // keeps the room: no copy
  return energy;
}

SparseMatrix smoothingMatrix(Smoothing kind, std::span<const Point2> vertices, std::span<const Triangle> triangles) {
  switch (kind) {
    case Smoothing::Membrane: return membraneEnergy(vertices, triangles);
    case Smoothing::Umbrella: return umbrellaEnergy(vertices, triangles, false);
    case Smoothing::UmbrellaWeighted: return umbrellaEnergy(vertices, triangles, true);
    case Smoothing::ThinPlate: return thinPlateEnergy(vertices, triangles);
    case Smoothing::None: break;
  }
  SparseMatrix m(static_cast<Eigen::Index>(vertices.size()), static_cast<Eigen::Index>(vertices.size()));
  return m;
}

double defaultLambda(const SparseMatrix& btb, const SparseMatrix& energy) {
  const double e = energy.norm();
  return e > 0.0 ? btb.norm() / e : 0.0;
}

void applyFixedVertices(SparseMatrix& a, Vector& b, std::span<const FixedVertex> fixed) {
  if (fixed.empty()) return;
  const auto n = static_cast<std::size_t>(a.rows());
  std::vector<char> isFixed(n, 0);
  Vector known = Vector::Zero(a.rows());
  for (const auto& f : fixed) {
    if (f.vertex >= n) {
      throw inputError("fixed vertex " + std::to_string(f.vertex) + " is not a vertex of the triangulation (" +
                       std::to_string(n) + " vertices)");
    }
    isFixed[f.vertex] = 1;
    known[f.vertex] = f.z;
  }
  for (Eigen::Index i = 0; i < a.outerSize(); ++i) {
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      const auto r = static_cast<std::size_t>(it.row()), c = static_cast<std::size_t>(it.col());
      if (isFixed[c] && !isFixed[r]) b[it.row()] -= it.value() * known[it.col()];
      if (isFixed[r] || isFixed[c]) it.valueRef() = r == c ? 1.0 : 0.0;
    }
  }
  for (const auto& f : fixed) {
    if (a.coeff(f.vertex, f.vertex) != 1.0) a.coeffRef(f.vertex, f.vertex) = 1.0;
    b[f.vertex] = f.z;
  }
}

namespace {

/// The diagonal of A; throws geometryError where it is not positive (an
/// unknown that neither data nor smoothing determine).
std::vector<double> positiveDiagonal(const SparseMatrix& a) {
  const Eigen::Index n = a.rows();
  std::vector<double> diagonal(static_cast<std::size_t>(n), 0.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      if (it.col() == i) diagonal[static_cast<std::size_t>(i)] = it.value();
    }
    if (!(diagonal[static_cast<std::size_t>(i)] > 0.0)) {
      throw geometryError("the least-squares system has no positive diagonal at unknown " + std::to_string(i), {},
                          "use a smoothing term (thin-plate, membrane or umbrella) when cells have no data");
    }
  }
  return diagonal;
}

/// The stopping rule of IterationControl, shared by both iterative solvers:
/// after a step that changed c by ‖Δc‖₂, stop when the relative improvement is
/// below its bound and then the relative residual is too (the residual is only
/// computed once the improvement is small).
struct StoppingRule {
  const SparseMatrix& a;
  const Vector& b;
  const IterationControl& control;
  double bNorm = std::max(b.norm(), 1e-300);

  [[nodiscard]] double relativeResidual(const Vector& c) const { return (b - a * c).norm() / bNorm; }

  bool done(const Vector& c, double change, SolveReport& report) const {
    if (change / std::max(c.norm(), 1e-300) >= control.relativeImprovement) return false;
    report.relativeResidual = relativeResidual(c);
    return report.relativeResidual < control.relativeResidual;
  }
};

SolveReport gaussSeidel(const SparseMatrix& a, const Vector& b, Vector& c, const IterationControl& control) {
  const Eigen::Index n = a.rows();
  const std::vector<double> diagonal = positiveDiagonal(a);
  const StoppingRule rule{a, b, control};
  SolveReport report;
  report.converged = false;
  for (int iter = 1; iter <= control.maxIterations; ++iter) {
    double change2 = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      double sum = b[i];
      for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
        if (it.col() != i) sum -= it.value() * c[it.col()];
      }
      const double next = sum / diagonal[static_cast<std::size_t>(i)];
      change2 += (next - c[i]) * (next - c[i]);
      c[i] = next;
    }
    report.iterations = iter;
    if (rule.done(c, std::sqrt(change2), report)) {
      report.converged = true;
      return report;
    }
  }
  report.relativeResidual = rule.relativeResidual(c);
  return report;
}

/// Conjugate gradients with the Jacobi preconditioner, from the given c, under
/// the same stopping rule as Gauss–Seidel. (A tolerance on ‖r‖/‖b‖ alone, as
/// Eigen's solver has, lets nested iteration stop before the first step: the
/// interpolated start of a new level is already close in that norm.)
SolveReport conjugateGradient(const SparseMatrix& a, const Vector& b, Vector& c, const IterationControl& control) {
  const std::vector<double> diagonal = positiveDiagonal(a);
  const Eigen::Map<const Vector> d(diagonal.data(), static_cast<Eigen::Index>(diagonal.size()));
  const StoppingRule rule{a, b, control};
  SolveReport report;
  report.converged = false;
  Vector r = b - a * c;
  Vector z = r.cwiseQuotient(d);
  Vector p = z;
  Vector q(b.size());
  double rz = r.dot(z);
  for (int iter = 1; iter <= control.maxIterations; ++iter) {
    report.iterations = iter;
    if (rz == 0.0) {  // exact solution reached
      report.relativeResidual = 0.0;
      report.converged = true;
      return report;
    }
    q.noalias() = a * p;
    const double alpha = rz / p.dot(q);
    c += alpha * p;
    r -= alpha * q;
    if (rule.done(c, std::abs(alpha) * p.norm(), report)) {
      report.converged = true;
      return report;
    }
    z = r.cwiseQuotient(d);
    const double rzNext = r.dot(z);
    p = z + (rzNext / rz) * p;
    rz = rzNext;
  }
  report.relativeResidual = rule.relativeResidual(c);
  return report;
}

}  // namespace

SolveReport solveSystem(const SparseMatrix& a, const Vector& b, Vector& c, SolverKind solver,
                        const IterationControl& control) {
  if (c.size() != b.size()) c = Vector::Zero(b.size());
  if (b.size() == 0) return {};
  switch (solver) {
    case SolverKind::Direct: {
      const Eigen::SparseMatrix<double, Eigen::ColMajor, int> colMajor = a;
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>> ldlt(colMajor);
      if (ldlt.info() != Eigen::Success || (ldlt.vectorD().array() <= 0.0).any()) {
        throw geometryError("the least-squares system is singular", {},
                            "use a smoothing term (thin-plate, membrane or umbrella) when some vertices have no data");
      }
      c = ldlt.solve(b);
      SolveReport report;
      report.relativeResidual = (b - a * c).norm() / std::max(b.norm(), 1e-300);
      return report;
    }
    case SolverKind::GaussSeidel: return gaussSeidel(a, b, c, control);
    case SolverKind::ConjugateGradient: return conjugateGradient(a, b, c, control);
  }
  return {};
}

LeastSquaresResult fitLeastSquares(std::span<const Point2> vertices, std::span<const Triangle> triangles,
                                   std::span<const Sample> samples, const LeastSquaresOptions& options,
                                   const Vector& initial) {
  // The multilevel fit's assembly: per-triangle moments, scattered into the
  // smoothing matrix's pattern (or alone without smoothing).
  const std::vector<TriangleMoments> moments = triangleMoments(vertices.size(), triangles, samples);
  LeastSquaresResult result;
  std::optional<SparseMatrix> energy;
  if (options.smoothing != Smoothing::None) {
    SparseMatrix built = smoothingMatrix(options.smoothing, vertices, triangles);
    energy.emplace().swap(built);  // swapped, not copied (see assembleSystem)
  }
  PenalizedSystem sys = assembleSystem(vertices.size(), triangles, moments, std::move(energy),
                                       options.lambdaFactor, options.lambdaAbsolute);
  result.lambdaDefault = sys.lambdaDefault;
  result.lambda = sys.lambda;
  SparseMatrix& a = sys.a;
  Vector& b = sys.b;
  applyFixedVertices(a, b, options.fixed);
  result.coefficients = initial.size() == b.size() ? initial : Vector::Zero(b.size());
  result.report = solveSystem(a, b, result.coefficients, options.solver, options.control);
  return result;
}

}  // namespace tinsmith::fit
