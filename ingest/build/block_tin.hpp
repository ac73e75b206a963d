// A TIN for more points than memory holds, built block by block (`tinsmith
// tin --block-points`): the Delaunay triangulation of the points without the
// triangles whose circumcircle's radius is more than `maxCircumradius` R —
// the same triangles whatever the blocks, as one machine's triangulation of
// all the points gives them (filtered alike, cocircular ties broken alike).
//
// Why blocks can decide it: the points are cut into squares (blocks). A
// block triangulates its own points and every point within 2R of its square
// (CdtOptions::canonicalTies, so the mesh is a function of the points alone)
// and keeps the triangles of radius ≤ R whose least corner by (x, y) is its
// own. Such a triangle's circle passes through that corner, so it lies within
// 2R of the square: every point that could be inside it was triangulated, and
// the triangle is Delaunay among all the points exactly when it is among the
// block's. Conversely a Delaunay triangle of radius ≤ R has its corners within
// 2R of its least one, so the block of that corner has it. Each triangle is
// kept once, by its least corner's block. What is left out is what no block
// can vouch for without holding everything: the hull's slivers (what
// --trim-hull cuts) and triangles across gaps in the data wider than 2R.
//
// Three stages, each holding at most one block and its surroundings (plus
// buffers of a few MB), in a folder:
//   1 prepare      the sources spooled chunk by chunk into one binary file,
//                  with their box; each point into its block's file
//                  (points/block-B.bin; squares of side B chosen so that a
//                  block holds about `blockPoints` on average); each block's
//                  exact (x, y) duplicates dropped, the first one's z kept;
//                  blocks.json says how (the grid, R, each block's first
//                  vertex, the blocks with points: stage 2's tasks)
//   2 triangulate  one task per block with points, in any order and process:
//                  its kept triangles as indices into what it read
//                  (triangles/TASK.tri, atomically)
//   3 assemble     the .tin (TinStreamWriter): the vertices block by block
//                  (rows of blocks from the south-west, each in the input's
//                  order), then each task's triangles
// buildTinByBlocks runs all three in one process, its folder next to the
// output and removed however it ends; tinsmith slurm-tin runs stage 2 as an
// array job. The output appears only when complete.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "core/tiles/pyramid.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/readers/point_sources.hpp"

namespace tinsmith::ingest {

struct BlockTinOptions {
  std::string crs;                      ///< recorded in the TIN
  std::size_t blockPoints = 1'000'000;  ///< about this many points a block's own
  /// The largest circumradius a triangle may have (metres); 0: 8 × the
  /// points' mean spacing over their box.
  double maxCircumradius = 0;
  unsigned threads = 1;  ///< for each block's triangulation (the TIN is the same for any)
};

struct BlockTinReport {
  std::size_t inputPoints = 0;
  std::size_t duplicates = 0;  ///< exact (x, y) repeats dropped
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t leftOut =
      0;  ///< triangles over maxCircumradius (each counted by its least corner's block)
  std::size_t gridBlocks = 0;  ///< blocks in the grid
  std::size_t blocks = 0;      ///< blocks with points
  double blockSide = 0;        ///< B, metres
  double maxCircumradius = 0;
  std::size_t largestTriangulated = 0;  ///< points one block triangulated, its surroundings' too
  std::size_t triangulated = 0;         ///< over every block: the overlap's cost against `vertices`
  tiles::Rect extent;
  double zMin = 0, zMax = 0;
  struct StageTime {
    std::string stage;
    double seconds = 0;
  };
  std::vector<StageTime> times;
  double totalSeconds = 0;
  [[nodiscard]] std::string summary() const;
  [[nodiscard]] std::string toJson() const;
};

/// The three stages apart, for a cluster (tinsmith slurm-tin): stage 1 in
/// one process, stage 2 one block a task anywhere (any order, each writes its
/// own file), stage 3 in one process after them all. The .tin has the bytes
/// buildTinByBlocks writes.
///
/// Stage 1: the points spooled, bucketed and deduplicated into `dir` (on a
/// filesystem the nodes share), with blocks.json saying how. Throws as
/// buildTinByBlocks.
BlockTinReport prepareBlocks(const std::vector<PointSource>& sources,
                             const std::filesystem::path& dir, const BlockTinOptions& options,
                             const Progress* progress = nullptr);
/// The blocks with points: stage 2's tasks, 0 … n − 1.
std::size_t blockTasks(const std::filesystem::path& dir);
/// The tasks whose triangles are not there yet (failed, cancelled or lost).
std::vector<std::size_t> untriangulatedBlocks(const std::filesystem::path& dir);
/// What one block's task did.
struct BlockResult {
  std::size_t triangulated = 0;  ///< its points and those within reach
  std::size_t kept = 0;          ///< its triangles
  std::size_t leftOut = 0;       ///< its triangles over the circumradius
};
/// Stage 2, one task: its block triangulated with the points within reach,
/// its triangles written to dir/triangles/TASK.tri (atomically).
BlockResult triangulateBlock(const std::filesystem::path& dir, std::size_t task,
                             unsigned threads = 1);
/// Stage 3: the .tin from every task's triangles. Throws inputError naming a
/// task without triangles (and what to run), or damaged files.
BlockTinReport assembleBlocks(const std::filesystem::path& dir, const std::filesystem::path& output,
                              const Progress* progress = nullptr);

/// Builds the TIN of `sources` into `output` (a .tin), the three stages in
/// one process with the scratch folder next to the output. Throws inputError for
/// a non-finite coordinate or one out of the triangulation's range (naming
/// the source and the point), geometryError when no triangle is within R,
/// usageError for R < 0 or blockPoints < 16, ioError when the scratch files
/// or the output cannot be written (nothing is left behind).
BlockTinReport buildTinByBlocks(const std::vector<PointSource>& sources,
                                const std::filesystem::path& output, const BlockTinOptions& options,
                                const Progress* progress = nullptr);

/// The circumcircle's radius of the triangle a, b, c (+inf when they are
/// collinear), computed from the corners sorted by (x, y), so the same
/// whatever their order: the rule both a block and a whole triangulation
/// apply.
double circumradius(Point2 a, Point2 b, Point2 c);

}  // namespace tinsmith::ingest
