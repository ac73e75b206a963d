// Helper of the martini comparison (vs_martini.sh): the parts of that benchmark
// that need the DEM-TIN, so that both pyramids are sampled and measured by the
// same code.
//
//   tile_error_bench store SITE.3dtiles
//     tinsmith's tiles per zoom from their records (asset.extras): tiles,
//     triangles (with skirts), .glb bytes, Draco payload bytes (the .glb's
//     binary chunk), measured max error, the range of the Draco position
//     error bounds. JSON lines.
//   tile_error_bench grids SITE.tin SITE.3dtiles SPACING TOLERANCES OUT.grids
//     For every tile of the store, the DEM-TIN sampled at the nodes of a
//     (2^k + 1)² grid over the tile's square, 2^k the least power of two whose
//     spacing is at most SPACING (m), or the same n = 2^k + 1 for every tile
//     when SPACING is "n=257" (say): the DEM resampled for martini. Nodes
//     outside the TIN take the TIN's z at the nearest point of its boundary
//     (a continuous extension) and are flagged. TOLERANCES is "z:t,z:t,…", the zoom
//     tolerances of tinsmith's summary, stored with each tile.
//   tile_error_bench error SITE.tin MESHES.bin [THREADS]
//     The exact max vertical difference (tiles::maxVerticalDifference, the
//     largest of tiles::triangleDifferences) between every tile mesh of
//     MESHES.bin and the DEM-TIN, per zoom, where it is reached, the max over
//     the triangles wholly inside the TIN, and the largest difference at a
//     TIN vertex (a DEM cell). JSON lines.
//
//
// Cesium terrain (terrain_vs_martini.sh), on the geographic working frame of
// core/tiles/terrain_tiling.hpp (x = lon·k, y = lat·k, k = kMetresPerDegree,
// z the ellipsoidal height; the geographic TIN is toGeographicTin of SITE.tin
// with the TIN's CRS and no geoid, as `tinsmith tile --scheme quantized-mesh`
// without --geoid builds it):
//
//   tile_error_bench terrain-store STORE
//     Per level, the quantized-mesh tiles terrain/z/x/y.terrain of STORE (a
//     .3dtiles archive or a directory): tiles, bytes, gzip -6 bytes, bytes of
//     the metadata extension (5 + its length), vertices, triangles, and the
//     max of the records' errors when the tiles carry one. JSON lines.
//   tile_error_bench terrain-grids SITE.tin STORE SPACING [MINCELLS:]MAXCELLS OUT.grids [FILL]
//     For every terrain tile of STORE, the geographic TIN sampled at the
//     nodes of a (2^k + 1)² longitude/latitude grid over the tile's rectangle
//     (geographicTileBounds), 2^k the least power of two whose spacing in the
//     working frame is at most SPACING, at least MINCELLS (default 1) and at
//     most MAXCELLS cells. Nodes
//     outside the TIN: FILL pullpush (the default) gives those within two
//     nodes of an inside node the TIN's z at the nearest boundary point and
//     fills the rest from them by pull-push (a pyramid of averages, bilinear
//     back down: smooth, so martini spends few triangles where no data is);
//     nearest
//     as for `grids`, the TIN's z at the nearest boundary point (continuous
//     along the boundary but not across the exterior's medial axis, where
//     the nearest point jumps between two sides of a bay: martini follows
//     those steps with thousands of triangles). Pull-push falls back to
//     nearest in a tile with no node inside; a tile whose rectangle misses
//     the TIN's bounding box is 0 (the ellipsoid). Format: per tile int32 level, x, y, n; float64
//     west, south, east, north (degrees); n·n float64 heights; n·n uint8
//     inside-flags; rows south to north.
//   tile_error_bench terrain-error SITE.tin STORE [THREADS [TILES.jsonl]]
//     Decodes every terrain/z/x/y.terrain of STORE as a client does (u, v
//     across the grid's rectangle of the tile, heights across the header's
//     range) into the working frame and measures it against the geographic
//     TIN with tiles::triangleDifferences. A triangle with a corner at height
//     0 (within 1e-6 m) is fill (the ellipsoid outside the TIN and the walls down to
//     it, as tinsmith's terrain_fill.hpp makes them): not counted in the
//     error, its largest difference over the TIN reported apart, and so are
//     the TIN vertices off the TIN's boundary that lie inside a fill triangle
//     and in no surface triangle ("underFill": the fill reaching into the
//     TIN by more than quantization can move the TIN's edge), with the
//     largest distance of one from the TIN's boundary. Per level:
//     max error, where, the largest at a TIN vertex. JSON lines; with
//     TILES.jsonl, one line per tile there too.
//
// The pyramid's square is computed as the tiler computes it
// (core/tiles/tiler.cpp): origin the TIN's min corner, size the larger side.
//
// Formats (little-endian). OUT.grids, per tile: int32 z, x, y, n (nodes a
// side); float64 x0, y0, x1, y1, zoom tolerance; n·n float64 heights and n·n
// uint8 inside-flags, row j (y = y0 + j·step, south to north) after row j − 1.
// MESHES.bin, per tile: int32 z, x, y; uint32 vertex count, triangle count;
// float64 x, y, z per vertex (project CRS); uint32 a, b, c per triangle (CCW).
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include "core/encode/quantized_mesh.hpp"
#include "core/geometry/predicates.hpp"
#include "core/tiles/geographic_grid.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/terrain_content.hpp"
#include "core/tiles/terrain_tiling.hpp"
#include "core/tiles/tile_content.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tinfile/tin_file.hpp"

using namespace tinsmith;
using namespace tinsmith::tiles;

namespace {

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "tile_error_bench: %s\n", message.c_str());
  std::exit(2);
}

PyramidGeometry pyramidOf(const TinData& tin) {
  const Rect extent = boundsOf(tin.vertices);
  return PyramidGeometry({extent.x0, extent.y0}, std::max(extent.width(), extent.height()));
}

