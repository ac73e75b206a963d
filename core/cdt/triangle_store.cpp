// The triangle store's bulk operations: vertex half-edges, reservation, the
// LOP from a set of edges, and compaction into a Mesh and back (see
// triangle_store.hpp).
#include "core/cdt/triangle_store.hpp"

#include <string>

#include "core/base/error.hpp"
#include "core/cdt/spatial_order.hpp"

namespace tinsmith::cdt {

void TriangleStore::startTrackingVhe() {
  if (trackVhe) return;
  vhe.assign(xy.size(), kNone);
  for (std::uint32_t h = 0; h < tv.size(); ++h) {
    if (tv[h] != kInf) vhe[tv[h]] = h;
  }
  trackVhe = true;
}

void TriangleStore::reserveTriangles(std::size_t triangles) {
  tv.reserve(3 * triangles);
  opp.reserve(3 * triangles);
  cons.reserve(3 * triangles);
}

void TriangleStore::lop(std::vector<std::pair<std::uint32_t, std::uint32_t>>& todo) {
  std::size_t flips = 0;
  while (!todo.empty()) {
    const auto [p, q] = todo.back();
    todo.pop_back();
    if (p == kInf || q == kInf) continue;
    const std::uint32_t h = findHalfedge(p, q);
    if (h == kNone || cons[h]) continue;
    const std::uint32_t c = tv[prv(h)], d = tv[prv(opp[h])];
    if (c == kInf || d == kInf) continue;
    if (geometry::incircle(xy[p], xy[q], xy[c], xy[d]) > 0) {
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

void TriangleStore::lopAround(std::uint32_t v) {
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

MeshStorage TriangleStore::pack(std::vector<std::uint8_t> inside, std::span<const double> z,
                                std::size_t featureCount, unsigned threads,
                                std::vector<std::uint32_t>& vertexOf) {
  const std::uint32_t nt = triCount();
  // triMap: working triangle → output triangle (kNone outside); monotone, so
  // the compaction below can run in place. Transient: freed before the output
  // points are allocated.
  std::vector<std::uint32_t> triMap;
  {
    triMap.resize(nt);
    std::uint32_t k = 0;
    for (std::uint32_t t = 0; t < nt; ++t) triMap[t] = inside[t] ? k++ : kNone;
    std::vector<std::uint8_t>().swap(inside);
  }
  std::vector<std::uint32_t> used(xy.size(), kNone);
  std::uint32_t outT = 0;
  for (std::uint32_t t = 0; t < nt; ++t) {
    if (triMap[t] == kNone) continue;
    ++outT;
    for (std::uint32_t i = 0; i < 3; ++i) used[tv[3 * t + i]] = 0;
  }
  std::uint32_t outV = 0;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (used[v] != kNone) used[v] = outV++;
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
  std::vector<std::uint32_t> boundary;  // output half-edges without twin, ascending
  for (std::uint32_t t = 0; t < nt; ++t) {
    const std::uint32_t b = 3 * t;
    if (triMap[t] == kNone) {
      removed.push_back({t,
                         {tv[b], tv[b + 1], tv[b + 2]},
                         {opp[b], opp[b + 1], opp[b + 2]},
                         {cons[b], cons[b + 1], cons[b + 2]}});
      continue;
    }
    // Read t completely before writing slot triMap[t] <= t.
    const std::uint32_t c[3] = {tv[b], tv[b + 1], tv[b + 2]};
    const std::uint32_t g[3] = {opp[b], opp[b + 1], opp[b + 2]};
    const std::uint8_t k[3] = {cons[b], cons[b + 1], cons[b + 2]};
    const std::uint32_t o = 3 * triMap[t];
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (!k[i]) continue;
      fs.clear();
      for (FeatureId f : edgeFeatures.find(edgeKey(c[i], c[(i + 1) % 3]))) {
        if (f < featureCount) fs.push_back(f);
      }
      if (fs.empty()) continue;
      std::sort(fs.begin(), fs.end());
      mesh.consBits[(o + i) / 64] |= std::uint64_t{1} << ((o + i) % 64);
      mesh.featureIds.insert(mesh.featureIds.end(), fs.begin(), fs.end());
      mesh.featureBegin.push_back(static_cast<std::uint32_t>(mesh.featureIds.size()));
    }
    for (std::uint32_t i = 0; i < 3; ++i) {
      const std::uint32_t n = triMap[g[i] / 3];
      tv[o + i] = used[c[i]];
      opp[o + i] = n != kNone ? 3 * n + g[i] % 3 : kNone;
      cons[o + i] = k[i];
    }
    for (std::uint32_t i = 0; i < 3; ++i) {
      if (opp[o + i] == kNone) boundary.push_back(o + i);
    }
  }
  // Outgoing half-edge per vertex, the rule of Mesh::build: the first boundary
  // half-edge leaving v if there is one, else the first. Written back to
  // front without reading (the vertex order is unrelated to the triangle
  // order, so these stores are scattered).
  for (std::uint32_t h = 3 * outT; h-- > 0;) mesh.outgoing[tv[h]] = HalfedgeId(h);
  for (std::size_t i = boundary.size(); i-- > 0;) {
    mesh.outgoing[tv[boundary[i]]] = HalfedgeId(boundary[i]);
  }
  std::vector<std::uint32_t>().swap(boundary);
  std::vector<std::uint32_t>().swap(triMap);
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
  parallelChunks(threads, used.size(), [&](unsigned, std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (used[v] != kNone) mesh.points[used[v]] = {xy[v].x, xy[v].y, z[v]};
    }
  });
  vertexOf = std::move(used);
  return mesh;
}

void TriangleStore::unpack(std::vector<std::uint32_t>&& corners, std::vector<std::uint32_t>&& twins,
                           const std::vector<std::uint32_t>& workingVertex) {
  if (!packed) return;
  const std::uint32_t outT = packedTriangles;
  const auto nt = static_cast<std::uint32_t>(outT + removed.size());
  tv = std::move(corners);
  opp = std::move(twins);
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
      tv[3 * t + i] = workingVertex[tv[3 * o + i]];
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

}  // namespace tinsmith::cdt
