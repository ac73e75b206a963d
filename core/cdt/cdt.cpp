// The Cdt facade (see cdt.hpp): input goes to the working triangulation
// (cdt::ConstrainedTriangulation, constraints.hpp), finalize() inserts it,
// the first reader packs it into the output Mesh, classified by the domain.
// The rooms behind it:
//   triangle_store.*        the data structure: arrays, flips, splits,
//                           legalization, compaction into a Mesh
//   point_insertion.*       input vertices, insertion order, location, merges
//   two_halves.cpp          the two-halves parallel build of a first bulk
//   constraints.hpp,
//   constraint_insertion.cpp  input segments walked into the triangulation
//   crossing_resolution.cpp   where a segment meets a constraint (named steps)
//   domain.*                which triangles are inside (boundary, holes)
//   validator.cpp           Cdt::validate
//   edge_feature_map.hpp    constrained edges' features
// (spatial sorts: core/geometry/spatial_sort.hpp; threads: core/base/parallel.hpp)
#include "core/cdt/cdt.hpp"

#include <algorithm>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "core/base/error.hpp"
#include "core/cdt/cdt_impl.hpp"
#include "core/cdt/cdt_test_access.hpp"

namespace tinsmith {

using cdt::kDomainFeature;
using cdt::Role;

Cdt::Cdt(CdtOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
Cdt::~Cdt() = default;
Cdt::Cdt(Cdt&&) noexcept = default;
Cdt& Cdt::operator=(Cdt&&) noexcept = default;

FeatureId Cdt::addFeature(FeatureKind kind, std::string source) {
  impl_->features.push_back({kind, std::move(source)});
  impl_->domain.featureRole.push_back(Role::None);
  return static_cast<FeatureId>(impl_->features.size() - 1);
}

const std::vector<TinFeature>& Cdt::features() const {
  return impl_->features;
}
VertexId Cdt::insertPoint(const Point3& p, FeatureId feature) {
  return insertPoints(std::span<const Point3>(&p, 1), feature);
}

VertexId Cdt::insertPoints(std::span<const Point3> points, FeatureId feature) {
  const VertexId first = impl_->appendPoints(points, feature);
  if (!points.empty()) impl_->inputAdded();
  return first;
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
  m.segments.push_back({a, b, feature});
  m.inputAdded();
}

void Cdt::addBoundary(std::span<const Point3> ring, FeatureId feature) {
  if (feature == kNoFeature || feature >= impl_->features.size()) {
    throw usageError("addBoundary needs a registered feature");
  }
  insertConstraint(ring, feature, true);  // all or nothing: may throw
  impl_->domain.featureRole[feature] = Role::Boundary;
  impl_->domain.hasBoundary = true;
  impl_->inputAdded();
}

void Cdt::addHole(std::span<const Point3> ring, FeatureId feature) {
  if (feature == kNoFeature || feature >= impl_->features.size()) {
    throw usageError("addHole needs a registered feature");
  }
  insertConstraint(ring, feature, true);  // all or nothing: may throw
  impl_->domain.featureRole[feature] = Role::Hole;
  impl_->domain.hasHole = true;
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
    m.unpackMesh();
  }
  m.insertPendingPoints();
  m.insertPendingSegments();
  if (m.options.canonicalTies) m.settleTies();
  // Vertex half-edges serve constraint insertion only: recomputed when more
  // constraints come.
  m.trackVhe = false;
  std::vector<HalfedgeId>().swap(m.vhe);
  m.finalized = true;
  m.changed = false;
  m.meshBuilt = false;
}

void Cdt::Impl::unpackMesh() {
  if (!packed) return;
  MeshStorage storage = std::move(mesh).release();
  // Mesh vertex → working vertex (live roots only have mesh vertices).
  std::vector<VertexId> workingVertex(storage.points.size());
  for (std::uint32_t k = 0; k < rep.size(); ++k) {
    const VertexId v(k);
    if (rep[v] == v && meshOf[v].valid()) workingVertex[meshOf[v].value] = v;
  }
  std::vector<std::uint32_t> corners = std::move(storage.corners);
  std::vector<std::uint32_t> twins = std::move(storage.twins);
  storage = MeshStorage();
  meshBuilt = false;
  unpack(std::move(corners), std::move(twins), workingVertex);
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
  cdt::IdVector<VertexId, VertexId> used;
  MeshStorage storage = m.pack(m.domain.classify(m), m.z, m.features.size(), m.threadCount(), used);
  storage.crs = m.options.crs;
  storage.features = m.features;
  m.mesh = Mesh::adopt(std::move(storage));

  m.report.dropped.erase(std::remove_if(m.report.dropped.begin(), m.report.dropped.end(),
                                        [](const CdtReport::Dropped& d) {
                                          return d.what ==
                                                 CdtReport::Dropped::What::PointOutsideDomain;
                                        }),
                         m.report.dropped.end());
  // used becomes meshOf: roots keep their entry, merged vertices take their root's.
  for (std::uint32_t k = 0; k < m.xy.size(); ++k) {
    const VertexId v(k), r = m.find(v);
    if (r != v) used[v] = used[r];
    if (r == v && !used[v].valid()) {
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

TinData Cdt::toTinData() const {
  return mesh().toTinData();
}

VertexId Cdt::meshVertex(VertexId input) const {
  if (!impl_->finalized) return {};
  buildMesh();
  if (input.value >= impl_->meshOf.size()) return {};
  return impl_->meshOf[input];
}

std::size_t Cdt::inputVertexCount() const {
  return impl_->xy.size();
}

const CdtReport& Cdt::report() const {
  if (impl_->finalized) buildMesh();  // completes the dropped-point list
  return impl_->report;
}

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

std::size_t CdtTestAccess::crossingsPlacedBy(const Cdt& cdt, cdt::CrossingStep step) {
  return cdt.impl_->crossingSteps[static_cast<std::size_t>(step)];
}

ValidationReport CdtTestAccess::validate(const Cdt& cdt, std::size_t& chainSteps,
                                         const ValidationOptions& options) {
  chainSteps = 0;
  return cdt.validateCounting(options, chainSteps);
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
    // (The loaded mesh's vertex ids are the input vertex ids.)
    cdt.impl_->segments.push_back({mesh.origin(h), mesh.target(h), kDomainFeature});
    any = true;
  }
  // Every TIN gets them, a convex one too (its hull): by parity, triangles
  // outside its outer loop or inside a loop around a hole stay outside, and
  // so do points added later beyond its edge.
  cdt.impl_->domain.hasBoundary = any;
  return cdt;
}

}  // namespace tinsmith