// The tiles of a store: "tiles/z/x/y.glb" keys, in the pyramid's order.
std::vector<TileId> storeTiles(const store::TileStore& s) {
  std::vector<TileId> ids;
  for (const std::string& key : s.keys()) {
    TileId id;
    if (std::sscanf(key.c_str(), "tiles/%d/%u/%u.glb", &id.z, &id.x, &id.y) == 3) ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end(), rowMajorLess);
  if (ids.empty()) fail("no tiles/z/x/y.glb in " + s.path().string());
  return ids;
}

std::uint32_t readU32(const std::string& b, std::size_t at) {
  if (at + 4 > b.size()) fail("truncated .glb");
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// glb: 12-byte header, then chunks (length, type, data); the second chunk is
// the binary one, which holds the Draco payload (or the raw buffers).
std::size_t binaryChunkBytes(const std::string& glb) {
  const std::uint32_t jsonLength = readU32(glb, 12);
  const std::size_t bin = 20 + jsonLength;
  return bin + 8 <= glb.size() ? readU32(glb, bin) : 0;
}

struct ZoomRow {
  std::size_t tiles = 0, triangles = 0, bytes = 0, payload = 0;
  double maxError = 0.0;
  double boundMin = HUGE_VAL, boundMax = 0.0;  ///< Draco position error bounds (m)
  TileId worst;
};

int storeCommand(const std::string& path) {
  const auto s = store::openStoreForReading(path);
  std::map<int, ZoomRow> rows;
  for (const TileId& id : storeTiles(*s)) {
    const std::string glb = *s->get("tiles/" + id.name() + ".glb");
    const auto record = recordFromGlb(glb);
    if (!record) fail("tile " + id.name() + " has no record");
    ZoomRow& r = rows[id.z];
    ++r.tiles;
    r.triangles += record->triangles;
    r.bytes += glb.size();
    r.payload += binaryChunkBytes(glb);
    if (record->error >= r.maxError) {
      r.maxError = record->error;
      r.worst = id;
    }
    r.boundMin = std::min(r.boundMin, record->positionErrorBound);
    r.boundMax = std::max(r.boundMax, record->positionErrorBound);
  }
  for (const auto& [z, r] : rows) {
    std::printf(
        "{\"zoom\":%d,\"tiles\":%zu,\"triangles\":%zu,\"bytes\":%zu,\"payload\":%zu,"
        "\"maxError\":%.6f,\"worst\":\"%s\",\"quantMin\":%.4f,\"quantMax\":%.4f}\n",
        z, r.tiles, r.triangles, r.bytes, r.payload, r.maxError, r.worst.name().c_str(), r.boundMin,
        r.boundMax);
  }
  return 0;
}

std::map<int, double> parseTolerances(const std::string& text) {
  std::map<int, double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    int z = 0;
    double t = 0;
    if (std::sscanf(item.c_str(), "%d:%lf", &z, &t) != 2) fail("bad tolerance item '" + item + "'");
    out[z] = t;
  }
  return out;
}

