// Constrained Delaunay triangulation (see cdt.hpp for the contract).
//
// Working structure: triangle-based half-edges in flat arrays. Triangle t owns
// half-edges 3t..3t+2; half-edge 3t+i runs from corner i to corner (i+1)%3 with
// the triangle on its left. The convex hull is closed by ghost triangles whose
// third corner is the vertex at infinity (kInf), so every half-edge has a twin.
// Flips and splits reuse triangle slots; nothing is ever deleted.
#include "core/cdt/cdt.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>

#include "core/base/error.hpp"
#include "core/cdt/cdt_test_access.hpp"
#include "core/geometry/hilbert.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith {
namespace {

using geometry::hilbertIndex13;
using geometry::incircle;
using geometry::orient2d;

constexpr std::uint32_t kNone = 0xffffffffu;
constexpr std::uint32_t kInf = 0xfffffffeu;
// How deep reroutes of crossed constraints may nest (rerouteThrough inserts
// segments, whose crossings may reroute again): far beyond what input needs
// (the tests and two minutes of fuzzing never nest a second one), far below a
// stack overflow (a level takes about 1.2 KB of stack in an optimised build).
constexpr std::size_t kRerouteDepthLimit = 256;
// Feature id of the boundary edges of a TIN loaded by fromTinData: bounds the
// domain, never exported.
constexpr FeatureId kDomainFeature = 0xfffffffeu;

inline std::uint32_t nxt(std::uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
inline std::uint32_t prv(std::uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

inline std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

/// A bounding box that grows by points and boxes.
struct Box {
  double minX = INFINITY, minY = INFINITY, maxX = -INFINITY, maxY = -INFINITY;
  void add(const Point2& p) {
    minX = std::min(minX, p.x);
    maxX = std::max(maxX, p.x);
    minY = std::min(minY, p.y);
    maxY = std::max(maxY, p.y);
  }
  void add(const Box& b) {
    minX = std::min(minX, b.minX);
    maxX = std::max(maxX, b.maxX);
    minY = std::min(minY, b.minY);
    maxY = std::max(maxY, b.maxY);
  }
};

/// Hilbert index (hilbertIndex13) of points on a 2^13 grid over a box.
class HilbertGrid {
 public:
  explicit HilbertGrid(const Box& box)
      : box_(box),
        sx_(box.maxX > box.minX ? kGrid / (box.maxX - box.minX) : 0.0),
        sy_(box.maxY > box.minY ? kGrid / (box.maxY - box.minY) : 0.0) {}
  [[nodiscard]] std::uint32_t operator()(const Point2& p) const {
    const auto gx = static_cast<std::uint32_t>(std::min(kGrid, (p.x - box_.minX) * sx_));
    const auto gy = static_cast<std::uint32_t>(std::min(kGrid, (p.y - box_.minY) * sy_));
    return hilbertIndex13(gx, gy);
  }

 private:
  static constexpr double kGrid = 8191.0;
  Box box_;
  double sx_, sy_;
};

/// Runs f(chunk, begin, end) over [0, n) split into `threads` contiguous
/// chunks (chunk k on its own thread; chunk 0 on the caller's). Chunk bounds
/// depend only on n and threads.
template <class F>
void parallelChunks(unsigned threads, std::size_t n, const F& f) {
  if (threads <= 1 || n < 4096) {
    f(0u, std::size_t{0}, n);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  for (unsigned k = 1; k < threads; ++k) {
    pool.emplace_back([&f, k, n, threads] { f(k, n * k / threads, n * (k + 1) / threads); });
  }
  f(0u, std::size_t{0}, n / threads);
  for (auto& t : pool) t.join();
}

// LSD radix sort of 64-bit values on their upper 32 bits (stable). With
// several threads each sorts its chunk's share into place through per-chunk
// bucket offsets, so the result is the same for any thread count.
void radixSortHigh32(std::vector<std::uint64_t>& v, unsigned threads) {
  std::vector<std::uint64_t> tmp(v.size());
  if (v.size() < 4096) threads = 1;
  std::vector<std::array<std::size_t, 256>> count(threads);
  for (int shift = 32; shift < 64; shift += 8) {
    parallelChunks(threads, v.size(), [&](unsigned k, std::size_t b, std::size_t e) {
      count[k].fill(0);
      for (std::size_t i = b; i < e; ++i) ++count[k][(v[i] >> shift) & 0xff];
    });
    std::size_t sum = 0;
    for (int d = 0; d < 256; ++d) {
      for (unsigned k = 0; k < threads; ++k) {
        const std::size_t c = count[k][d];
        count[k][d] = sum;
        sum += c;
      }
    }
    parallelChunks(threads, v.size(), [&](unsigned k, std::size_t b, std::size_t e) {
      auto& off = count[k];
      for (std::size_t i = b; i < e; ++i) tmp[off[(v[i] >> shift) & 0xff]++] = v[i];
    });
    v.swap(tmp);
  }
}

/// Features of constrained edges, keyed by edgeKey. Most edges carry one
/// feature, stored inline; edges shared by several features point to an
/// immutable list (copy on write, so split halves may share one). An open
/// addressing table (linear probing, 16 bytes a slot, at most 7/8 full):
/// terrain inputs constrain about one edge per vertex.
class EdgeFeatureMap {
 public:
  struct View {
    const FeatureId* data = nullptr;
    std::size_t size = 0;
    [[nodiscard]] const FeatureId* begin() const { return data; }
    [[nodiscard]] const FeatureId* end() const { return data + size; }
    [[nodiscard]] bool empty() const { return size == 0; }
  };

  [[nodiscard]] View find(std::uint64_t key) const {
    const std::size_t i = slotOf(key);
    if (i == kMissing) return {};
    return view(slots_[i].entry);
  }
  void add(std::uint64_t key, FeatureId f) {
    std::size_t i = slotOf(key);
    if (i == kMissing) {
      insertNew(key, {f, kNoList});
      return;
    }
    Entry& e = slots_[i].entry;
    if (e.list == kNoList) {
      if (e.single == f) return;
      lists_.push_back({e.single, f});
    } else {
      const auto& old = lists_[e.list];
      if (std::find(old.begin(), old.end(), f) != old.end()) return;
      std::vector<FeatureId> l = old;
      l.push_back(f);
      lists_.push_back(std::move(l));
    }
    e.list = static_cast<std::uint32_t>(lists_.size() - 1);
  }
  void erase(std::uint64_t key) {
    const std::size_t i = slotOf(key);
    if (i != kMissing) eraseAt(i);
  }
  /// The edge `from` was split into `a` and `b`: both inherit its features.
  void split(std::uint64_t from, std::uint64_t a, std::uint64_t b) {
    const std::size_t i = slotOf(from);
    if (i == kMissing) return;
    const Entry e = slots_[i].entry;
    eraseAt(i);
    set(a, e);
    set(b, e);
  }
  /// Room for n edges without growing (growing holds both tables at once).
  void reserve(std::size_t n) {
    std::size_t capacity = 64;
    while (8 * n > 7 * capacity) capacity *= 2;
    if (capacity > slots_.size()) rehash(capacity);
  }
  /// Calls f(key, features) for every edge.
  template <class F>
  void forEach(const F& f) const {
    for (const Slot& sl : slots_) {
      if (sl.key != kEmpty) f(sl.key, view(sl.entry));
    }
  }

 private:
  static constexpr std::uint32_t kNoList = 0xffffffffu;
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // no edgeKey is this
  static constexpr std::size_t kMissing = ~std::size_t{0};
  struct Entry {
    FeatureId single;
    std::uint32_t list;
  };
  struct Slot {
    std::uint64_t key = kEmpty;
    Entry entry{};
  };

  [[nodiscard]] View view(const Entry& e) const {
    if (e.list == kNoList) return {&e.single, 1};
    const auto& l = lists_[e.list];
    return {l.data(), l.size()};
  }
  [[nodiscard]] std::size_t hash(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  [[nodiscard]] std::size_t slotOf(std::uint64_t key) const {
    if (slots_.empty()) return kMissing;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(key);; i = (i + 1) & mask) {
      if (slots_[i].key == key) return i;
      if (slots_[i].key == kEmpty) return kMissing;
    }
  }
  /// Backward-shift deletion: later entries of the probe run move forward.
  void eraseAt(std::size_t i) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t j = (i + 1) & mask; slots_[j].key != kEmpty; j = (j + 1) & mask) {
      const std::size_t home = hash(slots_[j].key);
      if (((j - home) & mask) >= ((j - i) & mask)) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i].key = kEmpty;
    --size_;
  }
  void set(std::uint64_t key, const Entry& e) {
    const std::size_t i = slotOf(key);
    if (i == kMissing) {
      insertNew(key, e);
    } else {
      slots_[i].entry = e;
    }
  }
  void insertNew(std::uint64_t key, const Entry& e) {
    if (8 * (size_ + 1) > 7 * slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = hash(key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask;
    slots_[i] = {key, e};
    ++size_;
  }
  void grow() { rehash(slots_.empty() ? 64 : 2 * slots_.size()); }
  void rehash(std::size_t capacity) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(capacity, Slot{});
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
    for (const Slot& sl : old) {
      if (sl.key != kEmpty) insertNew(sl.key, sl.entry);
    }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  int shift_ = 64;
  std::vector<std::vector<FeatureId>> lists_;
};

enum class Role : std::uint8_t { None, Boundary, Hole };

/// An input constraint segment between input vertices (its role in the
/// domain is its feature's, featureRole).
struct Segment {
  std::uint32_t a, b;
  FeatureId feature;
};

enum class LocKind { InTriangle, OnEdge, OnVertex, Outside };
struct Location {
  LocKind kind;
  std::uint32_t t;  // triangle (InTriangle, Outside: the ghost)
  std::uint32_t h;  // half-edge (OnEdge), in a finite triangle
  std::uint32_t v;  // vertex (OnVertex)
};

}  // namespace

struct Cdt::Impl {
  CdtOptions options;
  std::vector<TinFeature> features;
  std::vector<Role> featureRole;  // per feature: bounds the domain (boundary, hole) or not

  // Input vertices (intersection vertices are appended).
  std::vector<Point2> xy;
  std::vector<double> z;
  std::vector<FeatureId> vfeat;
  std::vector<std::uint32_t> rep;  // kNone while pending; self if a vertex; else merged into
  std::vector<std::uint32_t> vhe;  // an outgoing half-edge of each live vertex
  std::size_t insertedUpTo = 0;

  // Triangles.
  std::vector<std::uint32_t> tv;   // corners
  std::vector<std::uint32_t> opp;  // twin half-edge
  std::vector<std::uint8_t> cons;  // constrained flag per half-edge
  EdgeFeatureMap edgeFeatures;

  std::vector<Segment> segments;
  std::size_t segmentsDone = 0;
  bool hasBoundary = false, hasHole = false;

  CdtReport report;
  std::unordered_map<std::uint32_t, std::uint32_t> zSource;  // vertex → input its z came from
  // Per feature: how far its constraints were bent by taking in apexes beside
  // them, beyond what report.intersections records (crossingVertex); the
  // validator allows that much more.
  std::vector<double> bend;
  // Reroutes under way (rerouteThrough), their bound and the deepest so far.
  std::size_t rerouteDepth = 0, rerouteDepthLimit = kRerouteDepthLimit, deepestReroute = 0;
  Mesh mesh;
  std::vector<std::uint32_t> meshOf;  // input vertex → mesh vertex (kNone if none)
  // finalize() has run and no input came after it: the mesh may be read.
  bool finalized = false;
  // Input (points, constraints, domain rings) came since the last finalize().
  bool changed = false;
  // The const readers (mesh(), report(), meshVertex()) build the mesh on first
  // use, possibly on several threads at once: one builds it under the lock,
  // the others wait for it (buildMesh).
  std::atomic<bool> meshBuilt = false;
  std::mutex meshMutex;

  // After buildMesh() the working triangle arrays live in `mesh` (compacted);
  // the triangles left out (ghosts, outside the domain) are kept here with
  // their slots so that unpack() restores the working arrays exactly.
  struct RemovedTriangle {
    std::uint32_t slot;
    std::uint32_t tv[3];
    std::uint32_t opp[3];
    std::uint8_t cons[3];
  };
  std::vector<RemovedTriangle> removed;
  bool packed = false;
  std::uint32_t packedTriangles = 0;

  std::uint32_t lastTriangle = 0;
  bool trackVhe = false;  // vhe is maintained only while constraints go in
  std::uint32_t rng = 2463534242u;
  std::vector<std::uint32_t> stack;
  // Scratch of nearVertex(): triangles to visit, and those visited (marked
  // meanwhile by bit 1 of cons[3t], which nearVertex() clears again).
  std::vector<std::uint32_t> nearTodo, nearSeen;
  static constexpr std::uint8_t kSeen = 2;

  /// Takes the triangles back from the output mesh (inverse of the
  /// compaction in buildMesh): the working arrays become exactly what they
  /// were before the mesh was built.
  void unpack() {
    if (!packed) return;
    const std::uint32_t outT = packedTriangles;
    const auto nt = static_cast<std::uint32_t>(outT + removed.size());
    // Mesh vertex → working vertex (live roots only have mesh vertices).
    std::vector<std::uint32_t> inv(mesh.points_.size(), kNone);
    for (std::uint32_t v = 0; v < rep.size(); ++v) {
      if (rep[v] == v && meshOf[v] != kNone) inv[meshOf[v]] = v;
    }
    tv = std::move(mesh.corners_);
    opp = std::move(mesh.twins_);
    mesh = Mesh();
    meshBuilt = false;
    tv.resize(3 * static_cast<std::size_t>(nt));
    opp.resize(3 * static_cast<std::size_t>(nt));
    cons.resize(3 * static_cast<std::size_t>(nt));
    std::vector<std::uint32_t> slotOf(outT);
    // Back to front: kept triangle o moves to slot t >= o.
    std::size_t r = removed.size();
    std::uint32_t o = outT;
    for (std::uint32_t t = nt; t-- > 0;) {
      if (r > 0 && removed[r - 1].slot == t) {
        --r;
        continue;  // filled below
      }
      --o;
      slotOf[o] = t;
      for (std::uint32_t i = 0; i < 3; ++i) {
        tv[3 * t + i] = inv[tv[3 * o + i]];
        opp[3 * t + i] = opp[3 * o + i];  // a mesh half-edge id; remapped below
        cons[3 * t + i] = cons[3 * o + i];
      }
    }
    r = 0;
    for (std::uint32_t t = 0; t < nt; ++t) {
      if (r < removed.size() && removed[r].slot == t) {
        ++r;
        continue;
      }
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t g = opp[3 * t + i];
        if (g != kNone) opp[3 * t + i] = 3 * slotOf[g / 3] + g % 3;
      }
    }
    for (const RemovedTriangle& x : removed) {
      for (std::uint32_t i = 0; i < 3; ++i) {
        tv[3 * x.slot + i] = x.tv[i];
        cons[3 * x.slot + i] = x.cons[i];
        link(3 * x.slot + i, x.opp[i]);
      }
    }
    std::vector<RemovedTriangle>().swap(removed);
    packed = false;
  }

  // ---------------------------------------------------------------- basics
  /// New input: the mesh is out of date until the next finalize().
  void inputAdded() {
    finalized = false;
    changed = true;
  }
  /// Throws what Cdt::insertPoint documents unless p can become input vertex
  /// `id` of `feature`.
  void checkPoint(const Point3& p, FeatureId feature, std::size_t id) const;
  /// Appends points as input vertices, all or none: every one is checked
  /// before the first goes in.
  VertexId appendPoints(std::span<const Point3> points, FeatureId feature);
  [[nodiscard]] bool triangulated() const { return !tv.empty(); }
  [[nodiscard]] std::uint32_t triCount() const { return static_cast<std::uint32_t>(tv.size() / 3); }
  [[nodiscard]] bool isGhost(std::uint32_t t) const {
    return tv[3 * t] == kInf || tv[3 * t + 1] == kInf || tv[3 * t + 2] == kInf;
  }
  std::uint32_t nextRandom() {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
  }
  int orient(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    return orient2d(xy[a], xy[b], xy[c]);
  }
  int orientP(std::uint32_t a, std::uint32_t b, const Point2& p) const {
    return orient2d(xy[a], xy[b], p);
  }
  static int priorityOf(const std::vector<TinFeature>& fs, FeatureId f) {
    return f == kNoFeature || f >= fs.size() ? -1 : constraintPriority(fs[f].kind);
  }
  std::uint32_t find(std::uint32_t v) {
    std::uint32_t r = v;
    while (rep[r] != r) r = rep[r];
    while (rep[v] != r) {
      const std::uint32_t n = rep[v];
      rep[v] = r;
      v = n;
    }
    return r;
  }

  std::uint32_t newTriangle() {
    const auto t = triCount();
    for (int i = 0; i < 3; ++i) {
      tv.push_back(kNone);
      opp.push_back(kNone);
      cons.push_back(0);
    }
    return t;
  }
  void setTri(std::uint32_t t, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    tv[3 * t] = a;
    tv[3 * t + 1] = b;
    tv[3 * t + 2] = c;
    if (trackVhe) {
      if (a != kInf) vhe[a] = 3 * t;
      if (b != kInf) vhe[b] = 3 * t + 1;
      if (c != kInf) vhe[c] = 3 * t + 2;
    }
  }
  /// Recomputes vhe from the triangles and keeps it current from now on
  /// (bulk point insertion does not need it and skips the upkeep).
  void startTrackingVhe() {
    if (trackVhe) return;
    vhe.assign(xy.size(), kNone);
    for (std::uint32_t h = 0; h < tv.size(); ++h) {
      if (tv[h] != kInf) vhe[tv[h]] = h;
    }
    trackVhe = true;
  }
  void link(std::uint32_t h, std::uint32_t g) {
    opp[h] = g;
    opp[g] = h;
  }

  /// Is p in conflict with triangle t (inside its circumcircle, or for a ghost
  /// strictly outside its hull edge, or on the open hull edge)?
  inline bool inConflict(std::uint32_t t, const Point2& p) const {
    const std::uint32_t a = tv[3 * t], b = tv[3 * t + 1], c = tv[3 * t + 2];
    if (std::max(a, std::max(b, c)) < kInf) [[likely]] {
      return incircle(xy[a], xy[b], xy[c], p) > 0;
    }
    std::uint32_t u, v;
    if (a == kInf) {
      u = b, v = c;
    } else if (b == kInf) {
      u = c, v = a;
    } else if (c == kInf) {
      u = a, v = b;
    } else {
      return incircle(xy[a], xy[b], xy[c], p) > 0;
    }
    const int o = orientP(u, v, p);
    if (o != 0) return o > 0;
    const Point2 &pu = xy[u], &pv = xy[v];
    return std::min(pu.x, pv.x) <= p.x && p.x <= std::max(pu.x, pv.x) &&
           std::min(pu.y, pv.y) <= p.y && p.y <= std::max(pu.y, pv.y) && !(p == pu) &&
           !(p == pv);
  }

  // --------------------------------------------------------------- flips
  /// Flips the edge of half-edge h (a→b in (a,b,c); twin in (b,a,d)) to c–d.
  /// Afterwards triangle h/3 = (c,a,d) and twin's triangle = (d,b,c).
  void flip(std::uint32_t h) {
    const std::uint32_t g = opp[h];
    const std::uint32_t t0 = h / 3, t1 = g / 3;
    const std::uint32_t a = tv[h], b = tv[nxt(h)], c = tv[prv(h)], d = tv[prv(g)];
    const std::uint32_t x1 = opp[nxt(h)], x2 = opp[prv(h)], x3 = opp[nxt(g)], x4 = opp[prv(g)];
    const std::uint8_t c1 = cons[nxt(h)], c2 = cons[prv(h)], c3 = cons[nxt(g)], c4 = cons[prv(g)];
    setTri(t0, c, a, d);
    setTri(t1, d, b, c);
    const std::uint32_t b0 = 3 * t0, b1 = 3 * t1;
    link(b0, x2);
    cons[b0] = c2;
    link(b0 + 1, x3);
    cons[b0 + 1] = c3;
    link(b0 + 2, b1 + 2);
    cons[b0 + 2] = 0;
    cons[b1 + 2] = 0;
    link(b1, x4);
    cons[b1] = c4;
    link(b1 + 1, x1);
    cons[b1 + 1] = c1;
  }

  /// Restores the (constrained) Delaunay property around vertex p after the
  /// half-edges on `stack` (each opposite p in its triangle) were created.
  void legalize(std::uint32_t p) {
    const Point2 pp = xy[p];
    while (!stack.empty()) {
      const std::uint32_t h = stack.back();
      stack.pop_back();
      if (cons[h]) continue;
      const std::uint32_t g = opp[h];
      if (!inConflict(g / 3, pp)) continue;
      flip(h);
      // p is corner 0 of triangle h/3 = (p,a,d) and corner 2 of (d,b,p).
      stack.push_back(3 * (h / 3) + 1);
      stack.push_back(3 * (g / 3));
    }
  }

  // -------------------------------------------------------------- splits
  /// Splits triangle t = (a,b,c) at new vertex p into (a,b,p), (b,c,p), (c,a,p).
  void splitTriangle(std::uint32_t t, std::uint32_t p) {
    const std::uint32_t a = tv[3 * t], b = tv[3 * t + 1], c = tv[3 * t + 2];
    const std::uint32_t o0 = opp[3 * t], o1 = opp[3 * t + 1], o2 = opp[3 * t + 2];
    const std::uint8_t c0 = cons[3 * t], c1 = cons[3 * t + 1], c2 = cons[3 * t + 2];
    const std::uint32_t n1 = newTriangle(), n2 = newTriangle();
    setTri(t, a, b, p);
    setTri(n1, b, c, p);
    setTri(n2, c, a, p);
    link(3 * t, o0);
    cons[3 * t] = c0;
    link(3 * n1, o1);
    cons[3 * n1] = c1;
    link(3 * n2, o2);
    cons[3 * n2] = c2;
    cons[3 * t + 1] = cons[3 * t + 2] = 0;  // the reused slot's inner edges are new
    link(3 * t + 1, 3 * n1 + 2);
    link(3 * t + 2, 3 * n2 + 1);
    link(3 * n1 + 1, 3 * n2 + 2);
    stack.clear();
    stack.push_back(3 * t);
    stack.push_back(3 * n1);
    stack.push_back(3 * n2);
    legalize(p);
  }

  /// Splits the edge of half-edge h (a→b in (a,b,c), twin in (b,a,d)) at new
  /// vertex p; a constrained edge stays constrained in both halves.
  void splitEdge(std::uint32_t h, std::uint32_t p) {
    const std::uint32_t g = opp[h];
    const std::uint32_t t0 = h / 3, t1 = g / 3;
    const std::uint32_t a = tv[h], b = tv[nxt(h)], c = tv[prv(h)], d = tv[prv(g)];
    const std::uint32_t xbc = opp[nxt(h)], xca = opp[prv(h)], xad = opp[nxt(g)],
                        xdb = opp[prv(g)];
    const std::uint8_t cbc = cons[nxt(h)], cca = cons[prv(h)], cad = cons[nxt(g)],
                       cdb = cons[prv(g)];
    const std::uint8_t split = cons[h];
    const std::uint32_t n0 = newTriangle(), n1 = newTriangle();
    setTri(t0, c, a, p);
    setTri(n0, b, c, p);
    setTri(t1, d, b, p);
    setTri(n1, a, d, p);
    link(3 * t0, xca);
    cons[3 * t0] = cca;
    link(3 * n0, xbc);
    cons[3 * n0] = cbc;
    link(3 * t1, xdb);
    cons[3 * t1] = cdb;
    link(3 * n1, xad);
    cons[3 * n1] = cad;
    link(3 * t0 + 1, 3 * n1 + 2);  // a→p / p→a
    link(3 * t0 + 2, 3 * n0 + 1);  // p→c / c→p
    link(3 * n0 + 2, 3 * t1 + 1);  // p→b / b→p
    link(3 * t1 + 2, 3 * n1 + 1);  // p→d / d→p
    cons[3 * t0 + 2] = cons[3 * n0 + 1] = cons[3 * t1 + 2] = cons[3 * n1 + 1] = 0;
    cons[3 * t0 + 1] = cons[3 * n1 + 2] = cons[3 * n0 + 2] = cons[3 * t1 + 1] = split;
    if (split) {
      edgeFeatures.split(edgeKey(a, b), edgeKey(a, p), edgeKey(p, b));
    }
    stack.clear();
    stack.push_back(3 * t0);
    stack.push_back(3 * n0);
    stack.push_back(3 * t1);
    stack.push_back(3 * n1);
    legalize(p);
  }

  // ------------------------------------------------------------ location
  Location classify(std::uint32_t t, const Point2& p) const {
    const std::uint32_t base = 3 * t;
    int o[3];
    for (int i = 0; i < 3; ++i) o[i] = orientP(tv[base + i], tv[base + (i + 1) % 3], p);
    const int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
    if (zeros == 0) return {LocKind::InTriangle, t, kNone, kNone};
    if (zeros == 1) {
      for (std::uint32_t i = 0; i < 3; ++i) {
        if (o[i] == 0) return {LocKind::OnEdge, t, base + i, kNone};
      }
    }
    // Two zeros: p is the corner shared by those edges.
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (o[i] == 0 && o[(i + 2) % 3] == 0) return {LocKind::OnVertex, t, kNone, tv[base + i]};
    }
    return {LocKind::OnVertex, t, kNone, tv[base]};
  }

  /// The finite edge u→v of ghost triangle t.
  std::uint32_t ghostEdge(std::uint32_t t) const {
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (tv[3 * t + i] != kInf && tv[3 * t + (i + 1) % 3] != kInf) return 3 * t + i;
    }
    return kNone;
  }

