// Elevation profiles of break lines (rivers, roads, lake shores) before they
// become constraints: draping 2D lines on a surface, making rivers descend
// downstream, smoothing roads. Pure functions on polylines; the surface is a
// callback so these need no triangulation and are tested on their own.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith::ingest {

/// z of the surface at (x, y), or nullopt outside it. Units: metres.
using ZLookup = std::function<std::optional<double>(double x, double y)>;

struct DrapeResult {
  std::size_t draped = 0;   ///< vertices that got z from the surface
  std::size_t outside = 0;  ///< vertices outside it, z interpolated along the line
};

/// Inserts vertices so that no segment is longer than `maxSpacing` (metres,
/// in x, y); z is interpolated linearly. maxSpacing <= 0 does nothing.
void densify(std::vector<Point3>& line, double maxSpacing);

/// Sets every vertex's z from `surface`. Vertices outside the surface take z
/// interpolated along the line (by length) from the nearest draped vertices on
/// either side (the nearest one beyond the last). Throws geometryError naming
/// `what` when no vertex of the line lies on the surface.
DrapeResult drape(std::vector<Point3>& line, const ZLookup& surface, const std::string& what);

struct DescentResult {
  bool reversed = false;       ///< flow runs against the digitised order
  std::size_t adjusted = 0;    ///< vertices whose z changed
  double maxAdjustment = 0.0;  ///< largest |Δz|, metres
  /// The vertex of the largest change: where, its z before and after.
  Point2 maxAt;
  double maxFrom = 0.0, maxTo = 0.0;
};

/// Makes z non-increasing downstream, in place, without changing x, y or the
/// vertex order. Downstream is the digitised order unless the end elevations
/// disagree (last z above first z), in which case the river is taken to be
/// digitised upstream and descends from its last vertex to its first.
/// The new profile is the monotone one closest to the old in the
/// length-weighted least-squares sense (isotonic regression by pool-adjacent-
/// violators): dams are lowered and pits raised by the least total amount,
/// rather than carving everything down to the lowest point.
DescentResult enforceDescent(std::vector<Point3>& line);

/// Rivers that meet end to end (a confluence: inflows end where an outflow
/// starts, all at one x, y) each descend on their own after enforceDescent,
/// but the shared point is one vertex in the TIN, where the first river's z
/// wins: an outflow whose own start was higher then rises from it. This
/// lowers, at every x, y where river ends meet, every end there to the
/// lowest of them, and carves each river's vertices downstream of a lowered
/// start down to it (z[k] = min(z[k], z[k − 1]) in flow order), until nothing
/// changes (only lowering, so it ends). `rivers` are descending in their
/// digitised order when `reversed[i]` is false, else from last to first.
/// Returns the number of vertices lowered.
std::size_t reconcileConfluences(std::vector<std::vector<Point3>*> rivers,
                                 const std::vector<bool>& reversed);

/// True when z never increases in the direction of flow (as enforceDescent
/// decides it), within `tolerance` metres.
bool descends(const std::vector<Point3>& line, double tolerance = 0.0);

struct SmoothResult {
  std::size_t spikesRemoved = 0;  ///< vertices replaced by the median of their neighbours
  double maxChange = 0.0;         ///< largest |Δz| overall, metres
};

/// Removes spikes and smooths z along the line's length (roads): first every
/// interior vertex whose z sticks out of both neighbours by more than
/// `spikeThreshold` metres takes their median; then z becomes a
/// triangular-kernel average over ±window/2 metres of length. End vertices
/// keep their z so roads still meet what they connect to. window <= 0 skips
/// the smoothing.
SmoothResult smoothAlongLength(std::vector<Point3>& line, double window, double spikeThreshold);

}  // namespace tinsmith::ingest