template <typename T>
void put(std::ofstream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

// The TIN's boundary edges (those of one triangle), for the grid nodes outside
// it: the TIN's z at the nearest boundary point.
class TinBoundary {
 public:
  explicit TinBoundary(const TinData& tin) : tin_(tin) {
    std::unordered_set<std::uint64_t> directed;
    auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
    for (const auto& t : tin.triangles) {
      for (int i = 0; i < 3; ++i) directed.insert(key(t[i], t[(i + 1) % 3]));
    }
    for (const auto& t : tin.triangles) {
      for (int i = 0; i < 3; ++i) {
        if (!directed.contains(key(t[(i + 1) % 3], t[i]))) edges_.push_back({t[i], t[(i + 1) % 3]});
      }
    }
  }

  /// The edges that can hold the nearest boundary point of a point in `r`:
  /// those whose bounding box is no farther from `r` than the smallest, over
  /// the edges, of the farthest distance from `r` to the edge (taken at a
  /// corner of `r`: the distance to a segment is convex).
  [[nodiscard]] std::vector<std::uint32_t> candidates(const Rect& r) const {
    double bound = HUGE_VAL;
    for (const auto& e : edges_) {
      double farthest = 0.0;
      for (const Point2 c :
           {Point2{r.x0, r.y0}, Point2{r.x1, r.y0}, Point2{r.x0, r.y1}, Point2{r.x1, r.y1}})
        farthest = std::max(farthest, nearestOnEdge(e, c).first);
      bound = std::min(bound, farthest);
    }
    std::vector<std::uint32_t> out;
    for (std::uint32_t i = 0; i < edges_.size(); ++i) {
      const Point3& a = tin_.vertices[edges_[i][0]];
      const Point3& b = tin_.vertices[edges_[i][1]];
      const double gx = std::max({0.0, std::min(a.x, b.x) - r.x1, r.x0 - std::max(a.x, b.x)});
      const double gy = std::max({0.0, std::min(a.y, b.y) - r.y1, r.y0 - std::max(a.y, b.y)});
      if (gx * gx + gy * gy <= bound) out.push_back(i);
    }
    return out;
  }

  [[nodiscard]] const std::vector<std::array<std::uint32_t, 2>>& edges() const { return edges_; }

  /// Distance from p to the boundary (all edges: for a few points).
  [[nodiscard]] double distance(Point2 p) const {
    double best = HUGE_VAL;
    for (const auto& e : edges_) best = std::min(best, nearestOnEdge(e, p).first);
    return std::sqrt(best);
  }

  /// z of the boundary point nearest p, interpolated along its edge, over
  /// `candidates` (of a rectangle holding p).
  [[nodiscard]] double nearestZ(Point2 p, const std::vector<std::uint32_t>& candidates) const {
    double best = HUGE_VAL, bestZ = 0.0;
    for (const std::uint32_t i : candidates) {
      const auto [d, z] = nearestOnEdge(edges_[i], p);
      if (d < best) {
        best = d;
        bestZ = z;
      }
    }
    return bestZ;
  }

 private:
  // Squared distance from p to the edge, and the edge's z at its point nearest p.
  [[nodiscard]] std::pair<double, double> nearestOnEdge(const std::array<std::uint32_t, 2>& e,
                                                        Point2 p) const {
    const Point3& a = tin_.vertices[e[0]];
    const Point3& b = tin_.vertices[e[1]];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double t =
        std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
    const double ex = a.x + t * dx - p.x, ey = a.y + t * dy - p.y;
    return {ex * ex + ey * ey, a.z + t * (b.z - a.z)};
  }

  const TinData& tin_;
  std::vector<std::array<std::uint32_t, 2>> edges_;
};

int gridsCommand(const std::string& tinPath, const std::string& storePath,
                 const std::string& spacing, const std::string& tolerances,
                 const std::string& outPath) {
  const auto t0 = std::chrono::steady_clock::now();
  const TinData tin = ingest::readTinFile(tinPath);
  const TinIndex index(tin);
  const PyramidGeometry pyramid = pyramidOf(tin);
  const TinBoundary boundary(tin);
  int fixedCells = 0;
  double resolution = 0.0;
  if (spacing.starts_with("n=")) {
    fixedCells = std::stoi(spacing.substr(2)) - 1;
    if (fixedCells < 1 || (fixedCells & (fixedCells - 1)) != 0)
      fail("a grid of n=2^k+1 nodes, not " + spacing);
  } else {
    resolution = std::stod(spacing);
    if (!(resolution > 0)) fail("the grid spacing must be positive, not " + spacing);
  }
  const auto s = store::openStoreForReading(storePath);
  const std::map<int, double> zoomTolerance = parseTolerances(tolerances);
  std::ofstream out(outPath, std::ios::binary);
  if (!out) fail("cannot write " + outPath);
  std::size_t nodes = 0, outside = 0, tiles = 0;
  for (const TileId& id : storeTiles(*s)) {
    const auto tol = zoomTolerance.find(id.z);
    if (tol == zoomTolerance.end()) fail("no tolerance given for zoom " + std::to_string(id.z));
    const Rect b = pyramid.bounds(id);
    int cells = 1;
    if (fixedCells > 0) {
      cells = fixedCells;
    } else {
      while (b.width() / cells > resolution && cells < 4096) cells *= 2;
    }
    const int n = cells + 1;
    const double step = b.width() / cells;
    std::vector<double> z(static_cast<std::size_t>(n) * n, 0.0);
    std::vector<std::uint8_t> inside(z.size(), 0);
    std::size_t insideCount = 0;
    auto nodeAt = [&](std::size_t k) {
      const int i = static_cast<int>(k % n), j = static_cast<int>(k / n);
      // The last node lands on the tile's side exactly, as tinsmith's does.
      return Point2{i == cells ? b.x1 : b.x0 + i * step, j == cells ? b.y1 : b.y0 + j * step};
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * n + i;
        if (const auto h = index.z(nodeAt(k))) {
          z[k] = *h;
          inside[k] = 1;
          ++insideCount;
        }
      }
    }
    if (insideCount == 0) fail("tile " + id.name() + " holds no TIN point on its grid");
    // Outside the TIN: the TIN's z at the nearest point of its boundary, a
    // continuous extension (martini needs a value at every node).
    if (insideCount < z.size()) {
      const std::vector<std::uint32_t> near = boundary.candidates(b);
      for (std::size_t k = 0; k < z.size(); ++k) {
        if (!inside[k]) z[k] = boundary.nearestZ(nodeAt(k), near);
      }
    }
    put(out, id.z);
    put(out, static_cast<std::int32_t>(id.x));
    put(out, static_cast<std::int32_t>(id.y));
    put(out, static_cast<std::int32_t>(n));
    for (double v : {b.x0, b.y0, b.x1, b.y1, tol->second}) put(out, v);
    out.write(reinterpret_cast<const char*>(z.data()), static_cast<std::streamsize>(z.size() * 8));
    out.write(reinterpret_cast<const char*>(inside.data()),
              static_cast<std::streamsize>(inside.size()));
    nodes += z.size();
    outside += z.size() - static_cast<std::size_t>(std::count(inside.begin(), inside.end(), 1));
    ++tiles;
  }
  if (!out.flush()) fail("cannot write " + outPath);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "{\"tiles\":%zu,\"nodes\":%zu,\"outside\":%zu,\"seconds\":%.3f,\"x0\":%.6f,\"y0\":%.6f,"
      "\"size\":%.6f}\n",
      tiles, nodes, outside, seconds, pyramid.origin().x, pyramid.origin().y, pyramid.size());
  return 0;
}

struct MeshTile {
  TileId id;
  std::vector<Point3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

std::vector<MeshTile> readMeshes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot read " + path);
  std::vector<MeshTile> tiles;
  for (;;) {
    std::int32_t head[3];
    if (!in.read(reinterpret_cast<char*>(head), sizeof head)) break;
    std::uint32_t counts[2];
    MeshTile t;
    t.id = {head[0], static_cast<std::uint32_t>(head[1]), static_cast<std::uint32_t>(head[2])};
    if (!in.read(reinterpret_cast<char*>(counts), sizeof counts)) fail("truncated " + path);
    t.vertices.resize(counts[0]);
    t.triangles.resize(counts[1]);
    in.read(reinterpret_cast<char*>(t.vertices.data()),
            static_cast<std::streamsize>(counts[0] * 24));
    in.read(reinterpret_cast<char*>(t.triangles.data()),
            static_cast<std::streamsize>(counts[1] * 12));
    if (!in) fail("truncated " + path + " in tile " + t.id.name());
    for (const auto& tri : t.triangles) {
      for (auto v : tri) {
        if (v >= counts[0]) fail("tile " + t.id.name() + ": vertex index out of range");
      }
    }
    tiles.push_back(std::move(t));
  }
  if (tiles.empty()) fail("no tiles in " + path);
  return tiles;
}

// One tile's errors against the TIN: the exact max over the whole mesh, the
// largest at a TIN vertex (a DEM cell), and the max over the triangles whose
// three corners lie in the TIN (a DEM-TIN's domain is convex, so these lie
// wholly inside it: what is left when the triangles across its boundary, where
// a square grid meets the convex hull, are set aside).
struct TileError {
  SurfaceDifference worst;
  double atVertex = 0.0;
  Point2 vertex;
  double inside = 0.0;
};