  /// Visibility walk from triangle `start` (stochastic edge order from a fixed
  /// seed — deterministic and it cannot cycle for ever); falls back to a scan
  /// of all triangles after too many steps.
  Location locate(const Point2& p, std::uint32_t start) {
    std::uint32_t t = start;
    std::uint32_t from = kNone;  // half-edge we entered through
    const std::size_t limit = 4 * static_cast<std::size_t>(triCount()) + 64;
    for (std::size_t steps = 0; steps < limit; ++steps) {
      if (isGhost(t)) {
        const std::uint32_t e = ghostEdge(t);
        if (orientP(tv[e], tv[nxt(e)], p) > 0) return {LocKind::Outside, t, kNone, kNone};
        from = opp[e];
        t = from / 3;
        continue;
      }
      const std::uint32_t r = nextRandom() % 3;
      bool moved = false;
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t h = 3 * t + (r + k) % 3;
        if (h == from) continue;
        if (orientP(tv[h], tv[nxt(h)], p) < 0) {
          from = opp[h];
          t = from / 3;
          if (isGhost(t)) return {LocKind::Outside, t, kNone, kNone};
          moved = true;
          break;
        }
      }
      if (!moved) return classify(t, p);
    }
    return scan(p);
  }

  Location scan(const Point2& p) const {
    for (std::uint32_t t = 0; t < triCount(); ++t) {
      if (isGhost(t)) continue;
      bool inside = true;
      for (std::uint32_t i = 0; i < 3 && inside; ++i) {
        inside = orientP(tv[3 * t + i], tv[3 * t + (i + 1) % 3], p) >= 0;
      }
      if (inside) return classify(t, p);
    }
    for (std::uint32_t t = 0; t < triCount(); ++t) {
      if (!isGhost(t)) continue;
      const std::uint32_t e = ghostEdge(t);
      if (orientP(tv[e], tv[nxt(e)], p) > 0) return {LocKind::Outside, t, kNone, kNone};
    }
    throw internalError("point location failed: the point is in no triangle");
  }

  // ----------------------------------------------------------- insertion
  /// Merges input vertex `dup` into live vertex `keep`, z by priority.
  void merge(std::uint32_t dup, std::uint32_t keep) {
    rep[dup] = keep;
    CdtReport::Merge m;
    m.at = xy[keep];
    m.kept = VertexId(keep);
    m.merged = VertexId(dup);
    const int pd = priorityOf(features, vfeat[dup]), pk = priorityOf(features, vfeat[keep]);
    double droppedZ = z[dup];
    FeatureId droppedF = vfeat[dup];
    // Which input the kept z came from (ties go to the earlier input).
    auto src = zSource.find(keep);
    const std::uint32_t from = src == zSource.end() ? keep : src->second;
    if (pd > pk || (pd == pk && dup < from)) {
      droppedZ = z[keep];
      droppedF = vfeat[keep];
      z[keep] = z[dup];
      vfeat[keep] = vfeat[dup];
      zSource[keep] = dup;
    }
    m.keptZ = z[keep];
    m.droppedZ = droppedZ;
    m.keptFeature = vfeat[keep];
    m.droppedFeature = droppedF;
    report.merges.push_back(m);
  }

  /// A live vertex within snapTolerance of p near location `loc`, or kNone.
  /// Looks at the vertices of every triangle in conflict with p reachable from
  /// the located one (p's Delaunay neighbours-to-be, which contain its nearest
  /// vertex).
  std::uint32_t nearVertex(const Point2& p, const Location& loc) {
    const double tol = options.snapTolerance;
    if (!(tol > 0)) return kNone;
    nearTodo.assign({loc.t});
    if (loc.kind == LocKind::OnEdge) nearTodo.push_back(opp[loc.h] / 3);
    nearSeen.clear();
    std::uint32_t best = kNone;
    double bestD = tol * tol;
    while (!nearTodo.empty() && nearSeen.size() < 4096) {
      const std::uint32_t t = nearTodo.back();
      nearTodo.pop_back();
      if (cons[3 * t] & kSeen) continue;
      cons[3 * t] |= kSeen;
      nearSeen.push_back(t);
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t v = tv[3 * t + i];
        if (v == kInf) continue;
        const double dx = xy[v].x - p.x, dy = xy[v].y - p.y;
        const double d = dx * dx + dy * dy;
        if (d <= bestD && (best == kNone || d < bestD || v < best)) {
          best = v;
          bestD = d;
        }
        const std::uint32_t n = opp[3 * t + i] / 3;
        if (!(cons[3 * n] & kSeen) && inConflict(n, p)) nearTodo.push_back(n);
      }
    }
    for (const std::uint32_t t : nearSeen) cons[3 * t] &= ~kSeen;
    return best;
  }

  /// Inserts input vertex v (rep[v] == kNone) into the triangulation.
  void insertVertex(std::uint32_t v) {
    const Point2 p = xy[v];
    const Location loc = locate(p, lastTriangle);
    if (loc.kind == LocKind::OnVertex) {
      merge(v, loc.v);
      lastTriangle = loc.t;
      return;
    }
    const std::uint32_t nearV = nearVertex(p, loc);
    if (nearV != kNone) {
      merge(v, nearV);
      lastTriangle = loc.t;
      return;
    }
    rep[v] = v;
    // After the flips, the split triangle's slot still touches v's
    // neighbourhood: a good start for the next walk.
    if (loc.kind == LocKind::OnEdge) {
      lastTriangle = loc.h / 3;
      splitEdge(loc.h, v);
    } else {
      lastTriangle = loc.t;
      splitTriangle(loc.t, v);
    }
  }

  /// Positions ib, ic in `order` such that order[0], order[ib], order[ic] are
  /// distinct and not collinear; false when every point of `order` lies on
  /// one line.
  bool findFirstTriangle(const std::vector<std::uint32_t>& order, std::size_t& ib,
                         std::size_t& ic) const {
    const std::uint32_t a = order[0];
    ib = kNone;
    ic = kNone;
    for (std::size_t i = 1; i < order.size(); ++i) {
      if (!(xy[order[i]] == xy[a])) {
        ib = i;
        break;
      }
    }
    if (ib == kNone) return false;
    for (std::size_t i = ib + 1; i < order.size(); ++i) {
      if (orient(a, order[ib], order[i]) != 0) {
        ic = i;
        return true;
      }
    }
    return false;
  }

  /// Builds the first triangle from pending vertices in `order`; returns the
  /// three used, or throws when all pending points are collinear.
  void initialTriangle(const std::vector<std::uint32_t>& order, std::size_t& usedA,
                       std::size_t& usedB, std::size_t& usedC) {
    const std::uint32_t a = order[0];
    std::size_t ib = kNone, ic = kNone;
    if (!findFirstTriangle(order, ib, ic)) {
      throw geometryError(
          "the input has fewer than 3 non-collinear distinct points (" +
              std::to_string(order.size()) + " points given)",
          {}, "give at least three points that do not lie on one line");
    }
    std::uint32_t b = order[ib], c = order[ic];
    if (orient(a, b, c) < 0) std::swap(b, c);
    usedA = 0;
    usedB = ib;
    usedC = ic;
    for (std::uint32_t v : {a, b, c}) rep[v] = v;
    const std::uint32_t t = newTriangle(), g0 = newTriangle(), g1 = newTriangle(),
                        g2 = newTriangle();
    setTri(g0, b, a, kInf);
    setTri(g1, c, b, kInf);
    setTri(g2, a, c, kInf);
    setTri(t, a, b, c);
    link(3 * t, 3 * g0);
    link(3 * t + 1, 3 * g1);
    link(3 * t + 2, 3 * g2);
    link(3 * g0 + 1, 3 * g2 + 2);
    link(3 * g0 + 2, 3 * g1 + 1);
    link(3 * g1 + 2, 3 * g2 + 1);
    lastTriangle = t;
  }

  [[nodiscard]] unsigned threadCount() const {
    if (options.threads != 0) return options.threads;
    return std::max(1u, std::thread::hardware_concurrency());
  }

  void insertPendingPoints() {
    const std::size_t n = xy.size();
    if (insertedUpTo >= n) return;
    const unsigned threads = threadCount();
    const std::size_t count = n - insertedUpTo;
    std::vector<Box> boxes(threads);
    parallelChunks(threads, count, [&](unsigned k, std::size_t b, std::size_t e) {
      for (std::size_t i = insertedUpTo + b; i < insertedUpTo + e; ++i) {
        if (rep[i] == kNone) boxes[k].add(xy[i]);
      }
    });
    Box box;
    for (const Box& bx : boxes) box.add(bx);
    // BRIO (biased randomized insertion order): point i goes to round k with
    // probability 2^-(k+1) (from a fixed hash of i, so deterministic); rounds
    // go in from the smallest, each in Hilbert order on a 2^13 grid over the
    // bounding box (ties keep input order). Random rounds keep the number of
    // flips per insertion near the random-order expectation; the Hilbert order
    // keeps walks short.
    const HilbertGrid hilbert(box);
    std::uint32_t rounds = 0;
    while (rounds < 20 && (std::size_t{1000} << rounds) < count) ++rounds;
    // Points already placed (merged during an earlier finalize) get the key
    // 0xffffffff: they sort last and are cut off.
    constexpr std::uint64_t kSkip = 0xffffffffull << 32;
    std::vector<std::uint64_t> keys(count);
    parallelChunks(threads, count, [&](unsigned, std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) {
        const std::size_t i = insertedUpTo + j;
        if (rep[i] != kNone) {
          keys[j] = kSkip | i;
          continue;
        }
        std::uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
        h ^= h >> 31;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 29;
        const auto round = static_cast<std::uint32_t>(std::min<int>(
            std::countr_zero(h | (std::uint64_t{1} << 40)), static_cast<int>(rounds)));
        const std::uint32_t key = ((rounds - round) << 26) | hilbert(xy[i]);
        keys[j] = (static_cast<std::uint64_t>(key) << 32) | i;
      }
    });
    radixSortHigh32(keys, threads);
    std::vector<std::uint32_t> order;
    order.reserve(count);
    for (std::uint64_t k : keys) {
      if ((k & kSkip) == kSkip) break;
      order.push_back(static_cast<std::uint32_t>(k & 0xffffffffu));
    }
    std::vector<std::uint64_t>().swap(keys);
    trackVhe = false;
    insertedUpTo = n;
    if (order.empty()) return;

    if (!triangulated()) {
      reserveTriangles(trianglesFor(order.size(), segments.size() - segmentsDone));
      edgeFeatures.reserve(segments.size() - segmentsDone);
      if (options.splitMinPoints > 0 && order.size() >= options.splitMinPoints &&
          insertAsTwoHalves(order)) {
        return;
      }
    }
    insertInOrder(order);
  }

  /// Triangles to reserve for a first bulk: 2 per point, plus room for
  /// constraint crossings (2 triangles each; up to 16 per segment, at most
  /// one per point) so that the arrays rarely grow: a doubling would briefly
  /// hold both copies, while capacity never used costs address space only
  /// (its pages are never touched).
  static std::size_t trianglesFor(std::size_t points, std::size_t segments) {
    return 2 * points + 4 + std::min(32 * segments, points);
  }
  void reserveTriangles(std::size_t triangles) {
    tv.reserve(3 * triangles);
    opp.reserve(3 * triangles);
    cons.reserve(3 * triangles);
  }

  /// Inserts the pending vertices `order` in that order (starting the
  /// triangulation with its first non-degenerate triple if there is none).
  void insertInOrder(const std::vector<std::uint32_t>& order) {
    std::size_t skipA = kNone, skipB = kNone, skipC = kNone;
    if (!triangulated()) initialTriangle(order, skipA, skipB, skipC);
    // The insertion order jumps around the input arrays: fetch ahead.
    constexpr std::size_t kAhead = 8;
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (i + kAhead < order.size()) {
        __builtin_prefetch(&xy[order[i + kAhead]]);
        __builtin_prefetch(&rep[order[i + kAhead]], 1);
      }
      if (i == skipA || i == skipB || i == skipC) continue;
      insertVertex(order[i]);
    }
  }

  // ------------------------------------------------- two-half bulk build
  // The first bulk of points may be triangulated as two halves on either side
  // of a vertical line x = xr, each on its own thread, and then merged by
  // repairing the seam between them:
  //   * a triangle of DT(left) whose circumcircle lies strictly left of every
  //     right point is a triangle of DT(all) — "safe" (likewise on the right);
  //   * every other triangle of DT(all) has its corners among the corners of
  //     the unsafe triangles (ghosts count as unsafe): the seam set S;
  //   * so DT(all) = safe left ∪ safe right ∪ the triangles of DT(S) in the
  //     hole the safe ones leave. DT(S) is built with the hole's border edges
  //     as constraints (they are Delaunay edges of all the points), which
  //     keeps the two sides consistent on cocircular input.
  // The same holds for constrained triangulations when each half carries only
  // constraints with both ends on its side (they stay there, so they cannot
  // cross the other side's safe triangles) and DT(S) also keeps the
  // constrained edges inside the hole; constraints across the split go in
  // afterwards.
  // The split depends on the points only, never on the thread count, so
  // neither does the mesh.

  /// x-extent [lo, hi] of the circumcircle of (a, b, c), CCW, widened by a
  /// bound on its rounding error; false when the triangle is too flat for the
  /// bound to hold (callers then treat it as unsafe).
  static bool circleXRange(const Point2& a, const Point2& b, const Point2& c, double& lo,
                           double& hi) {
    constexpr double eps = 0x1p-52;
    const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
    const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
    const double d = 2 * (bx * cy - by * cx);
    const double dErr = 16 * eps * (std::abs(bx * cy) + std::abs(by * cx));
    if (!(d > 4 * dErr)) return false;
    const double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
    // |error| of each centre coordinate: numerator rounding plus the relative
    // error of d (at most a third here), with a factor 2 to spare.
    const double uxErr = 2 * (16 * eps * (std::abs(cy) * b2 + std::abs(by) * c2) / d +
                              std::abs(ux) * dErr / (d - dErr));
    const double uyErr = 2 * (16 * eps * (std::abs(bx) * c2 + std::abs(cx) * b2) / d +
                              std::abs(uy) * dErr / (d - dErr));
    const double r = std::sqrt(ux * ux + uy * uy);
    const double slack = uxErr + uxErr + uyErr + 8 * eps * (std::abs(a.x) + std::abs(ux) + r);
    lo = a.x + ux - r - slack;
    hi = a.x + ux + r + slack;
    return std::isfinite(lo) && std::isfinite(hi);
  }

  /// Per triangle: 1 unless it is certainly Delaunay in the union of the two
  /// halves, the left one's points having x <= leftMax and the right one's
  /// x >= rightMin; `leftHalf` says which half this is. Ghosts are unsafe.
  /// Only triangles connected to a ghost through unsafe ones are tested: the
  /// triangles in conflict with any one point of the other half (outside this
  /// half's hull) form a connected set holding a ghost, so the unsafe set is
  /// connected too, and a triangle never reached is safe.
  [[nodiscard]] std::vector<std::uint8_t> unsafeTriangles(bool leftHalf, double leftMax,
                                                          double rightMin) const {
    std::vector<std::uint8_t> unsafe(triCount(), 0);
    std::vector<std::uint8_t> tested(triCount(), 0);
    std::vector<std::uint32_t> todo;
    for (std::uint32_t t = 0; t < triCount(); ++t) {
      if (isGhost(t)) {
        unsafe[t] = tested[t] = 1;
        todo.push_back(t);
      }
    }
    while (!todo.empty()) {
      const std::uint32_t t = todo.back();
      todo.pop_back();
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t n = opp[3 * t + i] / 3;
        if (tested[n]) continue;
        tested[n] = 1;
        double lo = 0, hi = 0;
        const bool known = circleXRange(xy[tv[3 * n]], xy[tv[3 * n + 1]], xy[tv[3 * n + 2]], lo, hi);
        if (!known || (leftHalf ? !(hi < rightMin) : !(lo > leftMax))) {
          unsafe[n] = 1;
          todo.push_back(n);
        }
      }
    }
    return unsafe;
  }

  /// The x value that splits the pending points `order` into a left part
  /// (x < split) and a right part (x >= split) of comparable size, with every
  /// left–right pair farther apart than the snap tolerance (so no merge can
  /// span the seam). NaN when there is none.
  [[nodiscard]] double splitValue(const std::vector<std::uint32_t>& order) const {
    std::vector<double> xs(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) xs[i] = xy[order[i]].x;
    const std::size_t mid = xs.size() / 2;
    std::nth_element(xs.begin(), xs.begin() + static_cast<std::ptrdiff_t>(mid), xs.end());
    const double median = xs[mid];
    const double tol = options.snapTolerance;
    if (!(tol > 0)) return median;
    // The gap wider than tol in x nearest to the median, from the sorted
    // values around it.
    for (double window = 64 * tol; window <= 1e6 * tol; window *= 64) {
      std::vector<double> near;
      for (double x : xs) {
        if (std::abs(x - median) <= window) near.push_back(x);
      }
      if (near.size() > xs.size() / 4) break;  // too dense around the median
      std::sort(near.begin(), near.end());
      double best = std::numeric_limits<double>::quiet_NaN();
      for (std::size_t i = 0; i + 1 < near.size(); ++i) {
        if (near[i + 1] - near[i] > tol &&
            !(std::abs(near[i + 1] - median) >= std::abs(best - median))) {
          best = near[i + 1];
        }
      }
      if (!std::isnan(best)) return best;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  /// Triangulates the pending points `order` (first bulk, nothing triangulated
  /// yet) as two halves and merges them, emptying `order`; false, with
  /// nothing changed, when the points do not split well (then the caller
  /// inserts them in one go).
  bool insertAsTwoHalves(std::vector<std::uint32_t>& order) {
    const double split = splitValue(order);
    if (std::isnan(split)) return false;
    std::vector<std::uint32_t> leftOrder, rightOrder;
    leftOrder.reserve(order.size() / 2 + 1);
    rightOrder.reserve(order.size() / 2 + 1);
    double leftMax = -INFINITY, rightMin = INFINITY;
    for (std::uint32_t v : order) {
      const double x = xy[v].x;
      if (x < split) {
        leftOrder.push_back(v);
        leftMax = std::max(leftMax, x);
      } else {
        rightOrder.push_back(v);
        rightMin = std::min(rightMin, x);
      }
    }
    std::size_t ib = 0, ic = 0;
    if (leftOrder.size() < order.size() / 8 || rightOrder.size() < order.size() / 8 ||
        !findFirstTriangle(leftOrder, ib, ic) || !findFirstTriangle(rightOrder, ib, ic)) {
      return false;
    }
    std::vector<std::uint32_t>().swap(order);

    // The right half in an Impl of its own, its vertices numbered in input
    // order (so that merge ties still go to the earlier input).
    std::vector<std::uint32_t> localOf(xy.size(), kNone);
    for (std::uint32_t v : rightOrder) localOf[v] = 0;
    std::vector<std::uint32_t> rightGlobal;
    rightGlobal.reserve(rightOrder.size());
    for (std::uint32_t g = 0; g < localOf.size(); ++g) {
      if (localOf[g] == kNone) continue;
      localOf[g] = static_cast<std::uint32_t>(rightGlobal.size());
      rightGlobal.push_back(g);
    }
    for (std::uint32_t& v : rightOrder) v = localOf[v];
    // Segments with both ends on one side go in with that half (a segment
    // lies on the side of its ends); the rest after the merge.
    std::vector<std::uint32_t> leftSegments, rightSegments, seamSegments;
    for (auto k = static_cast<std::uint32_t>(segmentsDone); k < segments.size(); ++k) {
      const bool leftA = xy[segments[k].a].x < split, leftB = xy[segments[k].b].x < split;
      (leftA && leftB ? leftSegments : !leftA && !leftB ? rightSegments : seamSegments).push_back(k);
    }
    Impl right;
    for (std::uint32_t k : rightSegments) {
      Segment sg = segments[k];
      sg.a = localOf[sg.a];
      sg.b = localOf[sg.b];
      right.segments.push_back(sg);
    }
    std::vector<std::uint32_t>().swap(localOf);
    right.options.snapTolerance = options.snapTolerance;
    right.options.splitMinPoints = 0;
    right.rerouteDepthLimit = rerouteDepthLimit;
    right.features = features;
    right.xy.resize(rightGlobal.size());
    right.z.resize(rightGlobal.size());
    right.vfeat.resize(rightGlobal.size());
    for (std::uint32_t j = 0; j < rightGlobal.size(); ++j) {
      right.xy[j] = xy[rightGlobal[j]];
      right.z[j] = z[rightGlobal[j]];
      right.vfeat[j] = vfeat[rightGlobal[j]];
    }
    right.rep.assign(rightGlobal.size(), kNone);
    right.insertedUpTo = rightGlobal.size();
    right.reserveTriangles(trianglesFor(rightOrder.size(), rightSegments.size()));
    right.edgeFeatures.reserve(rightSegments.size());

    // Each half is triangulated and classified on its own thread.
    std::vector<std::uint8_t> unsafeLeft, unsafeRight;
    std::exception_ptr rightError;
    auto buildRight = [&] {
      try {
        right.insertInOrder(rightOrder);
        right.insertPendingSegments();
        unsafeRight = right.unsafeTriangles(false, leftMax, rightMin);
      } catch (...) {
        rightError = std::current_exception();
      }
    };
    auto buildLeft = [&] {
      insertInOrder(leftOrder);
      insertSegments(leftSegments);
      unsafeLeft = unsafeTriangles(true, leftMax, rightMin);
    };
    if (threadCount() >= 2) {
      std::thread worker(buildRight);
      try {
        buildLeft();
      } catch (...) {
        worker.join();
        throw;
      }
      worker.join();
    } else {
      buildLeft();
      buildRight();
    }
    if (rightError) std::rethrow_exception(rightError);
    std::vector<std::uint32_t>().swap(leftOrder);
    std::vector<std::uint32_t>().swap(rightOrder);

    // The right half's vertices (its crossings get new global ids), merges,
    // crossings and constrained edges, in global ids.
    for (std::size_t j = rightGlobal.size(); j < right.xy.size(); ++j) {
      rightGlobal.push_back(static_cast<std::uint32_t>(xy.size()));
      xy.push_back(right.xy[j]);
      z.push_back(0);
      vfeat.push_back(kNoFeature);
      rep.push_back(kNone);
    }
    insertedUpTo = xy.size();
    for (std::uint32_t j = 0; j < rightGlobal.size(); ++j) {
      const std::uint32_t g = rightGlobal[j];
      rep[g] = rightGlobal[right.rep[j]];
      z[g] = right.z[j];
      vfeat[g] = right.vfeat[j];
    }
    for (const auto& [keep, from] : right.zSource) zSource[rightGlobal[keep]] = rightGlobal[from];
    for (CdtReport::Merge mg : right.report.merges) {
      mg.kept = VertexId(rightGlobal[mg.kept.value]);
      mg.merged = VertexId(rightGlobal[mg.merged.value]);
      report.merges.push_back(mg);
    }
    for (CdtReport::Intersection ev : right.report.intersections) {
      ev.vertex = VertexId(rightGlobal[ev.vertex.value]);
      report.intersections.push_back(ev);
    }
    deepestReroute = std::max(deepestReroute, right.deepestReroute);
    if (bend.size() < right.bend.size()) bend.resize(right.bend.size(), 0.0);
    for (std::size_t g = 0; g < right.bend.size(); ++g) bend[g] += right.bend[g];
    report.dropped.insert(report.dropped.end(), right.report.dropped.begin(),
                          right.report.dropped.end());
    right.edgeFeatures.forEach([&](std::uint64_t key, EdgeFeatureMap::View fs) {
      const std::uint64_t global = edgeKey(rightGlobal[key >> 32], rightGlobal[key & 0xffffffffu]);
      for (FeatureId f : fs) edgeFeatures.add(global, f);
    });
    // Only the right half's triangles are needed from here on.
    std::vector<Point2>().swap(right.xy);
    std::vector<double>().swap(right.z);
    std::vector<FeatureId>().swap(right.vfeat);
    std::vector<std::uint32_t>().swap(right.rep);
    std::vector<std::uint32_t>().swap(right.vhe);
    right.edgeFeatures = EdgeFeatureMap();
    right.report = CdtReport();

    mergeHalves(right, rightGlobal, unsafeLeft, unsafeRight);
    // Vertex half-edges are recomputed when next needed.
    trackVhe = false;
    insertSegments(seamSegments);
    segmentsDone = segments.size();
    return true;
  }

  /// A border edge between a safe triangle and the hole: u→v (global ids) has
  /// the hole on its left; `safe` is the twin half-edge in the safe triangle
  /// (in this Impl for the left half, in `right` for the right half).
  struct SeamBorder {
    std::uint32_t u, v, safe;
    bool rightHalf;
  };

  /// Replaces this Impl's triangles (the left half, global ids) by the union
  /// of the safe triangles of both halves and the triangles of DT(S) that
  /// fill the hole between them. `right` has the right half in local ids
  /// (rightGlobal maps them); unsafeLeft/unsafeRight flag each half's
  /// triangles (unsafeTriangles()). Frees right's triangle arrays as it
  /// copies them.
  void mergeHalves(Impl& right, const std::vector<std::uint32_t>& rightGlobal,
                   const std::vector<std::uint8_t>& unsafeLeft,
                   const std::vector<std::uint8_t>& unsafeRight) {
    // The seam set S (corners of unsafe triangles), numbered in input order,
    // and the border edges of the hole.
    std::unordered_map<std::uint32_t, std::uint32_t> seamOf;
    std::vector<std::uint32_t> seamGlobal;
    std::vector<SeamBorder> borders;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> inner;  // constrained edges in the hole
    auto collect = [&](const std::vector<std::uint32_t>& corners,
                       const std::vector<std::uint32_t>& twins,
                       const std::vector<std::uint8_t>& constrained,
                       const std::vector<std::uint8_t>& unsafe, bool rightHalf) {
      for (std::uint32_t t = 0; t < unsafe.size(); ++t) {
        if (!unsafe[t]) continue;
        for (std::uint32_t i = 0; i < 3; ++i) {
          std::uint32_t v = corners[3 * t + i];
          if (v == kInf) continue;
          if (rightHalf) v = rightGlobal[v];
          if (seamOf.try_emplace(v, 0).second) seamGlobal.push_back(v);
          const std::uint32_t h = 3 * t + i, g = twins[h];
          std::uint32_t w = corners[nxt(h)];
          if (rightHalf && w != kInf) w = rightGlobal[w];
          if (!unsafe[g / 3]) {
            borders.push_back({v, w, g, rightHalf});
          } else if (constrained[h] && h < g) {
            inner.emplace_back(v, w);
          }
        }
      }
    };
    collect(tv, opp, cons, unsafeLeft, false);
    collect(right.tv, right.opp, right.cons, unsafeRight, true);
    std::sort(seamGlobal.begin(), seamGlobal.end());
    for (std::uint32_t j = 0; j < seamGlobal.size(); ++j) seamOf[seamGlobal[j]] = j;

    // DT(S) with the border edges (feature 0) and the constrained edges in the
    // hole (feature 1) as constraints.
    Impl seam;
    seam.options.splitMinPoints = 0;
    seam.features = {{FeatureKind::Other, "seam border"}, {FeatureKind::Other, "constraint"}};
    seam.xy.reserve(seamGlobal.size());
    for (std::uint32_t g : seamGlobal) seam.xy.push_back(xy[g]);
    seam.z.assign(seamGlobal.size(), 0.0);
    seam.vfeat.assign(seamGlobal.size(), kNoFeature);
    seam.rep.assign(seamGlobal.size(), kNone);
    for (const SeamBorder& b : borders) {
      seam.segments.push_back({seamOf[b.u], seamOf[b.v], 0});
    }
    for (const auto& [u, w] : inner) seam.segments.push_back({seamOf[u], seamOf[w], 1});
    seam.insertPendingPoints();
    seam.insertPendingSegments();
    if (!seam.report.merges.empty() || !seam.report.intersections.empty() ||
        !seam.report.dropped.empty() || !seam.bend.empty()) {
      throw internalError("the seam between the two halves changed its input");
    }

    // The hole: DT(S) triangles reachable from the border without crossing it.
    // (With no safe triangle at all, DT(S) is the whole triangulation.)
    std::vector<std::uint8_t> inHole(seam.triCount(), borders.empty() ? 1 : 0);
    std::vector<std::uint32_t> seamHalfedge(borders.size());
    std::vector<std::uint32_t> todo;
    for (std::size_t k = 0; k < borders.size(); ++k) {
      const std::uint32_t h = seam.findHalfedge(seamOf[borders[k].u], seamOf[borders[k].v]);
      if (h == kNone) throw internalError("a seam border edge is missing");
      seamHalfedge[k] = h;
      if (!inHole[h / 3]) {
        inHole[h / 3] = 1;
        todo.push_back(h / 3);
      }
    }
    while (!todo.empty()) {
      const std::uint32_t t = todo.back();
      todo.pop_back();
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t h = 3 * t + i;
        if (seam.cons[h]) {
          const auto fs = seam.edgeFeatures.find(edgeKey(seam.tv[h], seam.tv[nxt(h)]));
          if (std::find(fs.begin(), fs.end(), FeatureId{0}) != fs.end()) continue;  // border
        }
        const std::uint32_t n = seam.opp[h] / 3;
        if (!inHole[n]) {
          inHole[n] = 1;
          todo.push_back(n);
        }
      }
    }
    for (std::uint32_t h : seamHalfedge) {
      if (inHole[seam.opp[h] / 3]) throw internalError("the seam hole is not closed");
    }

    // New slots: freed left slots first, then appended.
    std::vector<std::uint32_t> freeSlots;
    for (std::uint32_t t = 0; t < unsafeLeft.size(); ++t) {
      if (unsafeLeft[t]) {
        freeSlots.push_back(t);
        tv[3 * t] = kNone;
      }
    }
    std::size_t used = 0;
    std::uint32_t appended = triCount();
    auto takeSlot = [&] { return used < freeSlots.size() ? freeSlots[used++] : appended++; };
    std::vector<std::uint32_t> rightSlot(right.triCount(), kNone);
    for (std::uint32_t t = 0; t < right.triCount(); ++t) {
      if (!unsafeRight[t]) rightSlot[t] = takeSlot();
    }
    std::vector<std::uint32_t> seamSlot(seam.triCount(), kNone);
    for (std::uint32_t t = 0; t < seam.triCount(); ++t) {
      if (inHole[t]) seamSlot[t] = takeSlot();
    }
    // Copies the kept triangles of another Impl array by array, freeing each
    // source array once copied (two full copies of the right half's arrays
    // never coexist); twins outside the kept set are linked through the
    // borders below.
    const std::size_t size = 3 * static_cast<std::size_t>(appended);
    auto copyKept = [&](Impl& from, const std::vector<std::uint32_t>& slot,
                        const std::vector<std::uint32_t>& global) {
      auto each = [&](const auto& f) {
        parallelChunks(threadCount(), slot.size(), [&](unsigned, std::size_t b, std::size_t e) {
          for (std::size_t t = b; t < e; ++t) {
            if (slot[t] == kNone) continue;
            for (std::uint32_t i = 0; i < 3; ++i) f(3 * t + i, 3 * std::size_t{slot[t]} + i);
          }
        });
      };
      tv.resize(size);
      each([&](std::size_t h, std::size_t out) {
        const std::uint32_t v = from.tv[h];
        tv[out] = v == kInf ? kInf : global[v];
      });
      std::vector<std::uint32_t>().swap(from.tv);
      opp.resize(size);
      each([&](std::size_t h, std::size_t out) {
        const std::uint32_t g = from.opp[h];
        opp[out] = slot[g / 3] == kNone ? kNone : 3 * slot[g / 3] + g % 3;
      });
      std::vector<std::uint32_t>().swap(from.opp);
      cons.resize(size);
      each([&](std::size_t h, std::size_t out) { cons[out] = from.cons[h]; });
      std::vector<std::uint8_t>().swap(from.cons);
    };
    copyKept(right, rightSlot, rightGlobal);
    copyKept(seam, seamSlot, seamGlobal);
    // The seam's constraints include the hole's border: take the flags from
    // the real constrained edges instead.
    for (const std::uint32_t t : seamSlot) {
      if (t == kNone) continue;
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t u = tv[3 * t + i], w = tv[3 * t + (i + 1) % 3];
        cons[3 * t + i] = u != kInf && w != kInf && !edgeFeatures.find(edgeKey(u, w)).empty();
      }
    }
    for (std::size_t k = 0; k < borders.size(); ++k) {
      const SeamBorder& b = borders[k];
      const std::uint32_t h = seamHalfedge[k];
      const std::uint32_t safe = b.rightHalf ? 3 * rightSlot[b.safe / 3] + b.safe % 3 : b.safe;
      link(safe, 3 * seamSlot[h / 3] + h % 3);
    }
    for (const std::uint32_t t : seamSlot) {
      if (t == kNone) continue;
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t h = 3 * t + i;
        if (opp[h] >= opp.size() || opp[opp[h]] != h) {
          throw internalError("merging the two halves left a broken triangle");
        }
      }
    }

    // Close the gaps the unused freed slots left: the last triangles move in.
    std::uint32_t end = triCount();
    for (std::size_t k = used; k < freeSlots.size(); ++k) {
      const std::uint32_t f = freeSlots[k];
      while (end > 0 && tv[3 * (end - 1)] == kNone) --end;
      if (f >= end) break;
      const std::uint32_t t = --end;
      for (std::uint32_t i = 0; i < 3; ++i) {
        tv[3 * f + i] = tv[3 * t + i];
        cons[3 * f + i] = cons[3 * t + i];
        link(3 * f + i, opp[3 * t + i]);
      }
      tv[3 * t] = kNone;
    }
    while (end > 0 && tv[3 * (end - 1)] == kNone) --end;
    tv.resize(3 * static_cast<std::size_t>(end));
    opp.resize(3 * static_cast<std::size_t>(end));
    cons.resize(3 * static_cast<std::size_t>(end));
    lastTriangle = 0;
  }

  // --------------------------------------------------------- constraints
  /// Half-edge p→q, or kNone if p and q are not adjacent.
  std::uint32_t findHalfedge(std::uint32_t p, std::uint32_t q) const {
    const std::uint32_t start = vhe[p];
    std::uint32_t h = start;
    do {
      if (tv[nxt(h)] == q) return h;
      h = opp[prv(h)];
    } while (h != start);
    return kNone;
  }

  void addEdgeFeature(std::uint32_t p, std::uint32_t q, FeatureId f) {
    const std::uint32_t h = findHalfedge(p, q);
    if (h == kNone) throw internalError("constraint edge missing after insertion");
    cons[h] = cons[opp[h]] = 1;
    edgeFeatures.add(edgeKey(p, q), f);
  }

  /// Is c on the ray from a through b (c collinear with a, b assumed)?
  bool onRay(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    const Point2 &pa = xy[a], &pb = xy[b], &pc = xy[c];
    if (pb.x > pa.x) return pc.x > pa.x;
    if (pb.x < pa.x) return pc.x < pa.x;
    return pb.y > pa.y ? pc.y > pa.y : pc.y < pa.y;
  }

  double zAlong(std::uint32_t u, std::uint32_t w, const Point2& p) const {
    const double dx = xy[w].x - xy[u].x, dy = xy[w].y - xy[u].y;
    const double l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p.x - xy[u].x) * dx + (p.y - xy[u].y) * dy) / l2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return z[u] + t * (z[w] - z[u]);
  }

  /// Does feature f win a crossing or an edge against g? Higher
  /// constraintPriority() first, then the earlier registered feature.
  bool outranks(FeatureId f, FeatureId g) const {
    const int pf = priorityOf(features, f), pg = priorityOf(features, g);
    return pf > pg || (pf == pg && f < g);
  }

  /// The highest-ranking (outranks()) feature of the constrained edge u–w.
  FeatureId edgeWinner(std::uint32_t u, std::uint32_t w) const {
    FeatureId best = kNoFeature;
    for (FeatureId f : edgeFeatures.find(edgeKey(u, w))) {
      if (best == kNoFeature || outranks(f, best)) best = f;
    }
    return best;
  }

  /// Radius within which a constructed (rounded) point is taken to be an
  /// existing vertex: 2^-40 of its coordinate magnitude (about 6e-6 m at UTM
  /// northings), far above the rounding error of a crossing yet far below
  /// survey precision.
  static double constructionTolerance(const Point2& p) {
    return std::ldexp(std::max(std::fabs(p.x), std::fabs(p.y)), -40);
  }

  /// The triangle that holds point p strictly inside (or, with a target
  /// vertex at p, a triangle at the target), if the open segment from vertex a
  /// to p crosses no constrained edge and passes through no vertex; else kNone.
  [[gnu::noinline]] std::uint32_t clearPathEnd(std::uint32_t a, const Point2& p,
                                               std::uint32_t target = kNone) const {
    // The wedge at a that the segment leaves through: a→u→w, u right, w left.
    std::uint32_t e = kNone;
    const std::uint32_t start = vhe[a];
    std::uint32_t h = start;
    do {
      const std::uint32_t u = tv[nxt(h)], w = tv[prv(h)];
      if (target != kNone && (u == target || w == target)) return h / 3;
      if (u != kInf && w != kInf) {
        const int ou = orient2d(xy[a], p, xy[u]), ow = orient2d(xy[a], p, xy[w]);
        if (ou == 0 || ow == 0) return kNone;
        if (ou < 0 && ow > 0) {
          e = nxt(h);
          break;
        }
      }
      h = opp[prv(h)];
    } while (h != start);
    if (e == kNone) return kNone;
    for (std::size_t steps = 0; steps < tv.size(); ++steps) {
      const int o = orient2d(xy[tv[e]], xy[tv[nxt(e)]], p);
      if (o > 0) return e / 3;  // p is on this side of e: inside e's triangle
      if (o == 0 || cons[e]) return kNone;
      const std::uint32_t g = opp[e];
      const std::uint32_t x = tv[prv(g)];
      if (x == kInf) return kNone;
      if (x == target) return g / 3;
      const int ox = orient2d(xy[a], p, xy[x]);
      if (ox == 0) return kNone;
      e = ox > 0 ? nxt(g) : prv(g);
    }
    return kNone;
  }

  /// The constrained edge R–L is replaced by R→w→L, w a vertex the segments
  /// from R and L to which cross no constrained edge and pass through no
  /// vertex (an apex beside R–L, or see clearPathEnd): they are edges already
  /// or are recovered by flips alone. Throws internalError when R–L is no
  /// edge, or when reroutes nest deeper than rerouteDepthLimit (each reroute
  /// inserts segments that may cross constraints and reroute again; the
  /// guards of insertSegment are per call).
  [[gnu::noinline]] void rerouteThrough(std::uint32_t R, std::uint32_t L, std::uint32_t w) {
    const std::uint32_t h = findHalfedge(R, L);
    if (h == kNone) throw internalError("the constrained edge to reroute is missing");
    if (rerouteDepth >= rerouteDepthLimit) {
      throw internalError("constraint reroutes nested more than " +
                          std::to_string(rerouteDepthLimit) + " deep (at " +
                          std::to_string(xy[R].x) + ", " + std::to_string(xy[R].y) + ")");
    }
    struct Nesting {
      std::size_t& depth;
      explicit Nesting(std::size_t& d) : depth(d) { ++depth; }
      ~Nesting() { --depth; }
      Nesting(const Nesting&) = delete;
      Nesting& operator=(const Nesting&) = delete;
    } nesting(rerouteDepth);
    deepestReroute = std::max(deepestReroute, rerouteDepth);
    const auto view = edgeFeatures.find(edgeKey(R, L));
    const std::vector<FeatureId> fs(view.begin(), view.end());
    cons[h] = cons[opp[h]] = 0;
    edgeFeatures.erase(edgeKey(R, L));
    for (const FeatureId g : fs) {
      insertSegment(R, w, g);
      insertSegment(w, L, g);
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{R, L}};
    lop(todo);
  }

  /// Is each feature of the edge R–L on both or on neither of the edges R–u
  /// and u–L?
  bool chainsStayOpen(std::uint32_t R, std::uint32_t L, std::uint32_t u) const {
    const auto ru = edgeFeatures.find(edgeKey(R, u)), ul = edgeFeatures.find(edgeKey(u, L));
    for (const FeatureId g : edgeFeatures.find(edgeKey(R, L))) {
      const bool onRu = std::find(ru.begin(), ru.end(), g) != ru.end();
      const bool onUl = std::find(ul.begin(), ul.end(), g) != ul.end();
      if (onRu != onUl) return false;
    }
    return true;
  }

  /// Distance from vertex v to the segment between vertices a and b.
  double distanceToSegment(std::uint32_t v, std::uint32_t a, std::uint32_t b) const {
    const Point2 &p = xy[v], &pa = xy[a], &pb = xy[b];
    const double dx = pb.x - pa.x, dy = pb.y - pa.y, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p.x - pa.x) * dx + (p.y - pa.y) * dy) / l2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(p.x - (pa.x + t * dx), p.y - (pa.y + t * dy));
  }

  /// The constraint cur→tgt crosses constrained edge e (R→L, in the
  /// triangle on cur's side). Makes a vertex at the crossing and returns it:
  /// R, L or an apex beside e when the crossing is within the tolerance of
  /// one, else a new vertex at the rounded crossing X. Returns kNone when it
  /// rerouted e's constraint instead: the caller walks cur→tgt again.
  ///
  /// When X is within the tolerance of an end of cur→tgt that is not beside e
  /// (slivers between), e's constraint is rerouted through that end if the
  /// segments to it cross nothing (rerouteThrough).
  ///
  /// X splits e into four strictly counter-clockwise triangles unless a
  /// triangle beside e is a sliver and X, rounded, falls outside it. Then, in
  /// order of preference:
  /// - X lies strictly inside the other triangle beside e, or does so when
  ///   moved a few ulps across e (it fell on e or beyond by rounding): X goes
  ///   in there and e's constraint runs R→X→L, bent by rounding only. Both new
  ///   edges lie inside that triangle, so the reroute crosses nothing.
  /// - X lies in a triangle farther off (beyond a sliver) and the segments from
  ///   R and L to X cross no constrained edge and pass through no vertex: X
  ///   goes in there and e's constraint is recovered as R→X→L by flips alone.
  /// - An apex of a sliver lies on e within the tolerance, or nearer to e than
  ///   X to any vertex: it is taken into e's constraint (R→apex→L). That adds
  ///   no vertex and no crossing (its edges to R and L exist). Each feature's
  ///   chain gains the apex or drops e where it already runs through the apex
  ///   (sliverApexOnEdge); the walk's guard would stop a cycle of such steps.
  /// - Otherwise the crossing is moved to the nearest of R, L and the apexes,
  ///   reported as `forced` when that bends a constraint beyond the tolerance.
  std::uint32_t crossingVertex(std::uint32_t cur, std::uint32_t tgt, std::uint32_t e,
                               FeatureId f) {
    const std::uint32_t R = tv[e], L = tv[nxt(e)];
    const Point2 X = geometry::intersectionPoint(xy[cur], xy[tgt], xy[R], xy[L]);
    const FeatureId existing = edgeWinner(R, L);
    const bool insertedWins = outranks(f, existing);
    const double zE = zAlong(R, L, X), zI = zAlong(cur, tgt, X);

    auto dist2 = [&](std::uint32_t v) {
      const double dx = xy[v].x - X.x, dy = xy[v].y - X.y;
      return dx * dx + dy * dy;
    };
    const std::uint32_t c = tv[prv(e)], d = tv[prv(opp[e])];
    std::uint32_t nearest = dist2(R) <= dist2(L) ? R : L;
    // The apexes count too: with nearly collinear constraints the crossing
    // can be at cur itself (c) or at the vertex beyond (d).
    for (const std::uint32_t u : {c, d}) {
      if (u != kInf && dist2(u) < dist2(nearest)) nearest = u;
    }
    // X is rounded, and R or L may itself be a rounded crossing of the same
    // lines (three constraints through one point): a constructed point this
    // close to a vertex is that vertex, even with snapTolerance 0.
    // The rounding error of X scales with the coordinates it is computed
    // from, not with X (which may be near the origin).
    double magnitude = 0.0;
    for (const std::uint32_t u : {cur, tgt, R, L}) {
      magnitude = std::max({magnitude, std::fabs(xy[u].x), std::fabs(xy[u].y)});
    }
    const double tol =
        std::max(options.snapTolerance, constructionTolerance({magnitude, magnitude}));
    enum class Make { AtVertex, SplitEdge, InTriangle } make = Make::SplitEdge;
    Point2 at = X;  // where a new vertex goes
    std::uint32_t inTriangle = kNone;
    // The crossing at an end of cur→tgt that is no corner beside e (slivers
    // between them): e's constraint runs through that end if it can by flips.
    std::uint32_t end = kNone;
    for (const std::uint32_t u : {cur, tgt}) {
      if (u != R && u != L && u != c && u != d && dist2(u) <= tol * tol &&
          dist2(u) < dist2(nearest) && clearPathEnd(R, xy[u], u) != kNone &&
          clearPathEnd(L, xy[u], u) != kNone) {
        end = u;
      }
    }
    if (end != kNone) {
      rerouteThrough(R, L, end);
      nearest = end;
      make = Make::AtVertex;
    } else if (dist2(nearest) <= tol * tol) {
      make = Make::AtVertex;
    } else {
      // Is X strictly inside the triangle (a, b, u) beyond its edge a→b?
      auto inside = [&](std::uint32_t a, std::uint32_t b, std::uint32_t u) {
        return u != kInf && orient2d(xy[b], xy[u], X) > 0 && orient2d(xy[u], xy[a], X) > 0;
      };
      const bool cOk = inside(R, L, c), dOk = inside(L, R, d);
      if (!cOk || !dOk) {
        const int side = orient2d(xy[R], xy[L], X);  // > 0: c's side
        if (side > 0 && cOk) {
          make = Make::InTriangle;
          inTriangle = e / 3;
        } else if (side < 0 && dOk) {
          make = Make::InTriangle;
          inTriangle = opp[e] / 3;
        } else if (const auto P = nudgedInto(R, L, c, X); cOk && P) {
          make = Make::InTriangle;  // X was on e or just across it, by rounding
          inTriangle = e / 3;
          at = *P;
        } else if (const auto Q = nudgedInto(L, R, d, X); dOk && Q) {
          make = Make::InTriangle;
          inTriangle = opp[e] / 3;
          at = *Q;
        } else if (const std::uint32_t t = clearPathEnd(R, X);
                   t != kNone && clearPathEnd(L, X) == t) {
          make = Make::InTriangle;  // beyond a sliver, reachable by flips
          inTriangle = t;
        } else {
          const auto [apex, bendBy] = sliverApexOnEdge(e, !cOk ? c : kInf, !dOk ? d : kInf,
                                                       std::max(tol, std::sqrt(dist2(nearest))));
          if (apex != kNone && apex != cur && apex != tgt) {
            addBend(R, L, kNoFeature, bendBy);
            rerouteThrough(R, L, apex);
            return kNone;
          }
          // An apex at an end of cur→tgt: the crossing is there.
          if (apex != kNone) nearest = apex;
          make = Make::AtVertex;
        }
      }
    }
    CdtReport::Intersection ev;
    ev.existing = existing;
    ev.inserted = f;
    ev.zExisting = zE;
    ev.zInserted = zI;
    std::uint32_t v;
    if (make == Make::AtVertex) {
      // Both constraints now run through v: each bends by v's distance from
      // it (the distance from X is no measure where the lines nearly overlap).
      v = nearest;
      ev.moved = std::max(distanceToSegment(v, cur, tgt), distanceToSegment(v, R, L));
      ev.forced = ev.moved > tol;
      if (v == c || v == d) {
        // Every feature of e bends, not only the one the event names.
        addBend(R, L, existing, ev.moved);
        rerouteThrough(R, L, v);
      }
    } else {
      v = static_cast<std::uint32_t>(xy.size());
      xy.push_back(at);
      z.push_back(insertedWins ? zI : zE);
      vfeat.push_back(insertedWins ? f : existing);
      rep.push_back(v);
      vhe.push_back(kNone);
      insertedUpTo = xy.size();
      if (make == Make::SplitEdge) {
        splitEdge(e, v);
      } else {
        splitTriangle(inTriangle, v);  // e stays constrained, so it is not flipped
        rerouteThrough(R, L, v);
      }
      lopAround(v);
    }
    ev.vertex = VertexId(v);
    ev.at = {xy[v].x, xy[v].y, z[v]};
    report.intersections.push_back(ev);
    return v;
  }

  /// Records that the features of edge R–L (but `except`) bend by `by`.
  void addBend(std::uint32_t R, std::uint32_t L, FeatureId except, double by) {
    for (const FeatureId g : edgeFeatures.find(edgeKey(R, L))) {
      if (g == except) continue;
      if (g >= bend.size()) bend.resize(g + 1, 0.0);
      bend[g] += by;
    }
  }

  /// X moved by up to 8 ulps across the edge a→b towards u, to a point
  /// strictly inside the triangle (a, b, u); nullopt if none is found.
  [[gnu::noinline]] std::optional<Point2> nudgedInto(std::uint32_t a, std::uint32_t b,
                                                     std::uint32_t u, const Point2& X) const {
    if (u == kInf) return std::nullopt;
    const double dx = xy[b].x - xy[a].x, dy = xy[b].y - xy[a].y, len = std::hypot(dx, dy);
    if (!(len > 0)) return std::nullopt;
    double magnitude = std::max(std::fabs(X.x), std::fabs(X.y));
    for (const std::uint32_t w : {a, b}) {
      magnitude = std::max({magnitude, std::fabs(xy[w].x), std::fabs(xy[w].y)});
    }
    const double ulp = std::ldexp(magnitude, -52);
    for (int k = 1; k <= 8; ++k) {
      const double step = k * ulp / len;
      const Point2 P{X.x - dy * step, X.y + dx * step};  // left of a→b
      if (orient2d(xy[a], xy[b], P) > 0 && orient2d(xy[b], xy[u], P) > 0 &&
          orient2d(xy[u], xy[a], P) > 0) {
        return P;
      }
    }
    return std::nullopt;
  }

  /// Of the apexes c and d beside e (kInf to skip one), the one nearest to
  /// e's segment within maxDistance, and its distance; kNone if none. An apex
  /// qualifies if each of e's features is on both or on neither of its edges
  /// to e's ends: the feature's chain then grows by an edge, or loses e where
  /// it already runs through the apex. A feature on one of them only would
  /// make its chain run back on itself.
  [[gnu::noinline]] std::pair<std::uint32_t, double> sliverApexOnEdge(std::uint32_t e,
                                                                      std::uint32_t c,
                                                                      std::uint32_t d,
                                                                      double maxDistance) const {
    const std::uint32_t R = tv[e], L = tv[nxt(e)];
    std::pair<std::uint32_t, double> best{kNone, maxDistance};
    for (const std::uint32_t u : {c, d}) {
      if (u == kInf || !chainsStayOpen(R, L, u)) continue;
      const double du = distanceToSegment(u, R, L);
      if (du <= best.second) best = {u, du};
    }
    return best;
  }

  /// Is u a vertex exactly on the input segment a0→b0 (exact orient2d) and
  /// strictly between cur and tgt? After a split at a rounded crossing point,
  /// cur→tgt is no longer on the input line, so a vertex exactly on it must be
  /// found against a0→b0 or the constraint would bypass it by an ulp.
  bool onInputSegment(std::uint32_t a0, std::uint32_t b0, std::uint32_t cur, std::uint32_t tgt,
                      std::uint32_t u, const std::vector<std::uint32_t>& passed) const {
    if (u == kInf || u == cur || u == tgt || orient(a0, b0, u) != 0) return false;
    if (std::find(passed.begin(), passed.end(), u) != passed.end()) return false;
    const Point2 &pc = xy[cur], &pt = xy[tgt], &pu = xy[u];
    return (pu.x - pc.x) * (pt.x - pc.x) + (pu.y - pc.y) * (pt.y - pc.y) > 0 &&
           (pu.x - pt.x) * (pc.x - pt.x) + (pu.y - pt.y) * (pc.y - pt.y) > 0;
  }

  /// Inserts the constraint segment a→b (live vertices) for feature f.
  void insertSegment(std::uint32_t a, std::uint32_t b, FeatureId f) {
    const std::uint32_t a0 = a, b0 = b;
    std::vector<std::uint32_t> passed{a};  // vertices this segment already runs through
    std::vector<std::uint32_t> targets{b};
    std::uint32_t cur = a;
    const std::size_t guardLimit = 64 + 8 * xy.size();
    std::size_t guard = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> crossed;
    while (!targets.empty()) {
      if (++guard > guardLimit) {
        throw internalError("constraint insertion did not terminate");
      }
      const std::uint32_t tgt = targets.back();
      if (cur == tgt) {
        targets.pop_back();
        continue;
      }
      // Find the wedge at cur that holds the direction to tgt.
      std::uint32_t firstCross = kNone, onLine = kNone;
      {
        const std::uint32_t start = vhe[cur];
        std::uint32_t h = start;
        std::size_t turns = 0;
        do {
          const std::uint32_t u = tv[nxt(h)], w = tv[prv(h)];
          if (u != kInf) {
            if (u == tgt) {
              onLine = u;
              break;
            }
            const int ou = orient(cur, tgt, u);
            if ((ou == 0 && onRay(cur, tgt, u)) || onInputSegment(a0, b0, cur, tgt, u, passed)) {
              onLine = u;
              break;
            }
            if (w != kInf && ou < 0 && orient(cur, tgt, w) > 0) {
              if (onInputSegment(a0, b0, cur, tgt, w, passed)) {
                onLine = w;
              } else {
                firstCross = nxt(h);  // u→w, u right of cur→tgt, w left
              }
              break;
            }
          }
          h = opp[prv(h)];
        } while (h != start && ++turns < 1u << 30);
      }
      if (onLine != kNone) {
        addEdgeFeature(cur, onLine, f);
        cur = onLine;
        passed.push_back(cur);
        continue;
      }
      if (firstCross == kNone) throw internalError("constraint direction found in no triangle");

      // Walk the crossed edges.
      crossed.clear();
      std::uint32_t e = firstCross;
      std::uint32_t end = kNone, onInput = kNone;
      bool hitConstraint = false;
      for (;;) {
        if (cons[e]) {
          hitConstraint = true;
          break;
        }
        crossed.emplace_back(tv[e], tv[nxt(e)]);
        const std::uint32_t g = opp[e];
        const std::uint32_t x = tv[prv(g)];
        if (x == kInf) throw internalError("constraint leaves the convex hull");
        if (x == tgt) {
          end = tgt;
          break;
        }
        const int ox = orient(cur, tgt, x);
        if (ox == 0) {
          end = x;
          break;
        }
        if (onInputSegment(a0, b0, cur, tgt, x, passed)) {
          onInput = x;  // route through it: walk cur→x on its own line
          break;
        }
        e = ox > 0 ? nxt(g) : prv(g);
      }
      if (onInput != kNone) {
        targets.push_back(onInput);
        continue;
      }
      if (hitConstraint) {
        const std::uint32_t v = crossingVertex(cur, tgt, e, f);
        if (v != kNone) targets.push_back(v);
        continue;
      }
      removeCrossings(cur, end, crossed, f);
      cur = end;
      passed.push_back(cur);
    }
  }

  /// Swaps away every edge crossing a→b (Sloan; book 6.5), marks a–b
  /// constrained for f, then restores the Delaunay property from the new edges.
  void removeCrossings(std::uint32_t a, std::uint32_t b,
                       const std::vector<std::pair<std::uint32_t, std::uint32_t>>& crossed,
                       FeatureId f) {
    std::deque<std::pair<std::uint32_t, std::uint32_t>> queue(crossed.begin(), crossed.end());
    std::vector<std::pair<std::uint32_t, std::uint32_t>> fresh;
    std::size_t guard = 0;
    const std::size_t limit = 64 + 16 * crossed.size() * crossed.size();
    while (!queue.empty()) {
      if (++guard > limit) throw internalError("constraint edge recovery did not terminate");
      const auto [p, q] = queue.front();
      queue.pop_front();
      const std::uint32_t h = findHalfedge(p, q);
      if (h == kNone) throw internalError("crossing edge vanished");
      const std::uint32_t c = tv[prv(h)], d = tv[prv(opp[h])];
      if (orient(c, d, p) * orient(c, d, q) >= 0) {  // not strictly convex
        queue.emplace_back(p, q);
        continue;
      }
      flip(h);
      const bool endC = c == a || c == b, endD = d == a || d == b;
      if (!endC && !endD && orient(a, b, c) * orient(a, b, d) < 0) {
        queue.emplace_back(c, d);
      } else {
        fresh.emplace_back(c, d);
      }
    }
    addEdgeFeature(a, b, f);  // constrained before the LOP so it is never flipped
    lop(fresh);
  }

  /// Lawson's LOP (book 4.2) from the given edges (vertex pairs): flips every
  /// unconstrained edge that is not locally Delaunay, queueing the four edges
  /// around each flip. Consumes `todo`.
  void lop(std::vector<std::pair<std::uint32_t, std::uint32_t>>& todo) {
    std::size_t flips = 0;
    while (!todo.empty()) {
      const auto [p, q] = todo.back();
      todo.pop_back();
      if (p == kInf || q == kInf) continue;
      const std::uint32_t h = findHalfedge(p, q);
      if (h == kNone || cons[h]) continue;
      const std::uint32_t c = tv[prv(h)], d = tv[prv(opp[h])];
      if (c == kInf || d == kInf) continue;
      if (incircle(xy[p], xy[q], xy[c], xy[d]) > 0) {
        if (++flips > 64 + 64 * xy.size()) {
          throw internalError("edge legalization did not terminate");
        }
        flip(h);
        todo.emplace_back(p, c);
        todo.emplace_back(c, q);
        todo.emplace_back(q, d);
        todo.emplace_back(d, p);
      }
    }
  }

  /// Runs the LOP on every edge of the triangles around v — needed after a
  /// forced split at a rounded intersection point, where v may lie off the
  /// split edge and edges at v itself can be non-Delaunay.
  void lopAround(std::uint32_t v) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo;
    const std::uint32_t start = vhe[v];
    std::uint32_t h = start;
    do {
      todo.emplace_back(v, tv[nxt(h)]);
      todo.emplace_back(tv[nxt(h)], tv[prv(h)]);
      h = opp[prv(h)];
    } while (h != start);
    lop(todo);
  }

  void insertPendingSegments() {
    if (segmentsDone >= segments.size()) return;
    std::vector<std::uint32_t> pending(segments.size() - segmentsDone);
    for (std::size_t k = 0; k < pending.size(); ++k) {
      pending[k] = static_cast<std::uint32_t>(segmentsDone + k);
    }
    insertSegments(pending);
    segmentsDone = segments.size();
  }

  /// Inserts segments[k] for every k in `which` (ascending), in runs of up to
  /// 64 consecutive segments of one polyline (each starting where the last
  /// ended), the runs in the Hilbert order of their first midpoints: each
  /// segment starts next to the last one, and consecutive runs work on the
  /// same part of the mesh (and of memory). Nothing but rounding depends on
  /// this order: crossing ties are decided by feature (outranks()), not by
  /// which segment came first.
  void insertSegments(const std::vector<std::uint32_t>& which) {
    if (which.empty()) return;
    startTrackingVhe();
    std::vector<std::uint32_t> runStart;  // positions in `which`
    for (std::size_t k = 0; k < which.size(); ++k) {
      const bool continues = k > 0 && k - runStart.back() < 64 &&
                             segments[which[k]].a == segments[which[k - 1]].b;
      if (!continues) runStart.push_back(static_cast<std::uint32_t>(k));
    }
    auto midpoint = [&](std::uint32_t k) {
      const Point2 &p = xy[segments[which[k]].a], &q = xy[segments[which[k]].b];
      return Point2{0.5 * p.x + 0.5 * q.x, 0.5 * p.y + 0.5 * q.y};
    };
    Box box;
    for (const std::uint32_t k : runStart) box.add(midpoint(k));
    const HilbertGrid hilbert(box);
    std::vector<std::uint64_t> keys(runStart.size());
    for (std::size_t r = 0; r < runStart.size(); ++r) {
      keys[r] = (static_cast<std::uint64_t>(hilbert(midpoint(runStart[r]))) << 32) | r;
    }
    radixSortHigh32(keys, threadCount());
    for (const std::uint64_t key : keys) {
      const std::size_t r = key & 0xffffffffu;
      const std::size_t end = r + 1 < runStart.size() ? runStart[r + 1] : which.size();
      for (std::size_t k = runStart[r]; k < end; ++k) {
        const Segment sg = segments[which[k]];
        const std::uint32_t a = find(sg.a), b = find(sg.b);
        if (a == b) {
          report.dropped.push_back(
              {CdtReport::Dropped::What::ZeroLengthSegment, sg.feature, xy[a]});
          continue;
        }
        insertSegment(a, b, sg.feature);
      }
    }
  }

  /// Does half-edge h carry a domain ring: any boundary or hole (`boundary`
  /// false), or a boundary (`boundary` true)?
  bool isDomainEdge(std::uint32_t h, bool boundary = false) const {
    if (!cons[h]) return false;
    for (FeatureId f : edgeFeatures.find(edgeKey(tv[h], tv[nxt(h)]))) {
      if (f < featureRole.size() && featureRole[f] != Role::None) {
        if (!boundary || featureRole[f] == Role::Boundary) return true;
      }
      if (f == kDomainFeature) return true;  // domain edges of a loaded TIN bound it
    }
    return false;
  }

  /// Per triangle: the fewest half-edges with counts(h) crossed on a way in
  /// from outside the hull (0-1 breadth-first search over the triangles).
  template <class Counts>
  std::vector<std::uint32_t> crossingDepth(const Counts& counts) const {
    const std::uint32_t nt = triCount();
    std::vector<std::uint32_t> depth(nt, kNone);
    std::deque<std::uint32_t> dq;
    for (std::uint32_t t = 0; t < nt; ++t) {
      if (isGhost(t)) {
        depth[t] = 0;
        dq.push_back(t);
      }
    }
    while (!dq.empty()) {
      const std::uint32_t t = dq.front();
      dq.pop_front();
      for (std::uint32_t i = 0; i < 3; ++i) {
        const std::uint32_t h = 3 * t + i;
        const std::uint32_t n = opp[h] / 3;
        const std::uint32_t w = counts(h) ? 1 : 0;
        if (depth[t] + w < depth[n]) {
          depth[n] = depth[t] + w;
          if (w == 0) {
            dq.push_front(n);
          } else {
            dq.push_back(n);
          }
        }
      }
    }
    return depth;
  }

  /// Marks triangles inside the domain: crossing-count parity from the
  /// outside, rings nesting by parity. With a boundary, hole edges count only
  /// inside some boundary ring: a hole outside every boundary (or the part of
  /// one that is) bounds nothing. (Across a hole edge that is no boundary
  /// edge the boundary depth is the same on both sides.)
  std::vector<std::uint8_t> classifyDomain() const {
    const std::uint32_t nt = triCount();
    std::vector<std::uint8_t> inside(nt, 0);
    if (!hasBoundary && !hasHole) {
      for (std::uint32_t t = 0; t < nt; ++t) inside[t] = !isGhost(t);
      return inside;
    }
    std::vector<std::uint32_t> enclosing;  // boundary edges crossed
    if (hasBoundary && hasHole) {
      enclosing = crossingDepth([&](std::uint32_t h) { return isDomainEdge(h, true); });
    }
    const std::vector<std::uint32_t> depth = crossingDepth([&](std::uint32_t h) {
      if (!isDomainEdge(h)) return false;
      return enclosing.empty() || enclosing[h / 3] > 0 || isDomainEdge(h, true);
    });
    for (std::uint32_t t = 0; t < nt; ++t) {
      if (isGhost(t)) continue;
      inside[t] = hasBoundary ? (depth[t] % 2 == 1) : (depth[t] % 2 == 0);
    }
    return inside;
  }
};

