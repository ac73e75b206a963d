// The `.tin` file: one TinData (core/tin/tin_data.hpp) on disk, compact,
// versioned and checksummed. Little-endian throughout, no padding, so the same
// TinData always gives the same bytes on every machine.
//
//   header (32 bytes)
//     0  magic          8 bytes  89 'T' 'I' 'N' 0D 0A 1A 0A  (PNG-style: catches
//                                text-mode and 7-bit transfer damage)
//     8  version        u32      kTinFormatVersion; readers refuse newer ones
//    12  flags          u32      0 (reserved)
//    16  payload size   u64      bytes after the header
//    24  payload CRC    u32      CRC-32 (IEEE 802.3, as zlib's crc32) of the payload
//    28  header CRC     u32      CRC-32 of header bytes 0..27
//   payload
//     crs               u32 length + UTF-8 bytes ("EPSG:26912" or WKT; may be empty)
//     vertices          u64 n + n × (f64 x, f64 y, f64 z)
//     triangles         u64 n + n × (u32 a, b, c), counter-clockwise
//     features          u64 n + n × (u8 FeatureKind, u32 length + UTF-8 source)
//     constrained edges u64 n + n × (u32 a, u32 b, u32 feature), a < b
//     block index       (version 2 on; what a reader of part of the file needs)
//       u32 records a block, k (1024)
//       u32 CRC-32 of the frame: the crs section, the vertex and triangle
//           counts, the features section and the constrained-edge count, in
//           the file's order
//       for the vertices, the triangles and the constrained edges:
//         u64 blocks ⌈n / k⌉ + per block of k records (the last one shorter):
//           f64 x0, y0, x1, y1  the box of its vertices, of its triangles'
//                               corners, of its edges' ends
//           u32 CRC-32          of its records' bytes
//       summary (version 3; what lets a reader of part of the file read
//       only the part of the index its region needs):
//         u32 entries a group, g (1024)
//         for the vertices, the triangles and the constrained edges:
//           u64 groups ⌈blocks / g⌉ + per group of g entries (the last one shorter):
//             f64 x0, y0, x1, y1  the union of its entries' boxes
//             u32 CRC-32          of its entries' bytes
//         u32 CRC-32 of the index's first 8 bytes (k and the frame's CRC)
//             followed by the summary's bytes before it
//       u32 CRC-32 of the index's bytes before it
//
// Python check of a file's payload: zlib.crc32(data[32:]) == header CRC.
// Version 1 files (no block index) and version 2 files (no summary) are
// still read, whole or in part.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/mesh.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::ingest {

inline constexpr std::uint32_t kTinFormatVersion = 3;
/// Records a block of the block index (the file says its own).
inline constexpr std::uint32_t kTinBlockRecords = 1024;
/// Index entries a group of the index's summary (the file says its own).
inline constexpr std::uint32_t kTinIndexGroupBlocks = 1024;
inline constexpr std::size_t kTinHeaderSize = 32;

/// Writes `tin` atomically (temp file + rename; a failure leaves no file).
/// Throws internalError when `tin` breaks the TinData contract (an index out of
/// range, a non-finite coordinate) and ioError when the file cannot be written.
/// With threads other than 1 (0: every core), the checksum of the large
/// arrays is computed on a second thread while they are written; the bytes are
/// the same.
void writeTinFile(const std::filesystem::path& path, const TinData& tin, unsigned threads = 1);
/// Writes a mesh as writeTinFile(path, mesh.toTinData()) would — the same
/// bytes — without the TinData copy (only the constrained-edge records, 12
/// bytes each, are made).
void writeTinFile(const std::filesystem::path& path, const Mesh& mesh, unsigned threads = 1);

/// Writes a `.tin` whose sections come in pieces, for a TIN that is never
/// whole in memory (ingest/build/block_tin.hpp): all the vertices first, then
/// the triangles, each with its corners' points (for the block index). The
/// bytes are those writeTinFile writes for the whole TIN (no constrained
/// edges); the counts are patched in at the end, the payload's CRC combined
/// from its pieces'. Atomic: nothing appears until commit().
class TinStreamWriter {
 public:
  /// Throws ioError naming `path` when its directory is not writable.
  TinStreamWriter(const std::filesystem::path& path, std::string crs,
                  std::uint32_t recordsPerBlock = kTinBlockRecords);
  ~TinStreamWriter();
  TinStreamWriter(const TinStreamWriter&) = delete;
  TinStreamWriter& operator=(const TinStreamWriter&) = delete;

