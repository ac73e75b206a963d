#include "ingest/tiles/tiling_plan.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/base/error.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/base/le_bytes.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {

namespace {

constexpr std::string_view kMagic{"\x89TSPLAN\n", 8};

/// A reader whose failures say the plan is not one tinsmith reads.
LeReader planReader(std::string_view bytes, const std::string& name) {
  return LeReader(bytes, [&name](const std::string& why) {
    throw inputError("not a tiling plan tinsmith can read: " + why, fileLocation(name),
                     "plan the job again (tinsmith slurm in a new --workdir)");
  });
}

}  // namespace

TilingPlan makeTilingPlan(const TinData& tin, const tiles::TilerOptions& options, int cornerZoom) {
  const TinIdentity identity{crc32(encodeTin(tin)), tin.vertices.size(), tin.triangles.size()};
  return makeTilingPlan(tiles::Tiler(tin, options), options, cornerZoom, identity);
}

TilingPlan makeTilingPlan(const tiles::Tiler& tiler, const tiles::TilerOptions& options,
                          int cornerZoom, const TinIdentity& tin) {
  TilingPlan plan;
  plan.tin = tin;
  plan.options.tolerance = options.tolerance;
  plan.options.maxTriangles = options.maxTriangles;
  plan.options.maxZoom = options.maxZoom;
  plan.options.lambdaFactor = options.lambdaFactor;
  plan.tiler = tiler.plan(cornerZoom);
  return plan;
}

std::string encodeTilingPlan(const TilingPlan& plan) {
  LeWriter w;
  w.bytes.append(kMagic);
  w.put(kTilingPlanVersion);
  w.put(plan.tin.crc32);
  w.put(plan.tin.vertices);
  w.put(plan.tin.triangles);
  const tiles::TilerOptions& o = plan.options;
  w.put(o.tolerance);
  w.put(static_cast<std::uint64_t>(o.maxTriangles));
  w.put(static_cast<std::int32_t>(o.maxZoom.value_or(-1)));
  w.put(o.lambdaFactor);
  const tiles::TilerPlan& t = plan.tiler;
  w.put(t.geometry.origin().x);
  w.put(t.geometry.origin().y);
  w.put(t.geometry.size());
  for (const double v : {t.extent.x0, t.extent.y0, t.extent.x1, t.extent.y1}) w.put(v);
  w.put(static_cast<std::int32_t>(t.finestZoom));
  w.put(t.fitSpacing);
  w.put(static_cast<std::uint8_t>(t.tileFitAllData));
  w.put(static_cast<std::int32_t>(t.mosaicZoom));
  w.put(static_cast<std::uint32_t>(t.zoomLines.size()));
  for (const auto& lines : t.zoomLines) {
    w.put(static_cast<std::uint64_t>(lines.size()));
    for (const auto& line : lines) {
      w.put(static_cast<std::uint8_t>(line.kind));
      w.put(static_cast<std::uint8_t>(line.ring));
      w.put(static_cast<std::uint8_t>(line.closed));
      w.put(static_cast<std::uint64_t>(line.points.size()));
      for (const auto& p : line.points) {
        w.put(p.x);
        w.put(p.y);
        w.put(p.z);
      }
    }
  }
  w.put(static_cast<std::int32_t>(t.cornerZoom));
  w.put(static_cast<std::uint64_t>(t.offTinCorners.size()));
  for (const auto& c : t.offTinCorners) {
    w.put(static_cast<std::uint8_t>(c.zoom));
    w.put(c.row);
    w.put(c.column);
    w.put(c.z);
  }
  w.put(crc32(w.bytes));
  return std::move(w.bytes);
}