Cdt::Cdt(CdtOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
}
Cdt::~Cdt() = default;
Cdt::Cdt(Cdt&&) noexcept = default;
Cdt& Cdt::operator=(Cdt&&) noexcept = default;

FeatureId Cdt::addFeature(FeatureKind kind, std::string source) {
  impl_->features.push_back({kind, std::move(source)});
  impl_->featureRole.push_back(Role::None);
  return static_cast<FeatureId>(impl_->features.size() - 1);
}

const std::vector<TinFeature>& Cdt::features() const { return impl_->features; }

void Cdt::Impl::checkPoint(const Point3& p, FeatureId feature, std::size_t id) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    SourceLocation where;
    if (feature != kNoFeature && feature < features.size()) {
      where.file = features[feature].source;
    }
    throw inputError("point " + std::to_string(id) + " has a non-finite coordinate (" +
                         std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                         std::to_string(p.z) + ")",
                     where, "remove NaN/infinite values from the input");
  }
  if (feature != kNoFeature && feature >= features.size()) {
    throw usageError("feature id " + std::to_string(feature) + " was not registered with addFeature");
  }
  // The predicates are exact while their products neither overflow nor
  // underflow (predicates.hpp); this range keeps every case inside that.
  auto outOfRange = [](double c) {
    const double a = std::fabs(c);
    return a > 1e60 || (a != 0.0 && a < 1e-50);
  };
  if (outOfRange(p.x) || outOfRange(p.y)) {
    SourceLocation where;
    if (feature != kNoFeature) where.file = features[feature].source;
    throw inputError("point " + std::to_string(id) +
                         " has a coordinate outside the "
                         "supported range (0 or 1e-50 to 1e60 in magnitude)",
                     where, "check the coordinate units and CRS");
  }
  if (id >= kInf - 1) throw inputError("too many points (at most 2^32 - 3)");
}