  /// Throws internalError for a non-finite coordinate, or after triangles.
  void addVertices(std::span<const Point3> vertices);
  /// `corners` holds the points of each triangle's corners, three per
  /// triangle. Throws internalError for an index out of range or repeated.
  void addTriangles(std::span<const TinData::Triangle> triangles, std::span<const Point3> corners);
  [[nodiscard]] std::uint64_t vertexCount() const;
  [[nodiscard]] std::uint64_t triangleCount() const;
  /// Writes the features, the block index and the header, and renames the
  /// file into place. Throws ioError.
  void commit(const std::vector<TinFeature>& features);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Reads a `.tin` file. Throws inputError naming the file for: a missing or
/// unreadable file, a wrong magic (not a .tin file), a newer format version, a
/// truncated file, a checksum mismatch, and any index out of range.
TinData readTinFile(const std::filesystem::path& path);

/// What a `.tin` file's header tells (checked as readTinFile checks it).
struct TinFileHeader {
  std::uint32_t version = 0;
  std::uint32_t fileCrc = 0;  ///< CRC-32 of the whole file, from the header alone
  /// The payload's first section, which follows the header (unchecked: the
  /// frame's CRC covers it, checked when the file is read).
  std::string crs;
};
TinFileHeader readTinFileHeader(const std::filesystem::path& path);
/// Throws inputError naming the file unless it is of kTinFormatVersion, as
/// the shards of a tiling job need: they name their TIN by the CRC of its
/// bytes in this format (encodeTin), and read their parts through its
/// index's summary. The error says how to rewrite it (`tinsmith export`).
/// Gives the header it read.
TinFileHeader requireCurrentTinFormat(const std::filesystem::path& path);

/// Part of a `.tin` file, for the tiles of one square (a shard's subtree,
/// tiles::TilerOptions::region): the triangles whose boxes meet `region` (in
/// the file's order), the constrained edges whose boxes meet it, every
/// feature, and the vertices these use together with every vertex inside
/// `vertexRegion` (a box around `region`). The vertices keep the file's order
/// and are numbered anew from 0.
struct TinPart {
  TinData tin;
  std::uint32_t fileCrc = 0;    ///< CRC-32 of the whole file: crc32(encodeTin(whole TIN))
  std::size_t vertices = 0;     ///< in the whole file
  std::size_t triangles = 0;    ///< in the whole file
  std::uint64_t bytesRead = 0;  ///< of the file's, each checked against its CRC
};
/// Reads the part with the file mapped. A file of version 2 on is read
/// through its block index: only the blocks whose boxes meet the regions
/// (and those of the vertices their triangles and edges use) are read, each
/// checked against its own CRC, as are the header and the frame; damage in
/// a block the part does not read goes unseen here (readTinFile sees it).
/// Of a version 3 index only the summary and the groups of entries the part
/// needs are read, each checked against its CRC: what a part reads grows
/// with the part, not with the file. A version 2 index is read through and
/// checked whole. A version 1 file is read through, its checksum checked
/// after the parse, and given back as it is read.
TinPart readTinFilePart(const std::filesystem::path& path, const tiles::Rect& region,
                        const tiles::Rect& vertexRegion);

/// The exact bytes writeTinFile would write (for tests and tools); with
/// another block size or group size, those of a file readers read alike;
/// with an older version (1 or 2), the bytes of a file written by an older
/// tinsmith (for tests and benchmarks of what readers still read).
std::string encodeTin(const TinData& tin, std::uint32_t recordsPerBlock = kTinBlockRecords,
                      std::uint32_t blocksPerGroup = kTinIndexGroupBlocks,
                      std::uint32_t version = kTinFormatVersion);
/// Parses bytes as readTinFile does; `name` appears in error messages.
TinData decodeTin(std::string_view bytes, const std::string& name);

/// CRC-32 (IEEE, reflected, as zlib) continued from `crc` (0 to start).
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);
std::uint32_t crc32(std::string_view bytes, std::uint32_t crc = 0);
/// The CRC-32 of two byte strings one after the other, from the CRC of each
/// and the second's length (as zlib's crc32_combine).
std::uint32_t crc32Combine(std::uint32_t first, std::uint32_t second, std::uint64_t secondLength);

/// Throws (internalError when `forWriting`, else inputError naming `name`)
/// when `tin` breaks its contract: indices out of range, a triangle or edge
/// with repeated vertices, an edge with a >= b, a non-finite coordinate or an
/// unknown FeatureKind.
void checkTinContract(const TinData& tin, const std::string& name, bool forWriting);

/// "contour", "road", … — the names the config and the reports use.
std::string_view featureKindName(FeatureKind kind);
/// The inverse of featureKindName; nullopt for an unknown name.
std::optional<FeatureKind> featureKindFromName(std::string_view name);

}  // namespace tinsmith::ingest