TileError measureTile(const MeshTile& tile, const TinIndex& index) {
  std::vector<std::uint8_t> inTin(tile.vertices.size());
  for (std::size_t v = 0; v < inTin.size(); ++v)
    inTin[v] = index.z(tile.vertices[v].xy()).has_value();
  const std::vector<SurfaceDifference> diffs =
      triangleDifferences(tile.vertices, tile.triangles, index);
  TileError e;
  for (std::size_t t = 0; t < diffs.size(); ++t) {
    const SurfaceDifference& d = diffs[t];
    if (d.maxAbs > e.worst.maxAbs) e.worst = d;
    if (d.vertexAbs > e.atVertex) {
      e.atVertex = d.vertexAbs;
      e.vertex = d.vertex;
    }
    const auto& c = tile.triangles[t];
    if (inTin[c[0]] && inTin[c[1]] && inTin[c[2]]) e.inside = std::max(e.inside, d.maxAbs);
  }
  return e;
}

int errorCommand(const std::string& tinPath, const std::string& meshPath, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  const TinData tin = ingest::readTinFile(tinPath);
  const TinIndex index(tin);
  const std::vector<MeshTile> tiles = readMeshes(meshPath);
  std::vector<TileError> errors(tiles.size());
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failureLock;
  auto work = [&] {
    try {
      for (std::size_t i; (i = next++) < tiles.size();) errors[i] = measureTile(tiles[i], index);
    } catch (...) {
      const std::lock_guard lock(failureLock);
      failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  struct Row {
    std::size_t tiles = 0, triangles = 0;
    TileId worstTile;
    TileError worst;  // the largest of each measure over the zoom's tiles
  };
  std::map<int, Row> rows;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    Row& r = rows[tiles[i].id.z];
    const TileError& e = errors[i];
    ++r.tiles;
    r.triangles += tiles[i].triangles.size();
    if (e.worst.maxAbs >= r.worst.worst.maxAbs) {
      r.worst.worst = e.worst;
      r.worstTile = tiles[i].id;
    }
    if (e.atVertex >= r.worst.atVertex) {
      r.worst.atVertex = e.atVertex;
      r.worst.vertex = e.vertex;
    }
    r.worst.inside = std::max(r.worst.inside, e.inside);
  }
  for (const auto& [z, r] : rows) {
    const TileError& w = r.worst;
    std::printf(
        "{\"zoom\":%d,\"tiles\":%zu,\"surfaceTriangles\":%zu,\"maxError\":%.6f,"
        "\"maxInside\":%.6f,\"maxAtDemPoints\":%.6f,\"atDemPoint\":[%.3f,%.3f],\"worst\":\"%s\","
        "\"at\":[%.3f,%.3f],\"meshZ\":%.3f,\"tinZ\":%.3f}\n",
        z, r.tiles, r.triangles, w.worst.maxAbs, w.inside, w.atVertex, w.vertex.x, w.vertex.y,
        r.worstTile.name().c_str(), w.worst.at.x, w.worst.at.y, w.worst.meshZ, w.worst.tinZ);
  }
  std::printf("{\"seconds\":%.3f}\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

// ---- Cesium terrain (terrain_vs_martini.sh) ----

tiles::GeographicTin geographicTinOf(const TinData& tin) {
  const ingest::ProjGeoReference geo(tin.crs, "");
  return tiles::toGeographicTin(tin, geo);
}

// The terrain tiles of a store: "terrain/z/x/y.terrain" keys, level by level.
std::vector<TileId> terrainTiles(const store::TileStore& s) {
  std::vector<TileId> ids;
  for (const std::string& key : s.keys()) {
    TileId id;
    char tail[16] = {};
    if (std::sscanf(key.c_str(), "terrain/%d/%u/%u.%15s", &id.z, &id.x, &id.y, tail) == 4 &&
        std::string(tail) == "terrain")
      ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end(), rowMajorLess);
  if (ids.empty()) fail("no terrain/z/x/y.terrain in " + s.path().string());
  return ids;
}

std::string terrainKey(const TileId& id) {
  return "terrain/" + std::to_string(id.z) + "/" + std::to_string(id.x) + "/" +
         std::to_string(id.y) + ".terrain";
}

std::size_t gzipBytes(const std::string& in) {
  z_stream z{};
  if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) fail("zlib");
  std::string out(deflateBound(&z, in.size()) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  if (deflate(&z, Z_FINISH) != Z_STREAM_END) fail("zlib deflate");
  const std::size_t n = z.total_out;
  deflateEnd(&z);
  return n;
}

// A quantized-mesh-1.0 tile as a client reads it (the format's text, not
// tinsmith's encoder): header, zig-zag deltas, high-water-mark indices, edge
// lists, extensions. Throws on bytes that end early or are left over.
struct DecodedTerrain {
  double minHeight = 0, maxHeight = 0;
  std::vector<std::uint16_t> u, v, h;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::array<std::vector<std::uint32_t>, 4> edges;
  std::map<int, std::size_t> extensionBytes;  // id → 5 + length
};

DecodedTerrain decodeTerrain(const std::string& b, const std::string& name) {
  DecodedTerrain d;
  std::size_t at = 0;
  auto read = [&](void* out, std::size_t n) {
    if (at + n > b.size()) fail(name + ": ends early");
    std::memcpy(out, b.data() + at, n);
    at += n;
  };
  auto u32 = [&] {
    std::uint32_t x;
    read(&x, 4);
    return x;
  };
  at = 24;  // centre
  float lo, hi;
  read(&lo, 4);
  read(&hi, 4);
  d.minHeight = lo;
  d.maxHeight = hi;
  at = 88;
  const std::uint32_t n = u32();
  for (auto* values : {&d.u, &d.v, &d.h}) {
    values->resize(n);
    int value = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint16_t code;
      read(&code, 2);
      value += (code >> 1) ^ (-(code & 1));
      if (value < 0 || value > 32767) fail(name + ": a quantized value out of 0..32767");
      (*values)[i] = static_cast<std::uint16_t>(value);
    }
  }
  const bool wide = n > 65536;
  const std::size_t width = wide ? 4 : 2;
  while (at % width != 0) ++at;
  auto index = [&]() -> std::uint32_t {
    if (wide) return u32();
    std::uint16_t i;
    read(&i, 2);
    return i;
  };
  const std::uint32_t triangles = u32();
  d.triangles.resize(triangles);
  std::uint32_t highest = 0;
  for (auto& t : d.triangles) {
    for (auto& c : t) {
      const std::uint32_t code = index();
      c = highest - code;
      if (code == 0) ++highest;
      if (c >= n) fail(name + ": a triangle index out of range");
    }
  }
  for (auto& edge : d.edges) {
    const std::uint32_t count = u32();
    for (std::uint32_t k = 0; k < count; ++k) edge.push_back(index());
  }
  while (at < b.size()) {
    std::uint8_t id;
    read(&id, 1);
    const std::uint32_t length = u32();
    if (at + length > b.size()) fail(name + ": an extension runs past the end");
    d.extensionBytes[id] += 5 + length;
    at += length;
  }
  return d;
}

struct TerrainLevelRow {
  std::size_t tiles = 0, bytes = 0, gzip = 0, metadata = 0, vertices = 0, triangles = 0;
  double recordError = -1;
  TileId recordWorst;
};

int terrainStoreCommand(const std::string& path) {
  const auto s = store::openStoreForReading(path);
  std::map<int, TerrainLevelRow> rows;
  for (const TileId& id : terrainTiles(*s)) {
    const std::string bytes = *s->get(terrainKey(id));
    const DecodedTerrain d = decodeTerrain(bytes, id.name());
    TerrainLevelRow& r = rows[id.z];
    ++r.tiles;
    r.bytes += bytes.size();
    r.gzip += gzipBytes(bytes);
    if (d.extensionBytes.contains(encode::kMetadata))
      r.metadata += d.extensionBytes.at(encode::kMetadata);
    r.vertices += d.u.size();
    r.triangles += d.triangles.size();
    if (const auto record = tiles::recordFromTerrainTile(bytes);
        record && record->error >= r.recordError) {
      r.recordError = record->error;
      r.recordWorst = id;
    }
  }
  for (const auto& [z, r] : rows) {
    std::printf(
        "{\"level\":%d,\"tiles\":%zu,\"bytes\":%zu,\"gzip\":%zu,\"metadata\":%zu,\"vertices\":%zu,"
        "\"triangles\":%zu,\"recordError\":%.6f,\"recordWorst\":\"%s\",\"cesiumError\":%.6f}\n",
        z, r.tiles, r.bytes, r.gzip, r.metadata, r.vertices, r.triangles, r.recordError,
        r.recordWorst.name().c_str(), tiles::cesiumLevelMaximumGeometricError(z));
  }
  return 0;
}

// Pull-push fill of the nodes of an n × n grid (n = 2^k + 1) where `valid`
// is 0: a pyramid of tent-weighted averages of the valid nodes (pull), then
// each level's missing weight filled by bilinear interpolation of the level
// above (push). Smooth away from the valid nodes, with small steps next to
// them; false when no node is valid.
bool pullPushFill(std::vector<double>& z, const std::vector<std::uint8_t>& valid, int n) {
  struct Level {
    int n;
    std::vector<double> v, w;
  };
  std::vector<Level> levels;
  levels.push_back({n, z, std::vector<double>(z.size())});
  for (std::size_t k = 0; k < z.size(); ++k) levels[0].w[k] = valid[k] ? 1.0 : 0.0;
  while (levels.back().n > 2) {
    const Level& f = levels.back();
    Level c{(f.n - 1) / 2 + 1, {}, {}};
    c.v.assign(static_cast<std::size_t>(c.n) * c.n, 0.0);
    c.w.assign(c.v.size(), 0.0);
    for (int j = 0; j < c.n; ++j)
      for (int i = 0; i < c.n; ++i) {
        double sv = 0, sw = 0, st = 0;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int fi = 2 * i + di, fj = 2 * j + dj;
            if (fi < 0 || fj < 0 || fi >= f.n || fj >= f.n) continue;
            const double t = (di == 0 ? 1.0 : 0.5) * (dj == 0 ? 1.0 : 0.5);
            const std::size_t k = static_cast<std::size_t>(fj) * f.n + fi;
            sv += t * f.w[k] * f.v[k];
            sw += t * f.w[k];
            st += t;
          }
        const std::size_t k = static_cast<std::size_t>(j) * c.n + i;
        c.v[k] = sw > 0 ? sv / sw : 0.0;
        c.w[k] =
            std::min(1.0, sw / st * 4.0);  // a node with a quarter of its tent valid counts fully
      }
    levels.push_back(std::move(c));
  }
  {  // the top (2 × 2): the mean of what is there
    Level& t = levels.back();
    double sv = 0, sw = 0;
    for (std::size_t k = 0; k < t.v.size(); ++k) {
      sv += t.w[k] * t.v[k];
      sw += t.w[k];
    }
    if (sw <= 0) return false;
    for (std::size_t k = 0; k < t.v.size(); ++k) {
      t.v[k] = t.w[k] * t.v[k] + (1 - t.w[k]) * (sv / sw);
      t.w[k] = 1;
    }
  }
  for (std::size_t l = levels.size() - 1; l-- > 0;) {
    Level& f = levels[l];
    const Level& c = levels[l + 1];
    for (int j = 0; j < f.n; ++j)
      for (int i = 0; i < f.n; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * f.n + i;
        if (f.w[k] >= 1) continue;
        const int ci = i / 2, cj = j / 2, ci1 = std::min(ci + (i & 1), c.n - 1),
                  cj1 = std::min(cj + (j & 1), c.n - 1);
        const auto at = [&](int a, int b) { return c.v[static_cast<std::size_t>(b) * c.n + a]; };
        const double up = 0.25 * (at(ci, cj) + at(ci1, cj) + at(ci, cj1) + at(ci1, cj1));
        f.v[k] = f.w[k] * f.v[k] + (1 - f.w[k]) * up;
      }
  }
  for (std::size_t k = 0; k < z.size(); ++k)
    if (!valid[k]) z[k] = levels[0].v[k];
  return true;
}

int terrainGridsCommand(const std::string& tinPath, const std::string& storePath,
                        const std::string& spacing, const std::string& maxCellsText,
                        const std::string& outPath, const std::string& fillMode) {
  if (fillMode != "pullpush" && fillMode != "nearest") fail("FILL is pullpush or nearest");
  const auto t0 = std::chrono::steady_clock::now();
  const TinData projectTin = ingest::readTinFile(tinPath);
  const tiles::GeographicTin g = geographicTinOf(projectTin);
  const TinData& tin = g.tin;
  const TinIndex index(tin);
  const TinBoundary boundary(tin);
  const Rect extent = boundsOf(tin.vertices);
  const double resolution = std::stod(spacing);
  // "MAX" or "MIN:MAX" cells a side.
  const auto colon = maxCellsText.find(':');
  const int minCells = colon == std::string::npos ? 1 : std::stoi(maxCellsText.substr(0, colon));
  const int maxCells =
      std::stoi(colon == std::string::npos ? maxCellsText : maxCellsText.substr(colon + 1));
  const auto power = [](int c) { return c >= 1 && (c & (c - 1)) == 0; };
  if (!(resolution > 0) || !power(minCells) || !power(maxCells) || minCells > maxCells)
    fail("SPACING > 0 and [MINCELLS:]MAXCELLS powers of two");
  const auto s = store::openStoreForReading(storePath);
  std::ofstream out(outPath, std::ios::binary);
  if (!out) fail("cannot write " + outPath);
  std::size_t nodes = 0, outside = 0, tiles = 0;
  std::map<int, int> levelCells;
  for (const TileId& id : terrainTiles(*s)) {
    const tiles::GeoRect geo = tiles::geographicTileBounds(id);
    const Rect b{geo.west * kMetresPerDegree, geo.south * kMetresPerDegree,
                 geo.east * kMetresPerDegree, geo.north * kMetresPerDegree};
    int cells = minCells;
    while (b.width() / cells > resolution && cells < maxCells) cells *= 2;
    levelCells[id.z] = std::max(levelCells[id.z], cells);
    const int n = cells + 1;
    const double step = b.width() / cells;
    std::vector<double> z(static_cast<std::size_t>(n) * n, 0.0);
    std::vector<std::uint8_t> inside(z.size(), 0);
    auto nodeAt = [&](int i, int j) {
      return Point2{i == cells ? b.x1 : b.x0 + i * step, j == cells ? b.y1 : b.y0 + j * step};
    };
    if (b.overlaps(extent)) {
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const std::size_t k = static_cast<std::size_t>(j) * n + i;
          if (const auto h = index.z(nodeAt(i, j))) {
            z[k] = *h;
            inside[k] = 1;
          }
        }
      }
      // Outside: pull-push, or (nearest, or no node inside) the TIN's z at the
      // nearest boundary point, candidates per block of nodes (a coarse tile
      // is mostly outside).
      // With pull-push, the nodes within two of an inside node still take the
      // nearest boundary point's z (so the triangles across the TIN's edge
      // follow it), and pull-push fills the rest from those and the inside.
      const bool pullPush =
          fillMode == "pullpush" && std::find(inside.begin(), inside.end(), 1) != inside.end();
      std::vector<std::uint8_t> want(z.size(), 0);  // outside nodes to give the nearest z
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const std::size_t k = static_cast<std::size_t>(j) * n + i;
          if (inside[k]) continue;
          bool near = !pullPush;
          for (int dj = -2; dj <= 2 && !near; ++dj)
            for (int di = -2; di <= 2 && !near; ++di) {
              const int a = i + di, c = j + dj;
              near =
                  a >= 0 && c >= 0 && a < n && c < n && inside[static_cast<std::size_t>(c) * n + a];
            }
          want[k] = near;
        }
      constexpr int kBlock = 32;
      for (int bj = 0; bj < n; bj += kBlock) {
        for (int bi = 0; bi < n; bi += kBlock) {
          const int ei = std::min(n, bi + kBlock) - 1, ej = std::min(n, bj + kBlock) - 1;
          bool any = false;
          for (int j = bj; j <= ej && !any; ++j)
            for (int i = bi; i <= ei && !any; ++i) any = want[static_cast<std::size_t>(j) * n + i];
          if (!any) continue;
          const Point2 lo = nodeAt(bi, bj), hi = nodeAt(ei, ej);
          const std::vector<std::uint32_t> near = boundary.candidates(Rect{lo.x, lo.y, hi.x, hi.y});
          for (int j = bj; j <= ej; ++j)
            for (int i = bi; i <= ei; ++i) {
              const std::size_t k = static_cast<std::size_t>(j) * n + i;
              if (want[k]) z[k] = boundary.nearestZ(nodeAt(i, j), near);
            }
        }
      }
      if (pullPush) {
        for (std::size_t k = 0; k < z.size(); ++k) want[k] |= inside[k];
        pullPushFill(z, want, n);
      }
    }
    put(out, id.z);
    put(out, static_cast<std::int32_t>(id.x));
    put(out, static_cast<std::int32_t>(id.y));
    put(out, static_cast<std::int32_t>(n));
    for (double v : {geo.west, geo.south, geo.east, geo.north}) put(out, v);
    out.write(reinterpret_cast<const char*>(z.data()), static_cast<std::streamsize>(z.size() * 8));
    out.write(reinterpret_cast<const char*>(inside.data()),
              static_cast<std::streamsize>(inside.size()));
    nodes += z.size();
    outside += z.size() - static_cast<std::size_t>(std::count(inside.begin(), inside.end(), 1));
    ++tiles;
  }
  if (!out.flush()) fail("cannot write " + outPath);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string grid;
  for (const auto& [z, c] : levelCells)
    grid += (grid.empty() ? "" : ",") + ("\"" + std::to_string(z) + "\":" + std::to_string(c + 1));
  std::printf("{\"tiles\":%zu,\"nodes\":%zu,\"outside\":%zu,\"seconds\":%.3f,\"grid\":{%s}}\n",
              tiles, nodes, outside, seconds, grid.c_str());
  return 0;
}