VertexId Cdt::Impl::appendPoints(std::span<const Point3> points, FeatureId feature) {
  const auto first = VertexId(static_cast<std::uint32_t>(xy.size()));
  for (std::size_t i = 0; i < points.size(); ++i) checkPoint(points[i], feature, xy.size() + i);
  // Grow geometrically: many small polylines must not reallocate each time.
  const std::size_t need = xy.size() + points.size();
  if (need > xy.capacity()) {
    const std::size_t cap = std::max(need, 2 * xy.capacity());
    xy.reserve(cap);
    z.reserve(cap);
    vfeat.reserve(cap);
    rep.reserve(cap);
  }
  for (const Point3& p : points) {
    xy.push_back(p.xy());
    z.push_back(p.z);
    vfeat.push_back(feature);
    rep.push_back(kNone);
  }
  if (!points.empty()) inputAdded();
  return first;
}

VertexId Cdt::insertPoint(const Point3& p, FeatureId feature) {
  return impl_->appendPoints(std::span<const Point3>(&p, 1), feature);
}

VertexId Cdt::insertPoints(std::span<const Point3> points, FeatureId feature) {
  return impl_->appendPoints(points, feature);
}

void Cdt::insertConstraint(std::span<const Point3> polyline, FeatureId feature, bool closed) {
  if (polyline.empty()) return;
  // Every vertex is checked before the first goes in: a bad one adds nothing.
  const VertexId first = insertPoints(polyline, feature);
  for (std::uint32_t i = 0; i + 1 < polyline.size(); ++i) {
    insertConstraintSegment(VertexId(first.value + i), VertexId(first.value + i + 1), feature);
  }
  if (closed && polyline.size() > 2) {
    insertConstraintSegment(VertexId(first.value + static_cast<std::uint32_t>(polyline.size()) - 1),
                            first, feature);
  }
}

