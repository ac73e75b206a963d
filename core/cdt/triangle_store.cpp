// The triangle store's bulk operations: vertex half-edges, reservation, the
// LOP from a set of edges, and compaction into a Mesh and back (see
// triangle_store.hpp).
#include "core/cdt/triangle_store.hpp"

#include <string>

#include "core/base/error.hpp"
#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::cdt {

void TriangleStore::startTrackingVhe() {
  if (trackVhe) return;
  vhe.assign(xy.size(), HalfedgeId::invalid());
  for (std::uint32_t i = 0; i < tv.size(); ++i) {
    const HalfedgeId h(i);
    if (origin(h) != kInfinite) vhe[origin(h)] = h;
  }
  trackVhe = true;
}

void TriangleStore::reserveTriangles(std::size_t triangles) {
  tv.reserve(3 * triangles);
  opp.reserve(3 * triangles);
  cons.reserve(3 * triangles);
}

void TriangleStore::lop(std::vector<std::pair<VertexId, VertexId>>& todo) {
  // Lawson's flips end: a flipped edge never comes back (each flip lowers
  // the lifted surface), so there are fewer than one a pair of vertices.
  // More is a bug, not a long run (a fan of thousands of points along a
  // tile's side takes more than a few flips a point).
  const std::size_t n = xy.size();
  const std::size_t limit = 64 + n * (n - 1) / 2;
  std::size_t flips = 0;
  while (!todo.empty()) {
    const auto [p, q] = todo.back();
    todo.pop_back();
    if (p == kInfinite || q == kInfinite) continue;
    const HalfedgeId h = findHalfedge(p, q);
    if (!h.valid() || cons[h]) continue;
    const VertexId c = origin(prv(h)), d = origin(prv(twin(h)));
    if (c == kInfinite || d == kInfinite) continue;
    if (geometry::incircle(xy[p], xy[q], xy[c], xy[d]) > 0) {
      if (++flips > limit) {
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

void TriangleStore::lopAround(VertexId v) {
  std::vector<std::pair<VertexId, VertexId>> todo;
  const HalfedgeId start = vhe[v];
  HalfedgeId h = start;
  do {
    todo.emplace_back(v, origin(nxt(h)));
    todo.emplace_back(origin(nxt(h)), origin(prv(h)));
    h = twin(prv(h));
  } while (h != start);
  lop(todo);
}

namespace {

/// (x, y) order: the rank of the symbolic lift.
bool lessXY(const Point2& a, const Point2& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

}  // namespace

void TriangleStore::settleTies() {
  // Every edge once (the half-edge with the smaller id); each flip queues the
  // quad's four outer edges. A flip at a tie keeps every incircle test where
  // it was, so the rest of the mesh stays Delaunay; the perturbed lift makes
  // the flips a descent, so they end (Lawson).
  std::vector<HalfedgeId> todo;
  for (std::uint32_t i = 0; i < tv.size(); ++i) {
    const HalfedgeId h(i);
    if (i < twin(h).value) todo.push_back(h);
  }
  std::size_t flips = 0;
  while (!todo.empty()) {
    const HalfedgeId h = todo.back();
    todo.pop_back();
    if (cons[h]) continue;
    const HalfedgeId g = twin(h);
    const VertexId p = origin(h), q = origin(nxt(h)), c = origin(prv(h)), d = origin(prv(g));
    if (std::max({p, q, c, d}) >= kInfinite) continue;
    if (geometry::incircle(xy[p], xy[q], xy[c], xy[d]) != 0) continue;
    // Raising the least point's lift puts d inside (p, q, c) when the least
    // is p or q (d's barycentric weights there are positive), outside when
    // it is c or d: flip pq to cd exactly when pq touches the least point.
    VertexId least = p;
    for (const VertexId v : {q, c, d})
      if (lessXY(xy[v], xy[least])) least = v;
    if (least != p && least != q) continue;
    if (++flips > 64 + 64 * xy.size())
      throw internalError("settling cocircular ties did not terminate");
    flip(h);
    const TriangleId t0 = triangleOf(h), t1 = triangleOf(g);
    for (const HalfedgeId e :
         {halfedgeOf(t0, 0), halfedgeOf(t0, 1), halfedgeOf(t1, 0), halfedgeOf(t1, 1)})
      todo.push_back(e);
  }
}

MeshStorage TriangleStore::pack(std::vector<std::uint8_t> inside, std::span<const double> z,
                                std::size_t featureCount, unsigned threads,
                                IdVector<VertexId, VertexId>& vertexOf) {
  const std::uint32_t nt = triCount();
  // triMap: working triangle → output triangle (invalid outside); monotone,
  // so the compaction below can run in place. Transient: freed before the
  // output points are allocated.
  IdVector<TriangleId, TriangleId> triMap;
  {
    triMap.resize(nt);
    std::uint32_t k = 0;
    for (std::uint32_t t = 0; t < nt; ++t) {
      triMap[TriangleId(t)] = inside[t] ? TriangleId(k++) : TriangleId::invalid();
    }
    std::vector<std::uint8_t>().swap(inside);
  }
  // used: working vertex → mesh vertex (first only marked with id 0).
  IdVector<VertexId, VertexId> used(xy.size(), VertexId::invalid());
  std::uint32_t outT = 0;
  constexpr std::uint32_t kAhead = 16;  // triangles whose vertices are prefetched
  for (std::uint32_t i = 0; i < nt; ++i) {
    if (i + kAhead < nt)
      for (std::uint32_t h = 3 * (i + kAhead); h < 3 * (i + kAhead) + 3; ++h)
        if (tv[h] < used.size()) __builtin_prefetch(&used[VertexId(tv[h])], 1);
    const TriangleId t(i);
    if (!triMap[t].valid()) continue;
    ++outT;
    for (std::uint32_t c = 0; c < 3; ++c) used[corner(t, c)] = VertexId(0);
  }
  std::uint32_t outV = 0;
  for (VertexId& u : used) {
    if (u.valid()) u = VertexId(outV++);
  }
  MeshStorage mesh;
  mesh.outgoing.assign(outV, HalfedgeId());
  removed.clear();
  removed.reserve(nt - outT);
  // Features of constrained half-edges go straight into the mesh's compact
  // form (MeshStorage): output half-edges come in ascending order.
  mesh.consBits.assign(3 * static_cast<std::size_t>(outT) / 64 + 1, 0);
  mesh.featureBegin.assign(1, 0);
  std::vector<FeatureId> fs;
  std::vector<HalfedgeId> boundary;  // output half-edges without twin, ascending
  // The arrays are rewritten in place, as the mesh's raw corners and twins.
  // A triangle's corners and its neighbours are anywhere in `used` and
  // `triMap`: those of the triangle kAhead slots on are prefetched.
  for (std::uint32_t i = 0; i < nt; ++i) {
    if (i + kAhead < nt) {
      for (std::uint32_t h = 3 * (i + kAhead); h < 3 * (i + kAhead) + 3; ++h) {
        if (tv[h] < used.size()) __builtin_prefetch(&used[VertexId(tv[h])]);
        if (opp[h] < opp.size()) __builtin_prefetch(&triMap[TriangleId(opp[h] / 3)]);
      }
    }
    const TriangleId t(i);
    const std::uint32_t b = halfedgeOf(t, 0).value;
    if (!triMap[t].valid()) {
      removed.push_back({t,
                         {tv[b], tv[b + 1], tv[b + 2]},
                         {opp[b], opp[b + 1], opp[b + 2]},
                         {cons[halfedgeOf(t, 0)], cons[halfedgeOf(t, 1)], cons[halfedgeOf(t, 2)]}});
      continue;
    }
    // Read t completely before writing slot triMap[t] <= t.
    const VertexId c[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
    const HalfedgeId g[3] = {twin(halfedgeOf(t, 0)), twin(halfedgeOf(t, 1)),
                             twin(halfedgeOf(t, 2))};
    const std::uint8_t k[3] = {cons[halfedgeOf(t, 0)], cons[halfedgeOf(t, 1)],
                               cons[halfedgeOf(t, 2)]};
    const TriangleId o = triMap[t];
    for (std::uint32_t j = 0; j < 3; ++j) {
      if (!k[j]) continue;
      fs.clear();
      for (FeatureId f : edgeFeatures.find(edgeKey(c[j], c[(j + 1) % 3]))) {
        if (f < featureCount) fs.push_back(f);
      }
      if (fs.empty()) continue;
      std::sort(fs.begin(), fs.end());
      const std::uint32_t out = halfedgeOf(o, j).value;
      mesh.consBits[out / 64] |= std::uint64_t{1} << (out % 64);
      mesh.featureIds.insert(mesh.featureIds.end(), fs.begin(), fs.end());
      mesh.featureBegin.push_back(static_cast<std::uint32_t>(mesh.featureIds.size()));
    }
    for (std::uint32_t j = 0; j < 3; ++j) {
      const HalfedgeId out = halfedgeOf(o, j);
      const TriangleId n = triMap[triangleOf(g[j])];
      tv[out.value] = used[c[j]].value;
      opp[out.value] = n.valid() ? halfedgeOf(n, cornerOf(g[j])).value : HalfedgeId::kInvalid;
      cons[out] = k[j];
    }
    for (std::uint32_t j = 0; j < 3; ++j) {
      if (!twin(halfedgeOf(o, j)).valid()) boundary.push_back(halfedgeOf(o, j));
    }
  }
  // Outgoing half-edge per vertex, the rule of Mesh::build: the first boundary
  // half-edge leaving v if there is one, else the first. Written back to
  // front without reading (the vertex order is unrelated to the triangle
  // order, so these stores are scattered). Corners are mesh vertices now.
  for (std::uint32_t h = 3 * outT; h-- > 0;) mesh.outgoing[tv[h]] = HalfedgeId(h);
  for (std::size_t i = boundary.size(); i-- > 0;) {
    mesh.outgoing[tv[boundary[i].value]] = boundary[i];
  }
  std::vector<HalfedgeId>().swap(boundary);
  std::vector<TriangleId>().swap(triMap);
  tv.resize(3 * static_cast<std::size_t>(outT));
  opp.resize(3 * static_cast<std::size_t>(outT));
  cons.resize(3 * static_cast<std::size_t>(outT));
  packedTriangles = outT;
  packed = true;

  mesh.corners = std::move(tv);
  mesh.twins = std::move(opp);
  tv.clear();
  opp.clear();
  mesh.points.resize(outV);
  parallelParts(
      used.size(), threads, threads,
      [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) {
          const VertexId v(static_cast<std::uint32_t>(i));
          if (used[v].valid()) mesh.points[used[v].value] = {xy[v].x, xy[v].y, z[i]};
        }
      },
      kSerialBelow);
  vertexOf = std::move(used);
  return mesh;
}

void TriangleStore::unpack(std::vector<std::uint32_t>&& corners, std::vector<std::uint32_t>&& twins,
                           const std::vector<VertexId>& workingVertex) {
  if (!packed) return;
  const std::uint32_t outT = packedTriangles;
  const auto nt = static_cast<std::uint32_t>(outT + removed.size());
  // Mesh corners and twins become working ones in place, in raw form.
  tv = std::move(corners);
  opp = std::move(twins);
  tv.resize(3 * static_cast<std::size_t>(nt));
  opp.resize(3 * static_cast<std::size_t>(nt));
  cons.resize(3 * static_cast<std::size_t>(nt));
  IdVector<TriangleId, TriangleId> slotOf(outT);  // mesh triangle → working slot
  // Back to front: kept triangle o moves to slot t >= o.
  std::size_t r = removed.size();
  std::uint32_t o = outT;
  for (std::uint32_t t = nt; t-- > 0;) {
    if (r > 0 && removed[r - 1].slot.value == t) {
      --r;
      continue;  // filled below
    }
    --o;
    slotOf[TriangleId(o)] = TriangleId(t);
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId to = halfedgeOf(TriangleId(t), i), from = halfedgeOf(TriangleId(o), i);
      tv[to.value] = workingVertex[tv[from.value]].value;
      opp[to.value] = opp[from.value];  // a mesh half-edge id; remapped below
      cons[to] = cons[from];
    }
  }
  r = 0;
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (r < removed.size() && removed[r].slot.value == t) {
      ++r;
      continue;
    }
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId h = halfedgeOf(TriangleId(t), i), g = twin(h);
      if (g.valid()) opp[h.value] = halfedgeOf(slotOf[triangleOf(g)], cornerOf(g)).value;
    }
  }
  for (const RemovedTriangle& x : removed) {
    for (std::uint32_t i = 0; i < 3; ++i) {
      const HalfedgeId h = halfedgeOf(x.slot, i);
      tv[h.value] = x.tv[i];
      cons[h] = x.cons[i];
      link(h, HalfedgeId(x.opp[i]));
    }
  }
  std::vector<RemovedTriangle>().swap(removed);
  packed = false;
}

}  // namespace tinsmith::cdt