struct TerrainTileError {
  TileId id;
  std::size_t triangles = 0, measured = 0, fill = 0;
  std::size_t collapsed = 0;  // surface triangles quantization left with no area or flipped
  SurfaceDifference worst;
  double atVertex = 0;
  Point2 vertex;
  double fillOverTin = 0;  // the fill's largest difference over the TIN
  Point2 fillAt;
  // TIN vertices off the TIN's boundary inside a fill triangle and in no
  // surface triangle (the fill reaching into the TIN), and one of them.
  std::size_t underFill = 0;
  Point2 underFillAt;  // the one farthest from the TIN's boundary
  double underFillDepth = 0;  // its distance from the boundary (working frame, m)
};

TerrainTileError measureTerrainTile(const TileId& id, const std::string& bytes,
                                    const TinIndex& index,
                                    const std::vector<std::uint8_t>& onTinBoundary,
                                    const TinBoundary& tinBoundary) {
  const DecodedTerrain d = decodeTerrain(bytes, id.name());
  const tiles::GeoRect g = tiles::geographicTileBounds(id);
  std::vector<Point3> p(d.u.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double lon = g.west + (g.east - g.west) * (d.u[i] / 32767.0);
    const double lat = g.south + (g.north - g.south) * (d.v[i] / 32767.0);
    const double h = d.minHeight + (d.maxHeight - d.minHeight) * (d.h[i] / 32767.0);
    p[i] = {lon * kMetresPerDegree, lat * kMetresPerDegree, h};
  }
  TerrainTileError e;
  e.id = id;
  e.triangles = d.triangles.size();
  // Walls are vertical: no area in the plane; skip them (and any degenerate
  // triangle) before measuring.
  std::vector<std::array<std::uint32_t, 3>> surface, fill;
  for (const auto& t : d.triangles) {
    const Point3 &a = p[t[0]], &b = p[t[1]], &c = p[t[2]];
    const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    // (tinsmith's header says -1.4e-45, the float below 0, as the minimum
    // height of a tile with fill: its fill decodes to that, not to 0.)
    const bool isFill = std::abs(a.z) < 1e-6 || std::abs(b.z) < 1e-6 || std::abs(c.z) < 1e-6;
    if (isFill) ++e.fill;
    if (area <= 0) {  // walls; or a surface triangle collapsed or flipped by quantization
      if (!isFill) ++e.collapsed;
      continue;
    }
    (isFill ? fill : surface).push_back(t);
  }
  e.measured = surface.size();
  for (const SurfaceDifference& s : triangleDifferences(p, surface, index)) {
    if (s.maxAbs > e.worst.maxAbs) e.worst = s;
    if (s.vertexAbs > e.atVertex) {
      e.atVertex = s.vertexAbs;
      e.vertex = s.vertex;
    }
  }
  for (const SurfaceDifference& s : triangleDifferences(p, fill, index)) {
    if (s.maxAbs > e.fillOverTin) {
      e.fillOverTin = s.maxAbs;
      e.fillAt = s.at;
    }
  }
  // Which TIN vertices the surface covers (closed triangles) and which the
  // fill holds strictly inside.
  const auto& tv = index.tin().vertices;
  std::unordered_set<std::uint32_t> bySurface, byFill;
  std::vector<std::uint32_t> near;
  auto visit = [&](const std::vector<std::array<std::uint32_t, 3>>& tris, bool strict,
                   std::unordered_set<std::uint32_t>& out) {
    for (const auto& t : tris) {
      const Point3 &a = p[t[0]], &b = p[t[1]], &c = p[t[2]];
      near.clear();
      index.verticesIn(Rect{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}),
                            std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y})},
                       near);
      for (const std::uint32_t v : near) {
        const Point3& q = tv[v];
        const int o1 = geometry::orient2d(a.x, a.y, b.x, b.y, q.x, q.y);
        const int o2 = geometry::orient2d(b.x, b.y, c.x, c.y, q.x, q.y);
        const int o3 = geometry::orient2d(c.x, c.y, a.x, a.y, q.x, q.y);
        if (strict ? (o1 > 0 && o2 > 0 && o3 > 0) : (o1 >= 0 && o2 >= 0 && o3 >= 0)) out.insert(v);
      }
    }
  };
  visit(surface, false, bySurface);
  visit(fill, true, byFill);
  for (const std::uint32_t v : byFill) {
    if (bySurface.contains(v) || onTinBoundary[v]) continue;
    ++e.underFill;
    const double depth = tinBoundary.distance(tv[v].xy());
    if (depth > e.underFillDepth) {
      e.underFillDepth = depth;
      e.underFillAt = tv[v].xy();
    }
  }
  return e;
}