TilingPlan decodeTilingPlan(std::string_view bytes, const std::string& name) {
  LeReader r = planReader(bytes, name);
  if (bytes.substr(0, kMagic.size()) != kMagic) r.fail("wrong magic bytes");
  if (bytes.size() < kMagic.size() + 8) r.fail("it ends early");
  const std::string_view body = bytes.substr(0, bytes.size() - 4);
  LeReader tail = planReader(bytes.substr(bytes.size() - 4), name);
  if (tail.get<std::uint32_t>() != crc32(body)) r.fail("the checksum does not match");
  (void)r.take(kMagic.size());  // checked above
  if (const auto version = r.get<std::uint32_t>(); version != kTilingPlanVersion)
    r.fail("format version " + std::to_string(version) + ", this tinsmith reads " +
           std::to_string(kTilingPlanVersion));
  TilingPlan plan;
  plan.tin.crc32 = r.get<std::uint32_t>();
  plan.tin.vertices = r.get<std::uint64_t>();
  plan.tin.triangles = r.get<std::uint64_t>();
  tiles::TilerOptions& o = plan.options;
  o.tolerance = r.get<double>();
  o.maxTriangles = r.get<std::uint64_t>();
  if (const auto z = r.get<std::int32_t>(); z >= 0) o.maxZoom = z;
  o.lambdaFactor = r.get<double>();
  tiles::TilerPlan& t = plan.tiler;
  const double x = r.get<double>(), y = r.get<double>(), size = r.get<double>();
  t.geometry = tiles::PyramidGeometry({x, y}, size);
  for (double* v : {&t.extent.x0, &t.extent.y0, &t.extent.x1, &t.extent.y1}) *v = r.get<double>();
  if (!(t.extent.x0 <= t.extent.x1 && t.extent.y0 <= t.extent.y1) || !std::isfinite(t.extent.x0) ||
      !std::isfinite(t.extent.x1) || !std::isfinite(t.extent.y0) || !std::isfinite(t.extent.y1))
    r.fail("the TIN's box is empty or not finite");
  t.finestZoom = r.get<std::int32_t>();
  t.fitSpacing = r.get<double>();
  t.tileFitAllData = r.get<std::uint8_t>() != 0;
  t.mosaicZoom = r.get<std::int32_t>();
  const auto zooms = r.get<std::uint32_t>();
  if (t.finestZoom < 0 || t.finestZoom > 30 ||
      zooms != static_cast<std::uint32_t>(t.finestZoom) + 1)
    r.fail("the finest zoom and the zooms of lines do not agree");
  if (t.mosaicZoom < 0 || t.mosaicZoom > t.finestZoom)
    r.fail("the mosaic zoom " + std::to_string(t.mosaicZoom) + " is not one of the planned zooms");
  t.zoomLines.resize(zooms);
  for (auto& lines : t.zoomLines) {
    lines.resize(r.count(11));
    for (auto& line : lines) {
      const auto kind = r.get<std::uint8_t>();
      if (kind > static_cast<std::uint8_t>(FeatureKind::BreakLine))
        r.fail("a line of unknown kind");
      line.kind = static_cast<FeatureKind>(kind);
      line.ring = r.get<std::uint8_t>() != 0;
      line.closed = r.get<std::uint8_t>() != 0;
      line.points.resize(r.count(24));
      for (auto& p : line.points) {
        p.x = r.get<double>();
        p.y = r.get<double>();
        p.z = r.get<double>();
      }
    }
  }
  t.cornerZoom = r.get<std::int32_t>();
  if (t.cornerZoom < -1 || t.cornerZoom > tiles::kMaxCornerZoom)
    r.fail("corners off the TIN to zoom " + std::to_string(t.cornerZoom));
  t.offTinCorners.resize(r.count(17));
  for (auto& c : t.offTinCorners) {
    c.zoom = r.get<std::uint8_t>();
    c.row = r.get<std::uint32_t>();
    c.column = r.get<std::uint32_t>();
    c.z = r.get<double>();
    const auto lines = (std::uint64_t{1} << std::min(c.zoom, 31)) + 1;
    if (c.zoom > t.cornerZoom || c.row >= lines || c.column >= lines)
      r.fail("a corner off the TIN outside the planned zooms");
  }
  for (std::size_t k = 1; k < t.offTinCorners.size(); ++k)
    if (!(t.offTinCorners[k - 1].key() < t.offTinCorners[k].key()))
      r.fail("the corners off the TIN are not in order");
  if (r.at() != body.size()) r.fail("bytes left over");
  return plan;
}

void writeTilingPlan(const std::filesystem::path& path, const TilingPlan& plan) {
  AtomicFile file(path);
  file.write(encodeTilingPlan(plan));
  file.commit();
}

TilingPlan readTilingPlan(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw inputError(
        "cannot read the tiling plan", fileLocation(path.string()),
        "give the tiler.plan in the job's --workdir (task 0 of tinsmith slurm's shard.sh "
        "writes it: the subtrees run after it)");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return decodeTilingPlan(bytes.str(), path.string());
}

void requirePlannedOptions(const TilingPlan& plan, const tiles::TilerOptions& options,
                           const std::string& planName) {
  const tiles::TilerOptions& p = plan.options;
  auto differs = [&](const std::string& what, const std::string& planned,
                     const std::string& given) {
    throw usageError(
        "the plan " + planName + " was made with " + what + " " + planned + ", not " + given,
        "give the options of the job's plan.json (tileArguments), or plan again");
  };
  if (p.tolerance != options.tolerance)
    differs("tolerance", std::to_string(p.tolerance), std::to_string(options.tolerance));
  if (p.maxTriangles != options.maxTriangles)
    differs("max triangles", std::to_string(p.maxTriangles), std::to_string(options.maxTriangles));
  if (p.maxZoom != options.maxZoom)
    differs("max zoom", p.maxZoom ? std::to_string(*p.maxZoom) : "none",
            options.maxZoom ? std::to_string(*options.maxZoom) : "none");
  if (p.lambdaFactor != options.lambdaFactor)
    differs("lambda", std::to_string(p.lambdaFactor), std::to_string(options.lambdaFactor));
}

}  // namespace tinsmith::ingest
