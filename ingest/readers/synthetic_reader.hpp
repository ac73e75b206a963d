// readers.synthetic: layers generated from a one-line description instead of
// read from a file (as PDAL's readers.faux), so tests, benchmarks and demos
// need no data files. A spec is written wherever a file path goes — a
// [[layer]]'s `path`, `tinsmith tin --points / --breaklines`, `tinsmith fit`:
//
//   synthetic:PATTERN?KEY=VALUE&KEY=VALUE…       (keys in any order, each once)
//
// Patterns, what they make, and the layer kinds that take them:
//   grid    nx × ny points `spacing` apart from (x0, y0), row by row      points, dem
//           (id = row·nx + col). Exact by default: the four corners of every
//           grid square are cocircular (the Delaunay tie); jitter=F moves
//           each point by up to F·spacing in x and y. ny=1: one collinear run.
//   random  n points uniform in the extent (id = index)                   points, dem
//   raster  an nx × ny height raster of `spacing` cells, north-up, its
//           lower-left corner at (x0, y0), read as a dem is: points at cell
//           centres, id = row·nx + col with row 0 at the top; nodata=F
//           leaves out about that fraction of cells (seeded)              points, dem
//   lines   n polylines of `vertices` vertices across the extent        contours, road,
//           (layout=hatch: horizontal, at y0 + k·height/(n+1) —          river
//           on grid rows when the numbers agree, i.e. collinear runs;
//           cross: n horizontal and n vertical, n² crossings; star: n lines
//           through the centre, all crossing in one point; random: seeded)
//   rings   n concentric closed rings (`vertices` each) round the extent's  contours, road,
//           centre, ring k = 1 (innermost) … n at z0 + (n + 1 − k)·interval:  river, lake,
//           a cone's contours                                            boundary, hole
//
// Keys (defaults in brackets; a key a pattern does not use is an error):
//   x0, y0 [0, 0]      lower-left corner; x0=500000&y0=4500000 puts the data at
//                      UTM-sized coordinates, where mm detail must survive
//   width, height [100, 100]  the extent of random, lines and rings (grid and
//                      raster: (nx − 1)·spacing resp. nx·spacing)
//   nx, ny [11, 11], spacing [10]   grid and raster;  n: point / line / ring count
//   surface [plane]    z of points and line vertices, over u, v ∈ [0, 1] across
//                      the extent: flat (z0), plane (z0 + scale·(u + v)/2),
//                      franke (z0 + scale·Franke(u, v)), hill (a Gaussian bump),
//                      cone (z0 + scale·max(0, 1 − 2r), r from the centre)
//   z0 [0], scale [100]  base height and relief, metres
//   noise [0]          adds a uniform z error in [−noise, noise] (seeded)
//   z [surface]        lines: z=none makes 2D lines (draped by the builder)
//   interval [10]      rings: the contour interval
//   duplicates [0]     point patterns: this many extra exact copies of points
//                      chosen by the seed (ids repeat the original's)
//   seed [1]           every random choice; the same spec gives the same bytes
//
// The layer's CRS is its `crs` key; in a config without one the layer is in
// the project CRS. `z_value` sets every z, as for files.
// Every problem is a tinsmith::Error (Input) whose location is the spec and
// whose message names the key: unknown pattern or key, a repeated key, a value
// that is not a number or out of range, a pattern the layer kind cannot take.
#pragma once

#include <string_view>

#include "ingest/base/height_grid.hpp"
#include "ingest/readers/ingested_layer.hpp"

namespace tinsmith::ingest {

/// True when `path` is a synthetic spec ("synthetic:…"), not a file.
bool isSyntheticSpec(std::string_view path);

/// Parses `spec` and checks that a layer of `kind` can take its pattern;
/// throws as described above. The config calls it so a bad spec fails at
/// load, naming the config line.
void checkSyntheticSpec(std::string_view spec, LayerKind kind);

/// readers.synthetic — the layer `config.path` (a spec) describes.
IngestedLayer readSyntheticLayer(const LayerConfig& config);

/// The height raster of a `raster` spec (nodata cells NaN), for tests of
/// raster code. Throws as above, also for another pattern.
HeightGrid syntheticHeightGrid(std::string_view spec);

}  // namespace tinsmith::ingest