int terrainErrorCommand(const std::string& tinPath, const std::string& storePath, int threads,
                        const std::string& tilesPath) {
  const auto t0 = std::chrono::steady_clock::now();
  const TinData projectTin = ingest::readTinFile(tinPath);
  const tiles::GeographicTin g = geographicTinOf(projectTin);
  const TinIndex index(g.tin);
  std::vector<std::uint8_t> onBoundary(g.tin.vertices.size(), 0);
  const TinBoundary boundary(g.tin);
  for (const auto& e : boundary.edges()) onBoundary[e[0]] = onBoundary[e[1]] = 1;
  const auto s = store::openStoreForReading(storePath);
  const std::vector<TileId> ids = terrainTiles(*s);
  std::vector<TerrainTileError> errors(ids.size());
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failureLock;
  auto work = [&] {
    try {
      for (std::size_t i; (i = next++) < ids.size();)
        errors[i] = measureTerrainTile(ids[i], *s->get(terrainKey(ids[i])), index, onBoundary, boundary);
    } catch (...) {
      const std::lock_guard lock(failureLock);
      failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  auto degrees = [](Point2 q) { return Point2{q.x / kMetresPerDegree, q.y / kMetresPerDegree}; };
  if (!tilesPath.empty()) {
    std::FILE* f = std::fopen(tilesPath.c_str(), "w");
    if (!f) fail("cannot write " + tilesPath);
    for (const auto& e : errors) {
      const Point2 at = degrees(e.worst.at), fa = degrees(e.fillAt);
      std::fprintf(
          f,
          "{\"tile\":\"%s\",\"triangles\":%zu,\"measured\":%zu,\"fill\":%zu,\"collapsed\":%zu,"
          "\"maxError\":%.6f,\"at\":[%.9f,%.9f],\"meshZ\":%.4f,\"tinZ\":%.4f,"
          "\"maxAtDemPoints\":%.6f,\"fillOverTin\":%.6f,\"fillAt\":[%.9f,%.9f],"
          "\"underFill\":%zu,\"underFillAt\":[%.9f,%.9f],\"underFillDepth\":%.4f}\n",
          e.id.name().c_str(), e.triangles, e.measured, e.fill, e.collapsed, e.worst.maxAbs, at.x,
          at.y, e.worst.meshZ, e.worst.tinZ, e.atVertex, e.fillOverTin, fa.x, fa.y, e.underFill,
          degrees(e.underFillAt).x, degrees(e.underFillAt).y, e.underFillDepth);
    }
    std::fclose(f);
  }
  std::map<int, TerrainTileError> rows;  // the worst of each measure per level
  std::map<int, std::size_t> tileCount, triangleCount, fillCount, collapsedCount, underFillCount;
  std::map<int, double> underFillDepth;
  std::map<int, TileId> underFillWorst;
  std::map<int, TileId> fillWorst;
  for (const auto& e : errors) {
    TerrainTileError& r = rows[e.id.z];
    ++tileCount[e.id.z];
    triangleCount[e.id.z] += e.triangles;
    fillCount[e.id.z] += e.fill;
    collapsedCount[e.id.z] += e.collapsed;
    underFillCount[e.id.z] += e.underFill;
    if (e.underFillDepth > underFillDepth[e.id.z]) {
      underFillDepth[e.id.z] = e.underFillDepth;
      underFillWorst[e.id.z] = e.id;
    }
    if (e.worst.maxAbs >= r.worst.maxAbs) {
      r.worst = e.worst;
      r.id = e.id;
    }
    if (e.atVertex >= r.atVertex) {
      r.atVertex = e.atVertex;
      r.vertex = e.vertex;
    }
    if (e.fillOverTin >= r.fillOverTin) {
      r.fillOverTin = e.fillOverTin;
      r.fillAt = e.fillAt;
      fillWorst[e.id.z] = e.id;
    }
  }
  for (const auto& [z, r] : rows) {
    const Point2 at = degrees(r.worst.at), fa = degrees(r.fillAt);
    std::printf(
        "{\"level\":%d,\"tiles\":%zu,\"triangles\":%zu,\"fillTriangles\":%zu,\"collapsed\":%zu,"
        "\"maxError\":%.6f,"
        "\"worst\":\"%s\",\"at\":[%.9f,%.9f],\"meshZ\":%.4f,\"tinZ\":%.4f,\"maxAtDemPoints\":%.6f,"
        "\"fillOverTin\":%.6f,\"fillWorst\":\"%s\",\"fillAt\":[%.9f,%.9f],\"underFill\":%zu,"
        "\"underFillDepth\":%.4f,\"underFillWorst\":\"%s\",\"cesiumError\":%.6f}\n",
        z, tileCount[z], triangleCount[z], fillCount[z], collapsedCount[z], r.worst.maxAbs,
        r.id.name().c_str(), at.x, at.y, r.worst.meshZ, r.worst.tinZ, r.atVertex, r.fillOverTin,
        fillWorst[z].name().c_str(), fa.x, fa.y, underFillCount[z], underFillDepth[z],
        underFillWorst[z].name().c_str(), tiles::cesiumLevelMaximumGeometricError(z));
  }
  std::printf("{\"seconds\":%.3f}\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> a(argv + 1, argv + argc);
    if (a.size() == 2 && a[0] == "store") return storeCommand(a[1]);
    if (a.size() == 6 && a[0] == "grids") return gridsCommand(a[1], a[2], a[3], a[4], a[5]);
    if ((a.size() == 3 || a.size() == 4) && a[0] == "error")
      return errorCommand(a[1], a[2], a.size() == 4 ? std::stoi(a[3]) : 1);
    if (a.size() == 2 && a[0] == "terrain-store") return terrainStoreCommand(a[1]);
    if ((a.size() == 6 || a.size() == 7) && a[0] == "terrain-grids")
      return terrainGridsCommand(a[1], a[2], a[3], a[4], a[5], a.size() == 7 ? a[6] : "pullpush");
    if (a.size() >= 3 && a.size() <= 5 && a[0] == "terrain-error")
      return terrainErrorCommand(a[1], a[2], a.size() >= 4 ? std::stoi(a[3]) : 1,
                                 a.size() == 5 ? a[4] : "");
  } catch (const std::exception& e) {
    fail(e.what());
  }
  std::fprintf(
      stderr,
      "usage: tile_error_bench store SITE.3dtiles\n"
      "       tile_error_bench grids SITE.tin SITE.3dtiles SPACING|n=NODES Z:TOL,... OUT.grids\n"
      "       tile_error_bench error SITE.tin MESHES.bin [THREADS]\n"
      "       tile_error_bench terrain-store STORE\n"
      "       tile_error_bench terrain-grids SITE.tin STORE SPACING MAXCELLS OUT.grids "
      "[pullpush|nearest]\n"
      "       tile_error_bench terrain-error SITE.tin STORE [THREADS [TILES.jsonl]]\n");
  return 2;
}