void Cdt::insertConstraintSegment(VertexId a, VertexId b, FeatureId feature) {
  Impl& m = *impl_;
  if (a.value >= m.xy.size() || b.value >= m.xy.size()) {
    throw usageError("constraint segment names a vertex that was not inserted");
  }
  m.segments.push_back({a.value, b.value, feature});
  m.inputAdded();
}

void Cdt::addBoundary(std::span<const Point3> ring, FeatureId feature) {
  if (feature == kNoFeature || feature >= impl_->features.size()) {
    throw usageError("addBoundary needs a registered feature");
  }
  insertConstraint(ring, feature, true);  // all or nothing: may throw
  impl_->featureRole[feature] = Role::Boundary;
  impl_->hasBoundary = true;
  impl_->inputAdded();
}

void Cdt::addHole(std::span<const Point3> ring, FeatureId feature) {
  if (feature == kNoFeature || feature >= impl_->features.size()) {
    throw usageError("addHole needs a registered feature");
  }
  insertConstraint(ring, feature, true);  // all or nothing: may throw
  impl_->featureRole[feature] = Role::Hole;
  impl_->hasHole = true;
  impl_->inputAdded();
}

void Cdt::finalize() {
  Impl& m = *impl_;
  if (!m.triangulated() && m.xy.empty()) {
    throw geometryError("no points to triangulate", {}, "give at least three points");
  }
  if (m.packed) {
    if (!m.changed) {
      m.finalized = true;  // nothing new: the mesh stands
      return;
    }
    m.unpack();
  }
  m.insertPendingPoints();
  m.insertPendingSegments();
  // Vertex half-edges serve constraint insertion only: recomputed when more
  // constraints come.
  m.trackVhe = false;
  std::vector<std::uint32_t>().swap(m.vhe);
  m.finalized = true;
  m.changed = false;
  m.meshBuilt = false;
}

