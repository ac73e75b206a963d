// What reading a shard's part of a `.tin` costs when its block index is
// large (issue 24: a subtree shard reads its part through the index, which
// at 10⁹ vertices is about 105 MB). The index grows with the number of
// blocks, so a file written with few records a block stands for a much
// larger TIN: SRTM N44W072 (1.44 M vertices) at 1 record a block has the
// index of a TIN of about 1.5·10⁹ vertices at the usual 1 024.
//
//   tin_part_bench write IN.tin OUT.tin RECORDS_PER_BLOCK [VERSION]
//       the same TIN with another block size (a file every reader reads
//       alike), in the current format or an older one (2: the block index
//       without its summary, which a part reads through)
//   tin_part_bench square FILE.tin ZOOM X Y
//       the square x0 y0 x1 y1 of the subtree Z/X/Y of the TIN's bounding square
//   tin_part_bench read FILE.tin X0 Y0 X1 Y1
//       reads the part a subtree shard of that square reads (its square, and
//       the vertices an eighth of its width around it), and prints what it
//       read and the process's peak memory before and after (VmHWM), MiB
// e.g.
//   tin_part_bench write srtm.tin srtm-k1.tin 1
//   tin_part_bench read srtm-k1.tin $(tin_part_bench square srtm.tin 2 1 1)
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "core/tiles/pyramid.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace {

/// The process's peak resident memory so far, MiB (Linux VmHWM).
double peakMiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

int usage() {
  std::cerr << "usage: tin_part_bench write IN.tin OUT.tin RECORDS_PER_BLOCK [VERSION]\n"
               "       tin_part_bench square FILE.tin ZOOM X Y\n"
               "       tin_part_bench read FILE.tin X0 Y0 X1 Y1\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace tinsmith;
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "write" && (argc == 5 || argc == 6)) {
      const TinData tin = ingest::readTinFile(argv[2]);
      const auto version =
          argc == 6 ? static_cast<std::uint32_t>(std::stoul(argv[5])) : ingest::kTinFormatVersion;
      const std::string bytes =
          ingest::encodeTin(tin, static_cast<std::uint32_t>(std::stoul(argv[4])),
                            ingest::kTinIndexGroupBlocks, version);
      std::ofstream out(argv[3], std::ios::binary | std::ios::trunc);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      if (!out) throw std::runtime_error(std::string("cannot write ") + argv[3]);
      std::cout << "wrote " << argv[3] << ": " << bytes.size() << " bytes, " << tin.vertices.size()
                << " vertices\n";
      return 0;
    }
    if (mode == "square" && argc == 6) {
      // The pyramid a Tiler of the whole TIN makes: its bounding square.
      const tiles::Rect box = tiles::boundsOf(ingest::readTinFile(argv[2]).vertices);
      const tiles::PyramidGeometry pyramid({box.x0, box.y0}, std::max(box.width(), box.height()));
      const tiles::Rect square =
          pyramid.bounds({std::stoi(argv[3]), static_cast<std::uint32_t>(std::stoul(argv[4])),
                          static_cast<std::uint32_t>(std::stoul(argv[5]))});
      std::printf("%.17g %.17g %.17g %.17g\n", square.x0, square.y0, square.x1, square.y1);
      return 0;
    }
    if (mode == "read" && argc == 7) {
      const tiles::Rect region{std::stod(argv[3]), std::stod(argv[4]), std::stod(argv[5]),
                               std::stod(argv[6])};
      const double grow = region.width() / 8;
      const tiles::Rect vertexRegion{region.x0 - grow, region.y0 - grow, region.x1 + grow,
                                     region.y1 + grow};
      const double before = peakMiB();
      const ingest::TinPart part = ingest::readTinFilePart(argv[2], region, vertexRegion);
      const double after = peakMiB();
      std::printf(
          "%zu of %zu vertices, %zu of %zu triangles, %.1f MB read and checked; "
          "peak memory %.1f MiB before, %.1f MiB after (+%.1f)\n",
          part.tin.vertices.size(), part.vertices, part.tin.triangles.size(), part.triangles,
          part.bytesRead / 1e6, before, after, after - before);
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "tin_part_bench: " << e.what() << "\n";
    return 1;
  }
  return usage();
}