void Cdt::buildMesh() const {
  Impl& m = *impl_;
  if (m.meshBuilt.load(std::memory_order_acquire)) return;
  const std::lock_guard lock(m.meshMutex);
  if (m.meshBuilt.load(std::memory_order_relaxed)) return;
  // The output mesh takes over the working arrays: triangles inside the domain
  // are compacted in place (their order kept) and moved into the Mesh; ghosts
  // and triangles outside the domain are set aside so that unpack() can restore
  // the working triangulation exactly if more input comes.
  const std::uint32_t nt = m.triCount();
  // triMap: working triangle → output triangle (kNone outside); monotone, so
  // the compaction below can run in place. Transient: freed before the output
  // points are allocated.
  std::vector<std::uint32_t> triMap;
  {
    const std::vector<std::uint8_t> inside = m.classifyDomain();
    triMap.resize(nt);
    std::uint32_t k = 0;
    for (std::uint32_t t = 0; t < nt; ++t) triMap[t] = inside[t] ? k++ : kNone;
  }
  std::vector<std::uint32_t> used(m.xy.size(), kNone);
  std::uint32_t outT = 0;
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (triMap[t] == kNone) continue;
    ++outT;
    for (std::uint32_t i = 0; i < 3; ++i) used[m.tv[3 * t + i]] = 0;
  }
  std::uint32_t outV = 0;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (used[v] != kNone) used[v] = outV++;
  }
  Mesh& mesh = m.mesh;
  mesh = Mesh();
  mesh.crs_ = m.options.crs;
  mesh.features_ = m.features;
  mesh.outgoing_.assign(outV, HalfedgeId());
  m.removed.clear();
  m.removed.reserve(nt - outT);
  // Features of constrained half-edges go straight into the mesh's compact
  // form (Mesh::setEdgeFeatures): output half-edges come in ascending order.
  mesh.consBits_.assign(3 * static_cast<std::size_t>(outT) / 64 + 1, 0);
  mesh.featureBegin_.assign(1, 0);
  std::vector<FeatureId> fs;
  std::vector<std::uint32_t> boundary;  // output half-edges without twin, ascending
  for (std::uint32_t t = 0; t < nt; ++t) {
    const std::uint32_t b = 3 * t;
    if (triMap[t] == kNone) {
      m.removed.push_back({t,
                           {m.tv[b], m.tv[b + 1], m.tv[b + 2]},
                           {m.opp[b], m.opp[b + 1], m.opp[b + 2]},
                           {m.cons[b], m.cons[b + 1], m.cons[b + 2]}});
      continue;
    }
    // Read t completely before writing slot triMap[t] <= t.
    const std::uint32_t c[3] = {m.tv[b], m.tv[b + 1], m.tv[b + 2]};
    const std::uint32_t g[3] = {m.opp[b], m.opp[b + 1], m.opp[b + 2]};
    const std::uint8_t k[3] = {m.cons[b], m.cons[b + 1], m.cons[b + 2]};
    const std::uint32_t o = 3 * triMap[t];
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (!k[i]) continue;
      fs.clear();
      for (FeatureId f : m.edgeFeatures.find(edgeKey(c[i], c[(i + 1) % 3]))) {
        if (f < m.features.size()) fs.push_back(f);
      }
      if (fs.empty()) continue;
      std::sort(fs.begin(), fs.end());
      mesh.consBits_[(o + i) / 64] |= std::uint64_t{1} << ((o + i) % 64);
      mesh.featureIds_.insert(mesh.featureIds_.end(), fs.begin(), fs.end());
      mesh.featureBegin_.push_back(static_cast<std::uint32_t>(mesh.featureIds_.size()));
    }
    for (std::uint32_t i = 0; i < 3; ++i) {
      const std::uint32_t n = triMap[g[i] / 3];
      m.tv[o + i] = used[c[i]];
      m.opp[o + i] = n != kNone ? 3 * n + g[i] % 3 : kNone;
      m.cons[o + i] = k[i];
    }
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (m.opp[o + i] == kNone) boundary.push_back(o + i);
    }
  }
  // Outgoing half-edge per vertex, the rule of Mesh::build: the first boundary
  // half-edge leaving v if there is one, else the first. Written back to
  // front without reading (the vertex order is unrelated to the triangle
  // order, so these stores are scattered).
  for (std::uint32_t h = 3 * outT; h-- > 0;) mesh.outgoing_[m.tv[h]] = HalfedgeId(h);
  for (std::size_t i = boundary.size(); i-- > 0;) {
    mesh.outgoing_[m.tv[boundary[i]]] = HalfedgeId(boundary[i]);
  }
  std::vector<std::uint32_t>().swap(boundary);
  std::vector<std::uint32_t>().swap(triMap);
  m.tv.resize(3 * static_cast<std::size_t>(outT));
  m.opp.resize(3 * static_cast<std::size_t>(outT));
  m.cons.resize(3 * static_cast<std::size_t>(outT));
  m.packedTriangles = outT;
  m.packed = true;

  mesh.corners_ = std::move(m.tv);
  mesh.twins_ = std::move(m.opp);
  m.tv.clear();
  m.opp.clear();
  mesh.points_.resize(outV);
  parallelChunks(m.threadCount(), used.size(), [&](unsigned, std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (used[v] != kNone) mesh.points_[used[v]] = {m.xy[v].x, m.xy[v].y, m.z[v]};
    }
  });
  mesh.finishEdgeFeatures();

  // Input vertex → mesh vertex; live vertices outside the domain are dropped.
  m.report.dropped.erase(
      std::remove_if(m.report.dropped.begin(), m.report.dropped.end(),
                     [](const CdtReport::Dropped& d) {
                       return d.what == CdtReport::Dropped::What::PointOutsideDomain;
                     }),
      m.report.dropped.end());
  // used becomes meshOf: roots keep their entry, merged vertices take their root's.
  for (std::uint32_t v = 0; v < m.xy.size(); ++v) {
    const std::uint32_t r = m.find(v);
    if (r != v) used[v] = used[r];
    if (r == v && used[v] == kNone) {
      m.report.dropped.push_back(
          {CdtReport::Dropped::What::PointOutsideDomain, m.vfeat[v], m.xy[v]});
    }
  }
  m.meshOf = std::move(used);
  m.meshBuilt.store(true, std::memory_order_release);
}

const Mesh& Cdt::mesh() const {
  if (!impl_->finalized) {
    throw usageError("Cdt::mesh() called before finalize(), or with input added since the last one",
                     "call finalize() after the last insertion");
  }
  buildMesh();
  return impl_->mesh;
}

TinData Cdt::toTinData() const { return mesh().toTinData(); }

VertexId Cdt::meshVertex(VertexId input) const {
  if (!impl_->finalized) return {};
  buildMesh();
  if (input.value >= impl_->meshOf.size()) return {};
  const std::uint32_t v = impl_->meshOf[input.value];
  return v == kNone ? VertexId() : VertexId(v);
}

std::size_t Cdt::inputVertexCount() const { return impl_->xy.size(); }

const CdtReport& Cdt::report() const {
  if (impl_->finalized) buildMesh();  // completes the dropped-point list
  return impl_->report;
}

namespace {
std::string formatCoord(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
}  // namespace

ValidationReport Cdt::validate(const ValidationOptions& options) const {
  std::size_t chainSteps = 0;
  return validateCounting(options, chainSteps);
}

void CdtTestAccess::setRerouteDepthLimit(Cdt& cdt, std::size_t limit) {
  cdt.impl_->rerouteDepthLimit = limit;
}

std::size_t CdtTestAccess::deepestReroute(const Cdt& cdt) {
  return cdt.impl_->deepestReroute;
}

ValidationReport CdtTestAccess::validate(const Cdt& cdt, std::size_t& chainSteps,
                                         const ValidationOptions& options) {
  chainSteps = 0;
  return cdt.validateCounting(options, chainSteps);
}

ValidationReport Cdt::validateCounting(const ValidationOptions& options,
                                       std::size_t& chainSteps) const {
  ValidationReport r = tinsmith::validate(mesh(), options);
  const Impl& m = *impl_;
  if (m.meshOf.size() != m.xy.size()) throw internalError("the input vertex map is out of date");
  auto add = [&](const std::string& s) {
    r.ok = false;
    ++r.problemCount;
    if (r.problems.size() < options.maxProblems) r.problems.push_back(s);
  };
  // Every input vertex is a mesh vertex, or merged/dropped and reported.
  std::vector<std::uint8_t> merged(m.xy.size(), 0), dropped(m.xy.size(), 0);
  for (const auto& mg : m.report.merges) merged[mg.merged.value] = 1;
  for (std::uint32_t v = 0; v < m.xy.size(); ++v) {
    if (m.rep[v] != v && !merged[v]) {
      add("input vertex " + std::to_string(v) + " is neither a vertex nor reported as merged");
    }
    if (m.meshOf[v] != kNone) {
      const Point3& p = mesh().point(VertexId(m.meshOf[v]));
      const std::uint32_t r0 = m.rep[v];
      if (r0 == v && !(p.xy() == m.xy[v])) {
        add("input vertex " + std::to_string(v) + " moved");
      }
    }
  }
  // Every input constraint segment is a chain of mesh edges carrying its
  // feature and running along the input segment (checked from the input
  // coordinates, not from the edge flags, and when no domain clips the
  // constraints): a path of edges with its feature from the mesh vertex of one
  // end to the other through vertices within rounding/snap distance of the
  // segment (only connected, for features bent by a forced crossing).
  if (!m.hasBoundary && !m.hasHole) {
    const Mesh& me = mesh();
    std::vector<std::vector<std::pair<std::uint32_t, FeatureId>>> adj(me.vertexCount());
    for (std::uint32_t h = 0; h < me.halfedgeCount(); ++h) {
      const std::uint32_t o = me.origin(HalfedgeId(h)).value, t = me.target(HalfedgeId(h)).value;
      for (FeatureId f : me.edgeFeatures(HalfedgeId(h))) {
        adj[o].emplace_back(t, f);
        adj[t].emplace_back(o, f);
      }
    }
    // A crossing moved to a vertex beyond the tolerance is reported (forced);
    // it bends both features' constraints, and later crossings may split the
    // bent edges, so their segments are checked for connectivity only.
    // Crossings snapped to a vertex bend both constraints by the distance
    // moved, and a later crossing on the bent piece may snap again: a
    // feature's chain may stray by the sum of its crossings' moves.
    std::vector<std::uint8_t> bent(m.features.size(), 0);
    std::vector<double> moved(m.features.size(), 0.0);
    for (const auto& ev : m.report.intersections) {
      for (const FeatureId g : {ev.existing, ev.inserted}) {
        if (g >= bent.size()) continue;
        if (ev.forced) bent[g] = 1;
        moved[g] += ev.moved;
      }
    }
    for (std::size_t g = 0; g < m.bend.size() && g < moved.size(); ++g) moved[g] += m.bend[g];
    std::vector<std::uint8_t> visited(me.vertexCount(), 0);  // by the chain search, per segment
    std::vector<std::uint32_t> queue;
    for (const Segment& s : m.segments) {
      const std::uint32_t a = m.meshOf[s.a], b = m.meshOf[s.b];
      if (a == b || s.feature >= m.features.size()) continue;
      const std::string name = "constraint segment " + std::to_string(s.a) + "-" +
                               std::to_string(s.b) + " (feature " + std::to_string(s.feature) + ")";
      if (a == kNone || b == kNone) {
        add(name + " has an end that is not a mesh vertex");
        continue;
      }
      const Point2 P = m.xy[s.a], Q = m.xy[s.b];
      const double dx = Q.x - P.x, dy = Q.y - P.y, len2 = dx * dx + dy * dy;
      const double len = std::sqrt(len2);
      const double tol = std::max({2 * m.options.snapTolerance, 16 * Impl::constructionTolerance(P),
                                   16 * Impl::constructionTolerance(Q), 1e-6 * len}) +
                         moved[s.feature];
      auto near = [&](std::uint32_t v) {
        const Point2 w = me.xy(VertexId(v));
        const double along = ((w.x - P.x) * dx + (w.y - P.y) * dy) / len;
        return std::fabs((w.x - P.x) * dy - (w.y - P.y) * dx) <= tol * len && along >= -tol &&
               along <= len + tol;
      };
      // Breadth-first over the feature's edges between vertices near the
      // segment (crossings of nearly parallel lines may come out of order
      // along it, so the chain need not be monotone). `visited` is cleared
      // again for the vertices this search queued only: linear in what it
      // reached.
      queue.assign(1, a);
      visited[a] = 1;
      bool reached = false;
      for (std::size_t head = 0; head < queue.size() && !reached; ++head) {
        const std::uint32_t v = queue[head];
        for (const auto& [w, f] : adj[v]) {
          ++chainSteps;
          if (f != s.feature || visited[w]) continue;
          if (w == b) {
            reached = true;
            break;
          }
          if (!bent[s.feature] && !near(w)) continue;
          visited[w] = 1;
          queue.push_back(w);
        }
      }
      for (const std::uint32_t v : queue) visited[v] = 0;
      if (!reached) {
        add(name + " is not a chain of mesh edges carrying its feature within " + formatCoord(tol) +
            " m of it");
      }
    }
  }
  return r;
}

Cdt Cdt::fromTinData(const TinData& tin, CdtOptions options) {
  if (options.crs.empty()) options.crs = tin.crs;
  Cdt cdt(std::move(options));
  for (const auto& f : tin.features) cdt.addFeature(f.kind, f.source);
  cdt.insertPoints(tin.vertices);
  const auto nv = tin.vertices.size();
  for (const auto& e : tin.constrainedEdges) {
    if (e.a >= nv || e.b >= nv || e.feature >= tin.features.size()) {
      throw inputError("constrained edge " + std::to_string(e.a) + "-" + std::to_string(e.b) +
                       " is out of range");
    }
    cdt.insertConstraintSegment(VertexId(e.a), VertexId(e.b), e.feature);
  }
  // The loaded mesh's boundary edges bound the domain again.
  const Mesh mesh = Mesh::fromTinData(tin);
  bool any = false;
  for (HalfedgeId h : mesh.boundaryHalfedges()) {
    cdt.impl_->segments.push_back(
        {mesh.origin(h).value, mesh.target(h).value, kDomainFeature});
    any = true;
  }
  // Every TIN gets them, a convex one too (its hull): by parity, triangles
  // outside its outer loop or inside a loop around a hole stay outside, and
  // so do points added later beyond its edge.
  cdt.impl_->hasBoundary = any;
  return cdt;
}

}  // namespace tinsmith
