#include "ingest/tinfile/tin_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <tuple>
#include <vector>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/tinfile/tin_view.hpp"

namespace tinsmith::ingest {

namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'T', 'I', 'N', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr std::uint8_t kLastKind = static_cast<std::uint8_t>(FeatureKind::BreakLine);

// CRC-32 tables for slicing by 8 (eight bytes per step; table 0 is the
// classic byte-wise table, table k advances a byte by k more zero bytes).
constexpr std::array<std::array<std::uint32_t, 256>, 8> makeCrcTables() {
  std::array<std::array<std::uint32_t, 256>, 8> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[0][i] = c;
  }
  for (std::size_t k = 1; k < 8; ++k)
    for (std::uint32_t i = 0; i < 256; ++i)
      t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFFu];
  return t;
}
constexpr auto kCrcTables = makeCrcTables();

// Little-endian encoding of the fixed-size fields, independent of the host.
template <class T>
void putLe(std::uint8_t* out, T value) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint8_t>>;
  const U bits = std::bit_cast<U>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) out[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

template <class T>
T getLe(const std::uint8_t* in) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint8_t>>;
  U bits = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i)
    bits |= static_cast<U>(static_cast<U>(in[i]) << (8 * i));
  return std::bit_cast<T>(bits);
}

// What the writer reads: a view (tin_view.hpp) and the constrained-edge
// records. From a Mesh only those records are made, as Mesh::toTinData makes
// them, so both write the same bytes.
struct TinSource : TinDataView {
  [[nodiscard]] const std::vector<TinData::ConstrainedEdge>& constrainedEdges() const {
    return tin.constrainedEdges;
  }
};

struct MeshSource : MeshView {
  explicit MeshSource(const Mesh& m) : MeshView{m}, edges(m.constrainedEdges()) {}
  std::vector<TinData::ConstrainedEdge> edges;
  [[nodiscard]] const std::vector<TinData::ConstrainedEdge>& constrainedEdges() const {
    return edges;
  }
};

std::size_t blockCount(std::size_t records, std::size_t perBlock) {
  return (records + perBlock - 1) / perBlock;
}

constexpr std::size_t kBlockEntrySize = 4 * 8 + 4;

std::uint64_t blockIndexSize(std::size_t vertices, std::size_t triangles, std::size_t edges,
                             std::size_t perBlock, std::size_t perGroup,
                             std::uint32_t version = kTinFormatVersion) {
  if (version < 2) return 0;
  std::size_t blocks = 0, groups = 0;
  for (const std::size_t records : {vertices, triangles, edges}) {
    blocks += blockCount(records, perBlock);
    groups += blockCount(blockCount(records, perBlock), perGroup);
  }
  const std::uint64_t summary = version < 3 ? 0 : 4 + 3 * 8 + kBlockEntrySize * groups + 4;
  return 4 + 4 + 3 * 8 + kBlockEntrySize * blocks + summary + 4;
}

template <class Source>
std::uint64_t payloadSize(const Source& tin, std::size_t perBlock = kTinBlockRecords,
                          std::size_t perGroup = kTinIndexGroupBlocks,
                          std::uint32_t version = kTinFormatVersion) {
  std::uint64_t size = 4 + tin.crs().size();
  size += 8 + 24ull * tin.points().size();
  size += 8 + 12ull * tin.triangleCount();
  size += 8;
  for (const auto& f : tin.features()) size += 1 + 4 + f.source.size();
  size += 8 + 12ull * tin.constrainedEdges().size();
  return size + blockIndexSize(tin.points().size(), tin.triangleCount(),
                               tin.constrainedEdges().size(), perBlock, perGroup, version);
}

// Buffers payload bytes, keeps the running CRC, and hands full buffers to a sink.
template <class Sink>
class PayloadWriter {
 public:
  /// With `overlapChecksum`, the checksum of a large block is computed on a
  /// second thread while the sink takes it.
  PayloadWriter(Sink& sink, bool overlapChecksum)
      : sink_(sink), buffer_(kBuffer), overlapChecksum_(overlapChecksum) {}
  template <class T>
  void put(T value) {
    if (used_ + sizeof(T) > kBuffer) flush();
    putLe(buffer_.data() + used_, value);
    used_ += sizeof(T);
  }
  void putString(const std::string& text) {
    put(static_cast<std::uint32_t>(text.size()));
    append(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  }
  void append(const std::uint8_t* data, std::size_t size) {
    if (used_ + size > kBuffer) flush();
    if (size > kBuffer) {
      emit(data, size);
      return;
    }
    if (size) std::memcpy(buffer_.data() + used_, data, size);
    used_ += size;
  }
  void flush() {
    emit(buffer_.data(), used_);
    used_ = 0;
  }
  [[nodiscard]] std::uint32_t crc() const { return crc_; }

 private:
  static constexpr std::size_t kBuffer = 1 << 16;
  static constexpr std::size_t kOverlapFrom = std::size_t{1} << 22;
  void emit(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return;
    if (overlapChecksum_ && size >= kOverlapFrom) {
      // If the sink throws, the future's destructor waits for the checksum.
      auto crc = std::async(std::launch::async, [data, size, before = crc_] {
        return crc32({data, size}, before);
      });
      sink_(data, size);
      crc_ = crc.get();
      return;
    }
    crc_ = crc32({data, size}, crc_);
    sink_(data, size);
  }
  Sink& sink_;
  std::vector<std::uint8_t> buffer_;
  bool overlapChecksum_;
  std::size_t used_ = 0;
  std::uint32_t crc_ = 0;
};

/// `blockIndex()` gives the encoded block index, asked for after the sections.
template <class Source, class BlockIndexBytes, class Sink>
std::uint32_t writePayload(const Source& tin, BlockIndexBytes&& blockIndex, Sink& sink,
                           bool overlapChecksum = false) {
  PayloadWriter<Sink> w(sink, overlapChecksum);
  w.putString(tin.crs());
  w.put(static_cast<std::uint64_t>(tin.points().size()));
  // The file is little-endian: on such a host the vertex and triangle arrays
  // are the file's bytes already and go out whole.
  if constexpr (std::endian::native == std::endian::little && sizeof(Point3) == 24) {
    w.append(reinterpret_cast<const std::uint8_t*>(tin.points().data()), 24 * tin.points().size());
  } else {
    for (const auto& v : tin.points()) {
      w.put(v.x);
      w.put(v.y);
      w.put(v.z);
    }
  }
  w.put(static_cast<std::uint64_t>(tin.triangleCount()));
  const std::span<const std::uint32_t> corners = tin.cornerIndices();
  if constexpr (std::endian::native == std::endian::little) {
    w.append(reinterpret_cast<const std::uint8_t*>(corners.data()), 4 * corners.size());
  } else {
    for (const std::uint32_t i : corners) w.put(i);
  }
  w.put(static_cast<std::uint64_t>(tin.features().size()));
  for (const auto& f : tin.features()) {
    w.put(static_cast<std::uint8_t>(f.kind));
    w.putString(f.source);
  }
  w.put(static_cast<std::uint64_t>(tin.constrainedEdges().size()));
  for (const auto& e : tin.constrainedEdges()) {
    w.put(e.a);
    w.put(e.b);
    w.put(e.feature);
  }
  const std::string index = blockIndex();
  w.append(reinterpret_cast<const std::uint8_t*>(index.data()), index.size());
  w.flush();
  return w.crc();
}

std::array<std::uint8_t, kTinHeaderSize> makeHeader(std::uint64_t payload, std::uint32_t crc,
                                                    std::uint32_t version = kTinFormatVersion) {
  std::array<std::uint8_t, kTinHeaderSize> h{};
  std::memcpy(h.data(), kMagic.data(), kMagic.size());
  putLe(h.data() + 8, version);
  putLe(h.data() + 12, std::uint32_t{0});
  putLe(h.data() + 16, payload);
  putLe(h.data() + 24, crc);
  putLe(h.data() + 28, crc32({h.data(), 28}));
  return h;
}

// The block index (the file's layout above): per section, the box and the
// CRC of each block of kTinBlockRecords records.
struct BlockEntry {
  tiles::Rect box;
  std::uint32_t crc = 0;
};
enum BlockSection : std::size_t { kVertexBlocks, kTriangleBlocks, kEdgeBlocks };
constexpr std::array<const char*, 3> kBlockSectionNames = {"vertex", "triangle",
                                                           "constrained-edge"};
struct BlockIndex {
  std::uint32_t recordsPerBlock = kTinBlockRecords;
  std::uint32_t blocksPerGroup = kTinIndexGroupBlocks;  ///< of the summary (version 3)
  std::uint32_t frameCrc = 0;
  std::array<std::vector<BlockEntry>, 3> sections;
};

void unite(tiles::Rect& box, const tiles::Rect& other) {
  box.x0 = std::min(box.x0, other.x0);
  box.y0 = std::min(box.y0, other.y0);
  box.x1 = std::max(box.x1, other.x1);
  box.y1 = std::max(box.y1, other.y1);
}

void include(tiles::Rect& box, const Point3& p) {
  box.x0 = std::min(box.x0, p.x);
  box.y0 = std::min(box.y0, p.y);
  box.x1 = std::max(box.x1, p.x);
  box.y1 = std::max(box.y1, p.y);
}

/// x as a float no greater than it (roundedDown) or no less (roundedUp):
/// a box that holds the double one.
float roundedDown(double x) {
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  if (x > kMax) return kMax;
  if (x < -kMax) return -kInf;
  const auto f = static_cast<float>(x);  // NaN stays NaN
  return f > x ? std::nextafter(f, -kInf) : f;
}
float roundedUp(double x) {
  return -roundedDown(-x);
}

/// Appends little-endian values to a byte string.
class ByteString {
 public:
  template <class T>
  void put(T value) {
    std::array<std::uint8_t, sizeof(T)> b{};
    putLe(b.data(), value);
    bytes.append(reinterpret_cast<const char*>(b.data()), b.size());
  }
  void putString(const std::string& text) {
    put(static_cast<std::uint32_t>(text.size()));
    bytes += text;
  }
  std::string bytes;
};

template <class Source>
BlockIndex makeBlockIndex(const Source& tin, std::uint32_t perBlock = kTinBlockRecords,
                          std::uint32_t perGroup = kTinIndexGroupBlocks) {
  BlockIndex index;
  index.recordsPerBlock = perBlock;
  index.blocksPerGroup = perGroup;
  ByteString frame;
  frame.putString(tin.crs());
  frame.put(static_cast<std::uint64_t>(tin.points().size()));
  frame.put(static_cast<std::uint64_t>(tin.triangleCount()));
  frame.put(static_cast<std::uint64_t>(tin.features().size()));
  for (const auto& f : tin.features()) {
    frame.put(static_cast<std::uint8_t>(f.kind));
    frame.putString(f.source);
  }
  frame.put(static_cast<std::uint64_t>(tin.constrainedEdges().size()));
  index.frameCrc = crc32(frame.bytes);

  const auto& points = tin.points();
  // Each block's records are encoded as the file holds them, for its CRC.
  auto blocks = [perBlock = std::size_t{perBlock}](std::size_t records, auto&& encode,
                                                   auto&& boxOf) {
    std::vector<BlockEntry> out(blockCount(records, perBlock));
    ByteString bytes;
    for (std::size_t b = 0; b < out.size(); ++b) {
      bytes.bytes.clear();
      tiles::Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      const std::size_t end = std::min(records, (b + 1) * perBlock);
      for (std::size_t k = b * perBlock; k < end; ++k) {
        encode(k, bytes);
        boxOf(k, box);
      }
      out[b] = {box, crc32(bytes.bytes)};
    }
    return out;
  };
  index.sections[kVertexBlocks] = blocks(
      points.size(),
      [&](std::size_t k, ByteString& out) {
        out.put(points[k].x);
        out.put(points[k].y);
        out.put(points[k].z);
      },
      [&](std::size_t k, tiles::Rect& box) { include(box, points[k]); });
  const std::span<const std::uint32_t> corners = tin.cornerIndices();
  index.sections[kTriangleBlocks] = blocks(
      tin.triangleCount(),
      [&](std::size_t k, ByteString& out) {
        for (std::size_t i = 0; i < 3; ++i) out.put(corners[3 * k + i]);
      },
      [&](std::size_t k, tiles::Rect& box) {
        for (std::size_t i = 0; i < 3; ++i) include(box, points[corners[3 * k + i]]);
      });
  const auto& edges = tin.constrainedEdges();
  index.sections[kEdgeBlocks] = blocks(
      edges.size(),
      [&](std::size_t k, ByteString& out) {
        out.put(edges[k].a);
        out.put(edges[k].b);
        out.put(edges[k].feature);
      },
      [&](std::size_t k, tiles::Rect& box) {
        include(box, points[edges[k].a]);
        include(box, points[edges[k].b]);
      });
  return index;
}

/// The block index as a file of `version` (2 or 3) holds it: version 3
/// adds the summary of its groups of entries.
std::string encodeBlockIndex(const BlockIndex& index, std::uint32_t version = kTinFormatVersion) {
  ByteString out;
  out.put(index.recordsPerBlock);
  out.put(index.frameCrc);
  const auto putEntry = [&out](const tiles::Rect& box, std::uint32_t crc) {
    out.put(box.x0);
    out.put(box.y0);
    out.put(box.x1);
    out.put(box.y1);
    out.put(crc);
  };
  std::array<std::size_t, 3> entriesAt{};
  for (std::size_t s = 0; s < 3; ++s) {
    out.put(static_cast<std::uint64_t>(index.sections[s].size()));
    entriesAt[s] = out.bytes.size();
    for (const auto& block : index.sections[s]) putEntry(block.box, block.crc);
  }
  if (version >= 3) {
    const std::size_t summaryAt = out.bytes.size();
    const std::size_t perGroup = index.blocksPerGroup;
    out.put(index.blocksPerGroup);
    for (std::size_t s = 0; s < 3; ++s) {
      const auto& blocks = index.sections[s];
      out.put(static_cast<std::uint64_t>(blockCount(blocks.size(), perGroup)));
      for (std::size_t first = 0; first < blocks.size(); first += perGroup) {
        const std::size_t end = std::min(blocks.size(), first + perGroup);
        tiles::Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        for (std::size_t b = first; b < end; ++b) unite(box, blocks[b].box);
        const std::uint32_t crc = crc32(std::string_view(out.bytes).substr(
            entriesAt[s] + kBlockEntrySize * first, kBlockEntrySize * (end - first)));
        putEntry(box, crc);
      }
    }
    const std::uint32_t head = crc32(std::string_view(out.bytes).substr(0, 8));
    out.put(crc32(std::string_view(out.bytes).substr(summaryAt), head));
  }
  out.put(crc32(out.bytes));
  return std::move(out.bytes);
}

[[noreturn]] void corruptFile(const std::string& what, const std::string& name) {
  throw inputError("corrupt .tin file: " + what, fileLocation(name),
                   "the file is damaged; write it again with `tinsmith tin`");
}

// Bounds-checked reading of the payload: every count is checked against the
// bytes that remain before anything is allocated, so a damaged count can
// neither over-read nor ask for absurd memory.
class PayloadReader {
 public:
  PayloadReader(const std::uint8_t* data, std::size_t size, const std::string& name)
      : p_(data), end_(data + size), name_(name) {}
  template <class T>
  T get(const char* what) {
    need(sizeof(T), what);
    T value = getLe<T>(p_);
    p_ += sizeof(T);
    return value;
  }
  std::string getString(const char* what) {
    const auto n = get<std::uint32_t>(what);
    need(n, what);
    std::string s(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    return s;
  }
  std::size_t getCount(std::size_t recordSize, const char* what) {
    const auto n = get<std::uint64_t>(what);
    if (recordSize && n > static_cast<std::uint64_t>(end_ - p_) / recordSize)
      corrupt(std::string("the ") + what + " count (" + std::to_string(n) +
              ") does not fit in the file");
    return static_cast<std::size_t>(n);
  }
  /// Steps over `count` records of `recordSize` bytes (a count getCount checked).
  const std::uint8_t* skip(std::size_t count, std::size_t recordSize, const char* what) {
    const std::uint8_t* at = p_;
    need(count * recordSize, what);
    p_ += count * recordSize;
    return at;
  }
  [[nodiscard]] std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  [[nodiscard]] const std::uint8_t* position() const { return p_; }
  [[noreturn]] void corrupt(const std::string& what) const { corruptFile(what, name_); }

 private:
  void need(std::size_t n, const char* what) const {
    if (static_cast<std::size_t>(end_ - p_) < n) corrupt(std::string("it ends inside the ") + what);
  }
  const std::uint8_t* p_;
  const std::uint8_t* end_;
  const std::string& name_;
};

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  const auto& t = kCrcTables;
  crc = ~crc;
  const std::uint8_t* p = bytes.data();
  std::size_t n = bytes.size();
  for (; n >= 8; n -= 8, p += 8) {  // independent of the host's byte order
    const std::uint32_t lo = crc ^ (std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 |
                                    std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24);
    crc = t[7][lo & 0xFFu] ^ t[6][(lo >> 8) & 0xFFu] ^ t[5][(lo >> 16) & 0xFFu] ^ t[4][lo >> 24] ^
          t[3][p[4]] ^ t[2][p[5]] ^ t[1][p[6]] ^ t[0][p[7]];
  }
  for (; n > 0; --n, ++p) crc = t[0][(crc ^ *p) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t crc32(std::string_view bytes, std::uint32_t crc) {
  return crc32({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, crc);
}

namespace {

// Polynomials modulo the CRC's, in its reflected bit order: bit 31 is x^0.
std::uint32_t multiplyModCrc(std::uint32_t a, std::uint32_t b) {
  std::uint32_t product = 0;
  for (int i = 31; i >= 0; --i) {
    if ((a >> i) & 1u) product ^= b;
    b = (b & 1u) ? (b >> 1) ^ 0xEDB88320u : b >> 1;  // b · x
  }
  return product;
}

}  // namespace

std::uint32_t crc32Combine(std::uint32_t first, std::uint32_t second, std::uint64_t secondLength) {
  // Appending n bytes multiplies the first CRC by x^(8n): x^8, squared step by step.
  std::uint32_t shift = 1u << 31;  // x^0
  for (std::uint32_t power = 1u << 23; secondLength > 0; secondLength >>= 1) {
    if (secondLength & 1) shift = multiplyModCrc(power, shift);
    power = multiplyModCrc(power, power);
  }
  return multiplyModCrc(shift, first) ^ second;
}

std::string_view featureKindName(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::Other:
      return "other";
    case FeatureKind::SpotHeight:
      return "spot-height";
    case FeatureKind::Contour:
      return "contour";
    case FeatureKind::Road:
      return "road";
    case FeatureKind::River:
      return "river";
    case FeatureKind::Lake:
      return "lake";
    case FeatureKind::Boundary:
      return "boundary";
    case FeatureKind::Hole:
      return "hole";
    case FeatureKind::Raster:
      return "raster";
    case FeatureKind::BreakLine:
      return "breakline";
  }
  return "unknown";
}

std::optional<FeatureKind> featureKindFromName(std::string_view name) {
  for (std::uint8_t k = 0; k <= kLastKind; ++k) {
    const auto kind = static_cast<FeatureKind>(k);
    if (featureKindName(kind) == name) return kind;
  }
  return std::nullopt;
}

namespace {

template <class Source>
void checkContract(const Source& tin, const std::string& name, bool forWriting) {
  auto bad = [&](const std::string& what) {
    if (forWriting) throw internalError("TinData for '" + name + "' is malformed: " + what);
    corruptFile(what, name);
  };
  const std::size_t nv = tin.points().size();
  if (nv > 0xFFFFFFFFull) bad("more than 2^32 - 1 vertices");
  for (std::size_t i = 0; i < nv; ++i) {
    const auto& v = tin.points()[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      bad("vertex " + std::to_string(i) + " has a non-finite coordinate");
  }
  for (std::size_t t = 0; t < tin.triangleCount(); ++t) {
    const auto& tri = tin.triangle(t);
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv)
      bad("triangle " + std::to_string(t) + " refers to a vertex beyond the " + std::to_string(nv) +
          " vertices");
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      bad("triangle " + std::to_string(t) + " repeats a vertex");
  }
  for (std::size_t f = 0; f < tin.features().size(); ++f)
    if (static_cast<std::uint8_t>(tin.features()[f].kind) > kLastKind)
      bad("feature " + std::to_string(f) + " has an unknown kind " +
          std::to_string(static_cast<int>(tin.features()[f].kind)));
  for (std::size_t i = 0; i < tin.constrainedEdges().size(); ++i) {
    const auto& e = tin.constrainedEdges()[i];
    if (e.a >= nv || e.b >= nv)
      bad("constrained edge " + std::to_string(i) + " refers to a vertex out of range");
    if (e.a >= e.b) bad("constrained edge " + std::to_string(i) + " does not have a < b");
    if (e.feature >= tin.features().size())
      bad("constrained edge " + std::to_string(i) + " refers to feature " +
          std::to_string(e.feature) + " of " + std::to_string(tin.features().size()));
  }
}

}  // namespace

void checkTinContract(const TinData& tin, const std::string& name, bool forWriting) {
  checkContract(TinSource{{tin}}, name, forWriting);
}

std::string encodeTin(const TinData& tin, std::uint32_t recordsPerBlock,
                      std::uint32_t blocksPerGroup, std::uint32_t version) {
  if (recordsPerBlock == 0 || blocksPerGroup == 0)
    throw internalError("encodeTin: blocks of 0 records or groups of 0 blocks");
  if (version == 0 || version > kTinFormatVersion)
    throw internalError("encodeTin: no .tin format version " + std::to_string(version));
  checkTinContract(tin, "(memory)", true);
  std::string out;
  const TinSource source{{tin}};
  const std::uint64_t size = payloadSize(source, recordsPerBlock, blocksPerGroup, version);
  out.reserve(kTinHeaderSize + size);
  out.resize(kTinHeaderSize);
  auto sink = [&out](const std::uint8_t* data, std::size_t n) {
    out.append(reinterpret_cast<const char*>(data), n);
  };
  const std::uint32_t crc = writePayload(
      source,
      [&]() -> std::string {
        if (version < 2) return {};
        return encodeBlockIndex(makeBlockIndex(source, recordsPerBlock, blocksPerGroup), version);
      },
      sink);
  const auto header = makeHeader(size, crc, version);
  std::memcpy(out.data(), header.data(), header.size());
  return out;
}

namespace {

template <class Source>
void writeFile(const std::filesystem::path& path, const Source& tin, unsigned threads) {
  checkContract(tin, path.string(), true);
  // With threads, the block index is made while the sections are written.
  const bool overlap = resolveThreads(threads) > 1;
  auto blockIndex = std::async(overlap ? std::launch::async : std::launch::deferred,
                               [&tin] { return encodeBlockIndex(makeBlockIndex(tin)); });
  AtomicFile file(path);
  const std::uint64_t size = payloadSize(tin);
  const auto placeholder = makeHeader(size, 0);
  file.write(placeholder.data(), placeholder.size());
  auto sink = [&file](const std::uint8_t* data, std::size_t n) { file.write(data, n); };
  const std::uint32_t crc = writePayload(
      tin, [&blockIndex] { return blockIndex.get(); }, sink, overlap);
  const auto header = makeHeader(size, crc);
  file.writeAt(0, header.data(), header.size());
  file.commit();
}

}  // namespace

void writeTinFile(const std::filesystem::path& path, const TinData& tin, unsigned threads) {
  writeFile(path, TinSource{{tin}}, threads);
}

// The payload as four pieces, each with its own CRC, combined at the end:
// [crs, vertex count, vertices] [triangle count] [triangles] [features,
// edge count, block index]. The two counts are written as 0 and patched.
struct TinStreamWriter::State {
  State(const std::filesystem::path& path, std::string crsText, std::uint32_t perBlock)
      : file(path), crs(std::move(crsText)) {
    index.recordsPerBlock = perBlock;
    const auto placeholder = makeHeader(0, 0);
    file.write(placeholder.data(), placeholder.size());
    ByteString head;
    head.putString(crs);
    vertexCountAt = kTinHeaderSize + head.bytes.size();
    head.put(std::uint64_t{0});
    file.write(head.bytes);
    headBytes = head.bytes.size();
  }
  /// A record of `section` went into the running block.
  void endRecord(BlockSection section) {
    if (++inBlock == index.recordsPerBlock) endBlock(section);
  }
  void endBlock(BlockSection section) {
    if (inBlock == 0) return;
    index.sections[section].push_back({box, blockCrc});
    box = {HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    blockCrc = 0;
    inBlock = 0;
  }
  void closeVertices() {
    if (verticesClosed) return;
    endBlock(kVertexBlocks);
    verticesClosed = true;
    triangleCountAt = kTinHeaderSize + headBytes + 24 * vertices;
    file.write(std::string(8, '\0'));
  }

  AtomicFile file;
  std::string crs;
  BlockIndex index;
  std::uint64_t vertices = 0, triangles = 0;
  std::uint64_t headBytes = 0;  // the crs section and the vertex count
  std::uint64_t vertexCountAt = 0, triangleCountAt = 0;
  std::uint32_t vertexCrc = 0, triangleCrc = 0;  // of the records
  tiles::Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  std::uint32_t blockCrc = 0;
  std::uint32_t inBlock = 0;  // records in the running block
  bool verticesClosed = false;
  std::vector<std::uint8_t> bytes;  // records of one call, as the file holds them
};

TinStreamWriter::TinStreamWriter(const std::filesystem::path& path, std::string crs,
                                 std::uint32_t recordsPerBlock)
    : state_(std::make_unique<State>(path, std::move(crs), recordsPerBlock)) {
  if (recordsPerBlock == 0) throw internalError("TinStreamWriter: blocks of 0 records");
}

TinStreamWriter::~TinStreamWriter() = default;

std::uint64_t TinStreamWriter::vertexCount() const {
  return state_->vertices;
}
std::uint64_t TinStreamWriter::triangleCount() const {
  return state_->triangles;
}

void TinStreamWriter::addVertices(std::span<const Point3> vertices) {
  State& s = *state_;
  if (s.verticesClosed) throw internalError("TinStreamWriter: vertices after triangles");
  s.bytes.resize(24 * vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Point3& p = vertices[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw internalError("TinStreamWriter: a vertex with a non-finite coordinate");
    std::uint8_t* record = s.bytes.data() + 24 * i;
    putLe(record, p.x);
    putLe(record + 8, p.y);
    putLe(record + 16, p.z);
    s.blockCrc = crc32({record, 24}, s.blockCrc);
    include(s.box, p);
    ++s.vertices;
    s.endRecord(kVertexBlocks);
  }
  s.vertexCrc = crc32(s.bytes, s.vertexCrc);
  s.file.write(s.bytes.data(), s.bytes.size());
}

void TinStreamWriter::addTriangles(std::span<const TinData::Triangle> triangles,
                                   std::span<const Point3> corners) {
  State& s = *state_;
  if (corners.size() != 3 * triangles.size())
    throw internalError("TinStreamWriter: not three corner points per triangle");
  s.closeVertices();
  s.bytes.resize(12 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    if (std::max({tri[0], tri[1], tri[2]}) >= s.vertices || tri[0] == tri[1] || tri[1] == tri[2] ||
        tri[0] == tri[2])
      throw internalError("TinStreamWriter: a triangle's corner is out of range or repeated");
    std::uint8_t* record = s.bytes.data() + 12 * t;
    for (int i = 0; i < 3; ++i) {
      putLe(record + 4 * i, tri[i]);
      include(s.box, corners[3 * t + i]);
    }
    s.blockCrc = crc32({record, 12}, s.blockCrc);
    ++s.triangles;
    s.endRecord(kTriangleBlocks);
  }
  s.triangleCrc = crc32(s.bytes, s.triangleCrc);
  s.file.write(s.bytes.data(), s.bytes.size());
}

void TinStreamWriter::commit(const std::vector<TinFeature>& features) {
  State& s = *state_;
  s.closeVertices();
  s.endBlock(kTriangleBlocks);
  ByteString frame;
  frame.putString(s.crs);
  frame.put(s.vertices);
  frame.put(s.triangles);
  ByteString tail;
  tail.put(static_cast<std::uint64_t>(features.size()));
  for (const auto& f : features) {
    tail.put(static_cast<std::uint8_t>(f.kind));
    tail.putString(f.source);
  }
  tail.put(std::uint64_t{0});  // constrained edges
  frame.bytes += tail.bytes;
  s.index.frameCrc = crc32(frame.bytes);
  tail.bytes += encodeBlockIndex(s.index);
  s.file.write(tail.bytes);

  ByteString head;
  head.putString(s.crs);
  head.put(s.vertices);
  ByteString count;
  count.put(s.triangles);
  std::uint32_t crc = crc32Combine(crc32(head.bytes), s.vertexCrc, 24 * s.vertices);
  crc = crc32Combine(crc, crc32(count.bytes), 8);
  crc = crc32Combine(crc, s.triangleCrc, 12 * s.triangles);
  crc = crc32Combine(crc, crc32(tail.bytes), tail.bytes.size());
  const std::uint64_t payload =
      s.headBytes + 24 * s.vertices + 8 + 12 * s.triangles + tail.bytes.size();
  s.file.writeAt(s.vertexCountAt, head.bytes.data() + head.bytes.size() - 8, 8);
  s.file.writeAt(s.triangleCountAt, count.bytes.data(), 8);
  const auto header = makeHeader(payload, crc);
  s.file.writeAt(0, header.data(), header.size());
  s.file.commit();
}

void writeTinFile(const std::filesystem::path& path, const Mesh& mesh, unsigned threads) {
  writeFile(path, MeshSource(mesh), threads);
}

namespace {

/// A .tin file's payload, after its header was checked.
struct CheckedPayload {
  std::span<const std::uint8_t> bytes;
  std::uint32_t version = 0;
  std::uint32_t crc = 0;      ///< the header's payload CRC
  std::uint32_t fileCrc = 0;  ///< CRC-32 of the whole file, from the header alone
};

/// Checks the header of a .tin file's bytes (all of them).
CheckedPayload checkedPayload(std::span<const std::uint8_t> bytes, const std::string& name) {
  const std::uint8_t* data = bytes.data();
  if (bytes.size() < kMagic.size() || std::memcmp(data, kMagic.data(), kMagic.size()) != 0)
    throw inputError("not a .tin file (wrong magic bytes)", fileLocation(name),
                     "give a file written by `tinsmith tin`");
  if (bytes.size() < kTinHeaderSize)
    throw inputError("truncated .tin file: " + std::to_string(bytes.size()) +
                         " bytes, shorter than the 32-byte header",
                     fileLocation(name),
                     "the file is incomplete; write it again with `tinsmith tin`");
  const auto version = getLe<std::uint32_t>(data + 8);
  if (getLe<std::uint32_t>(data + 28) != crc32({data, 28}))
    corruptFile("the header checksum does not match", name);
  if (version > kTinFormatVersion)
    throw inputError(".tin format version " + std::to_string(version) +
                         " is newer than this tinsmith reads (version " +
                         std::to_string(kTinFormatVersion) + ")",
                     fileLocation(name), "use a newer tinsmith to read it");
  if (version == 0) corruptFile("format version 0", name);
  const auto payload = getLe<std::uint64_t>(data + 16);
  const std::uint64_t have = bytes.size() - kTinHeaderSize;
  if (have < payload)
    throw inputError("truncated .tin file: the header announces " + std::to_string(payload) +
                         " payload bytes but only " + std::to_string(have) + " follow",
                     fileLocation(name),
                     "the file is incomplete; write it again with `tinsmith tin`");
  if (have > payload)
    corruptFile(std::to_string(have - payload) + " unexpected bytes after the payload", name);
  const auto crc = getLe<std::uint32_t>(data + 24);
  return {{data + kTinHeaderSize, payload},
          version,
          crc,
          crc32Combine(crc32({data, kTinHeaderSize}), crc, payload)};
}

bool meetsRegion(const tiles::Rect& region, std::initializer_list<Point3> corners) {
  return tiles::boundsOf(corners).overlaps(region);
}

/// Reads a payload's sections up to the block index into `tin`: all of it,
/// or with `region` every vertex and feature, the triangles and the
/// constrained edges whose boxes meet it (their vertices, in the file's
/// numbering, go to `keep`). `pace()` runs every 65 536 records of the large
/// sections. Returns the file's triangle count.
template <class Pace>
std::size_t readSections(PayloadReader& r, TinData& tin, const tiles::Rect* region,
                         std::vector<std::uint32_t>& keep, Pace&& pace) {
  tin.crs = r.getString("CRS text");
  tin.vertices.resize(r.getCount(24, "vertex"));
  for (std::size_t i = 0; i < tin.vertices.size(); ++i) {
    auto& v = tin.vertices[i];
    v.x = r.get<double>("vertices");
    v.y = r.get<double>("vertices");
    v.z = r.get<double>("vertices");
    if ((i & 0xFFFF) == 0) pace();
  }
  const std::size_t nv = tin.vertices.size();
  const std::size_t triangles = r.getCount(12, "triangle");
  if (!region) tin.triangles.reserve(triangles);
  for (std::size_t k = 0; k < triangles; ++k) {
    std::array<std::uint32_t, 3> t{};
    for (auto& i : t) i = r.get<std::uint32_t>("triangles");
    if ((k & 0xFFFF) == 0) pace();
    if (!region) {
      tin.triangles.push_back(t);  // checkTinContract checks the indices
      continue;
    }
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv)
      r.corrupt("triangle " + std::to_string(k) + " refers to a vertex beyond the " +
                std::to_string(nv) + " vertices");
    if (meetsRegion(*region, {tin.vertices[t[0]], tin.vertices[t[1]], tin.vertices[t[2]]})) {
      tin.triangles.push_back(t);
      keep.insert(keep.end(), t.begin(), t.end());
    }
  }
  tin.features.resize(r.getCount(5, "feature"));
  for (auto& f : tin.features) {
    f.kind = static_cast<FeatureKind>(r.get<std::uint8_t>("features"));
    f.source = r.getString("features");
  }
  const std::size_t edges = r.getCount(12, "constrained edge");
  if (!region) tin.constrainedEdges.reserve(edges);
  for (std::size_t k = 0; k < edges; ++k) {
    TinData::ConstrainedEdge e;
    e.a = r.get<std::uint32_t>("constrained edges");
    e.b = r.get<std::uint32_t>("constrained edges");
    e.feature = r.get<std::uint32_t>("constrained edges");
    if ((k & 0xFFFF) == 0) pace();
    if (!region) {
      tin.constrainedEdges.push_back(e);
      continue;
    }
    if (e.a >= nv || e.b >= nv)
      r.corrupt("constrained edge " + std::to_string(k) + " refers to a vertex out of range");
    if (meetsRegion(*region, {tin.vertices[e.a], tin.vertices[e.b]})) {
      tin.constrainedEdges.push_back(e);
      keep.push_back(e.a);
      keep.push_back(e.b);
    }
  }
  return triangles;
}

/// Numbers a part's vertices anew: `keep` (the file's numbers, in any order,
/// repeats allowed) in the file's order, with the triangles and edges, in
/// the file's numbers, mapped onto them. `vertexAt(v)` gives vertex v.
template <class VertexAt>
void renumberPart(TinData& tin, std::vector<std::uint32_t> keep, VertexAt&& vertexAt) {
  std::sort(keep.begin(), keep.end());
  keep.erase(std::unique(keep.begin(), keep.end()), keep.end());
  const auto local = [&keep](std::uint32_t v) {
    return static_cast<std::uint32_t>(std::lower_bound(keep.begin(), keep.end(), v) - keep.begin());
  };
  for (auto& t : tin.triangles)
    for (auto& v : t) v = local(v);
  for (auto& e : tin.constrainedEdges) {
    e.a = local(e.a);
    e.b = local(e.b);
  }
  std::vector<Point3> vertices;
  vertices.reserve(keep.size());
  for (const std::uint32_t v : keep) vertices.push_back(vertexAt(v));
  tin.vertices = std::move(vertices);
}

/// Checks what follows the sections: nothing in version 1; from version 2 on
/// the block index, which must be the one `tin` gives.
void checkBlockIndex(const PayloadReader& r, const TinData& tin, std::uint32_t version) {
  if (version < 2) {
    if (r.remaining() != 0) r.corrupt("bytes left over after the last section");
    return;
  }
  if (r.remaining() < 4) r.corrupt("it ends inside the block index");
  const auto perBlock = getLe<std::uint32_t>(r.position());
  if (perBlock == 0) r.corrupt("the block index has blocks of 0 records");
  std::uint32_t perGroup = kTinIndexGroupBlocks;
  if (version >= 3) {  // the summary follows the three sections' entries
    std::uint64_t summaryAt = 8;
    for (const std::size_t n :
         {tin.vertices.size(), tin.triangles.size(), tin.constrainedEdges.size()})
      summaryAt += 8 + kBlockEntrySize * blockCount(n, perBlock);
    if (r.remaining() < summaryAt + 4) r.corrupt("it ends inside the block index");
    perGroup = getLe<std::uint32_t>(r.position() + summaryAt);
    if (perGroup == 0) r.corrupt("the block index summary has groups of 0 entries");
  }
  const std::string expected =
      encodeBlockIndex(makeBlockIndex(TinSource{{tin}}, perBlock, perGroup), version);
  if (r.remaining() != expected.size() ||
      std::memcmp(r.position(), expected.data(), expected.size()) != 0)
    r.corrupt("its block index does not match its sections");
}

}  // namespace

TinData decodeTin(std::string_view bytes, const std::string& name) {
  const CheckedPayload payload =
      checkedPayload({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, name);
  if (crc32(payload.bytes) != payload.crc) corruptFile("the payload checksum does not match", name);

  PayloadReader r(payload.bytes.data(), payload.bytes.size(), name);
  TinData tin;
  std::vector<std::uint32_t> unused;
  readSections(r, tin, nullptr, unused, [] {});
  checkTinContract(tin, name, false);
  checkBlockIndex(r, tin, payload.version);
  return tin;
}

namespace {

/// Throws inputError naming the file unless it is a file this process can open.
void requireReadableFile(const std::filesystem::path& path, const std::string& name) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw inputError("the .tin file does not exist", fileLocation(name), "check the path");
  if (std::filesystem::is_directory(path, ec))
    throw inputError("is a directory, not a .tin file", fileLocation(name));
}

/// A file mapped read-only, unmapped with this.
class MappedFile {
 public:
  MappedFile(const std::filesystem::path& path, const std::string& name) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0)
      throw inputError("cannot open the .tin file for reading", fileLocation(name),
                       "check permissions");
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      ::close(fd_);
      throw inputError("cannot read the .tin file", fileLocation(name), "check permissions");
    }
    size_ = static_cast<std::size_t>(st.st_size);
    if (size_ > 0) {
      void* m = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
      if (m == MAP_FAILED) {
        ::close(fd_);
        throw inputError("cannot map the .tin file into memory", fileLocation(name));
      }
      data_ = static_cast<const std::uint8_t*>(m);
    }
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile() {
    if (data_) ::munmap(const_cast<std::uint8_t*>(data_), size_);
    ::close(fd_);
  }
  [[nodiscard]] std::span<const std::uint8_t> bytes() const { return {data_, size_}; }
  /// Tells the kernel the file will be read from start to end.
  void readInOrder() const {
    if (data_) ::madvise(const_cast<std::uint8_t*>(data_), size_, MADV_SEQUENTIAL);
  }
  /// Copies `n` bytes of the file from `at` (in bytes()) into `out` by
  /// reading the file, not the mapping: no page of it comes to count in the
  /// process's memory. False when the file cannot be read.
  bool copy(const std::uint8_t* at, std::size_t n, std::uint8_t* out) const {
    auto offset = static_cast<off_t>(at - data_);
    while (n > 0) {
      const ssize_t got = ::pread(fd_, out, n, offset);
      if (got <= 0) return false;
      out += got;
      offset += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  }
  /// Gives back the pages wholly before `upTo`, which have been read: they
  /// stop counting in the process's memory (a second read maps them again).
  void release(const std::uint8_t* upTo) const {
    const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    const std::size_t n = static_cast<std::size_t>(upTo - data_) / page * page;
    if (n > 0) ::madvise(const_cast<std::uint8_t*>(data_), n, MADV_DONTNEED);
  }

 private:
  int fd_ = -1;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

/// A version 1 file's part: every section read through, the checksum
/// following the reader a window at a time and what it has passed given
/// back, so the file is never all in memory.
TinPart readPartThrough(const MappedFile& file, const CheckedPayload& payload,
                        const std::string& name, const tiles::Rect& region,
                        const tiles::Rect& vertexRegion) {
  file.readInOrder();
  const std::span<const std::uint8_t> body = payload.bytes;
  std::uint32_t crc = 0;
  const std::uint8_t* checked = body.data();
  const auto checkUpTo = [&](const std::uint8_t* to) {
    crc = crc32({checked, static_cast<std::size_t>(to - checked)}, crc);
    checked = to;
    file.release(to);
  };
  constexpr std::ptrdiff_t kWindow = std::ptrdiff_t{8} << 20;
  PayloadReader r(body.data(), body.size(), name);
  const auto keepUp = [&] {
    if (r.position() - checked >= kWindow) checkUpTo(r.position());
  };

  TinPart part;
  std::vector<std::uint32_t> keep;
  part.triangles = readSections(r, part.tin, &region, keep, keepUp);
  if (r.remaining() != 0) r.corrupt("bytes left over after the last section");
  checkUpTo(body.data() + body.size());
  if (crc != payload.crc) corruptFile("the payload checksum does not match", name);
  part.bytesRead = kTinHeaderSize + body.size();
  part.vertices = part.tin.vertices.size();
  const std::vector<Point3> all = std::move(part.tin.vertices);
  for (std::uint32_t v = 0; v < all.size(); ++v)
    if (vertexRegion.contains(all[v].xy())) keep.push_back(v);
  renumberPart(part.tin, std::move(keep), [&all](std::uint32_t v) { return all[v]; });
  return part;
}

/// What the part of a file keeps of its block index: the triangle and edge
/// blocks whose boxes meet its region, the vertex blocks whose boxes meet
/// its vertex region, and the box and CRC of any vertex block it asks for.
struct PartIndex {
  struct KeptBlock {
    std::size_t block;
    std::uint32_t crc;
  };
  /// A vertex block's box in floats rounded outward (the test it serves only
  /// rules triangles out), and its CRC.
  struct VertexBlock {
    std::array<float, 4> box;  // x0, y0, x1, y1
    std::uint32_t crc;
    static VertexBlock of(const BlockEntry& e) {
      return {
          {roundedDown(e.box.x0), roundedDown(e.box.y0), roundedUp(e.box.x1), roundedUp(e.box.y1)},
          e.crc};
    }
  };
  std::size_t perBlock = 0;
  std::uint32_t frameCrc = 0;
  std::array<std::vector<KeptBlock>, 3> keptBlocks;  // of the triangles and the edges
  std::vector<std::size_t> vertexRegionBlocks;
  /// The vertex blocks by groups of vertexGroupBlocks, each read when first
  /// asked for (readVertexGroup; version 3) or all at once (version 2).
  std::size_t vertexGroupBlocks = 1;
  std::vector<std::vector<VertexBlock>> vertexGroups;
  std::function<std::vector<VertexBlock>(std::size_t group)> readVertexGroup;

  const VertexBlock& vertexBlock(std::size_t b) {
    const std::size_t g = b / vertexGroupBlocks;
    if (vertexGroups[g].empty()) vertexGroups[g] = readVertexGroup(g);
    return vertexGroups[g][b % vertexGroupBlocks];
  }
};

BlockEntry blockEntryAt(const std::uint8_t* p) {
  return {{getLe<double>(p), getLe<double>(p + 8), getLe<double>(p + 16), getLe<double>(p + 24)},
          getLe<std::uint32_t>(p + 32)};
}

/// Reads the index's head (k and the frame's CRC) into `index`.
void readIndexHead(PayloadReader& r, PartIndex& index) {
  index.perBlock = r.get<std::uint32_t>("block index");
  if (index.perBlock == 0) r.corrupt("the block index has blocks of 0 records");
  index.frameCrc = r.get<std::uint32_t>("block index");
}

/// Reads a section's block count, which must be that of its records.
std::size_t readBlockCount(PayloadReader& r, std::size_t section, std::size_t records,
                           std::size_t perBlock) {
  const std::size_t blocks = r.getCount(kBlockEntrySize, "block index");
  if (blocks != blockCount(records, perBlock))
    r.corrupt("the block index lists " + std::to_string(blocks) + " " +
              kBlockSectionNames[section] + " blocks for " + std::to_string(records) + " records");
  return blocks;
}

/// A version 2 block index, read through once, its CRC following, and given
/// back to the kernel as it goes (at 10⁹ vertices it is about 105 MB): every
/// vertex block is kept, and the triangle and edge blocks that meet the region.
PartIndex readWholeIndex(const MappedFile& file, PayloadReader& r,
                         const std::array<std::size_t, 3>& records, const tiles::Rect& region,
                         const tiles::Rect& vertexRegion, std::uint64_t& bytesRead) {
  PartIndex index;
  const std::uint8_t* from = r.position();
  std::uint32_t indexCrc = 0;
  const std::uint8_t* crcUpTo = from;
  const auto followIndex = [&] {
    indexCrc = crc32({crcUpTo, static_cast<std::size_t>(r.position() - crcUpTo)}, indexCrc);
    crcUpTo = r.position();
    file.release(crcUpTo);
  };
  readIndexHead(r, index);
  constexpr std::size_t kIndexWindow = std::size_t{8} << 20;
  for (std::size_t s = 0; s < 3; ++s) {
    const std::size_t blocks = readBlockCount(r, s, records[s], index.perBlock);
    std::vector<PartIndex::VertexBlock> vertexBlocks;
    if (s == kVertexBlocks) vertexBlocks.reserve(blocks);
    for (std::size_t b = 0; b < blocks; ++b) {
      const BlockEntry entry = blockEntryAt(r.skip(1, kBlockEntrySize, "block index"));
      if (s == kVertexBlocks) {
        vertexBlocks.push_back(PartIndex::VertexBlock::of(entry));
        if (entry.box.overlaps(vertexRegion)) index.vertexRegionBlocks.push_back(b);
      } else if (entry.box.overlaps(region)) {
        index.keptBlocks[s].push_back({b, entry.crc});
      }
      if (static_cast<std::size_t>(r.position() - crcUpTo) >= kIndexWindow) followIndex();
    }
    if (s == kVertexBlocks) {
      index.vertexGroupBlocks = std::max<std::size_t>(1, blocks);
      index.vertexGroups.push_back(std::move(vertexBlocks));
    }
  }
  followIndex();
  const std::size_t indexSize = static_cast<std::size_t>(r.position() - from);
  if (r.get<std::uint32_t>("block index") != indexCrc)
    r.corrupt("the block index checksum does not match");
  if (r.remaining() != 0) r.corrupt("bytes left over after the block index");
  bytesRead += indexSize + 4;
  return index;
}

/// A version 3 block index through its summary: the summary is read and
/// checked, then only the groups of entries whose boxes meet the regions,
/// each checked against its CRC in the summary, and any other group of
/// vertex blocks when one of its blocks is asked for.
PartIndex readIndexSummary(const MappedFile& file, PayloadReader& r,
                           const std::array<std::size_t, 3>& records, const tiles::Rect& region,
                           const tiles::Rect& vertexRegion, std::uint64_t& bytesRead) {
  PartIndex index;
  const std::uint8_t* head = r.position();
  readIndexHead(r, index);
  std::array<std::size_t, 3> blocks{};
  std::array<const std::uint8_t*, 3> entries{};
  for (std::size_t s = 0; s < 3; ++s) {
    blocks[s] = readBlockCount(r, s, records[s], index.perBlock);
    entries[s] = r.skip(blocks[s], kBlockEntrySize, "block index");
  }
  const std::uint8_t* summary = r.position();
  const std::size_t perGroup = r.get<std::uint32_t>("block index summary");
  if (perGroup == 0) r.corrupt("the block index summary has groups of 0 entries");
  std::array<const std::uint8_t*, 3> groups{};
  for (std::size_t s = 0; s < 3; ++s) {
    const std::size_t n = r.getCount(kBlockEntrySize, "block index summary");
    if (n != blockCount(blocks[s], perGroup))
      r.corrupt("the block index summary lists " + std::to_string(n) + " " + kBlockSectionNames[s] +
                " groups for " + std::to_string(blocks[s]) + " blocks");
    groups[s] = r.skip(n, kBlockEntrySize, "block index summary");
  }
  const std::size_t summarySize = static_cast<std::size_t>(r.position() - summary);
  if (r.get<std::uint32_t>("block index summary") !=
      crc32({summary, summarySize}, crc32({head, 8})))
    r.corrupt("the block index summary checksum does not match");
  (void)r.get<std::uint32_t>("block index");  // the whole index's CRC: readTinFile checks it
  if (r.remaining() != 0) r.corrupt("bytes left over after the block index");
  file.release(r.position());  // what the frame and the summary brought in
  bytesRead += 8 + 3 * 8 + summarySize + 4 + 4;

  // Group g of section s: its box, and its entries once checked.
  const auto groupBox = [&groups](std::size_t s, std::size_t g) {
    return blockEntryAt(groups[s] + kBlockEntrySize * g).box;
  };
  // The entries are read from the file, not through the mapping, so that
  // they do not stay in the process's memory: their copies do, and only
  // the vertex groups' are kept.
  const auto readGroup = [&file, &r, &bytesRead, blocks, entries, groups, perGroup](std::size_t s,
                                                                                    std::size_t g) {
    const std::size_t first = g * perGroup;
    std::vector<std::uint8_t> bytes(kBlockEntrySize * std::min(perGroup, blocks[s] - first));
    if (!file.copy(entries[s] + kBlockEntrySize * first, bytes.size(), bytes.data()))
      r.corrupt("the block index cannot be read");
    if (crc32(bytes) != blockEntryAt(groups[s] + kBlockEntrySize * g).crc)
      r.corrupt(std::string("the block index's ") + kBlockSectionNames[s] + " group " +
                std::to_string(g) + " does not match its checksum");
    bytesRead += bytes.size();
    std::vector<BlockEntry> out;
    out.reserve(bytes.size() / kBlockEntrySize);
    for (std::size_t i = 0; i < bytes.size(); i += kBlockEntrySize)
      out.push_back(blockEntryAt(bytes.data() + i));
    return out;
  };
  index.vertexGroupBlocks = perGroup;
  index.vertexGroups.resize(blockCount(blocks[kVertexBlocks], perGroup));
  index.readVertexGroup = [readGroup](std::size_t g) {
    std::vector<PartIndex::VertexBlock> out;
    for (const BlockEntry& e : readGroup(kVertexBlocks, g))
      out.push_back(PartIndex::VertexBlock::of(e));
    return out;
  };
  for (std::size_t g = 0; g < index.vertexGroups.size(); ++g) {
    if (!groupBox(kVertexBlocks, g).overlaps(vertexRegion)) continue;
    index.vertexGroups[g] = index.readVertexGroup(g);
    for (std::size_t i = 0; i < index.vertexGroups[g].size(); ++i) {
      const std::array<float, 4>& b = index.vertexGroups[g][i].box;
      if (tiles::Rect{b[0], b[1], b[2], b[3]}.overlaps(vertexRegion))
        index.vertexRegionBlocks.push_back(g * perGroup + i);
    }
  }
  for (const BlockSection s : {kTriangleBlocks, kEdgeBlocks}) {
    for (std::size_t g = 0; g < blockCount(blocks[s], perGroup); ++g) {
      if (!groupBox(s, g).overlaps(region)) continue;
      const std::vector<BlockEntry> group = readGroup(s, g);
      for (std::size_t i = 0; i < group.size(); ++i)
        if (group[i].box.overlaps(region))
          index.keptBlocks[s].push_back({g * perGroup + i, group[i].crc});
    }
  }
  return index;
}

/// A part of a file of version 2 on, through its block index: the frame
/// (CRS, counts, features) is read whole and checked, and what the part needs
/// of the index (PartIndex), then only the blocks the part needs, each
/// checked against its CRC.
TinPart readPartByBlocks(const MappedFile& file, const CheckedPayload& payload,
                         const std::string& name, const tiles::Rect& region,
                         const tiles::Rect& vertexRegion) {
  PayloadReader r(payload.bytes.data(), payload.bytes.size(), name);
  TinPart part;
  TinData& tin = part.tin;
  // The frame's pieces, each with its CRC continued from the last.
  std::uint32_t frameCrc = 0;
  const auto frameFrom = [&](const std::uint8_t* from) {
    const std::span<const std::uint8_t> piece(from, static_cast<std::size_t>(r.position() - from));
    frameCrc = crc32(piece, frameCrc);
    part.bytesRead += piece.size();
  };
  const std::uint8_t* from = r.position();
  tin.crs = r.getString("CRS text");
  const std::size_t nv = r.getCount(24, "vertex");
  frameFrom(from);
  const std::uint8_t* vertexRecords = r.skip(nv, 24, "vertices");
  from = r.position();
  const std::size_t nt = r.getCount(12, "triangle");
  frameFrom(from);
  const std::uint8_t* triangleRecords = r.skip(nt, 12, "triangles");
  from = r.position();
  tin.features.resize(r.getCount(5, "feature"));
  for (auto& f : tin.features) {
    f.kind = static_cast<FeatureKind>(r.get<std::uint8_t>("features"));
    f.source = r.getString("features");
  }
  const std::size_t ne = r.getCount(12, "constrained edge");
  frameFrom(from);
  const std::uint8_t* edgeRecords = r.skip(ne, 12, "constrained edges");

  const std::array<std::size_t, 3> records{nv, nt, ne};
  PartIndex index = payload.version < 3
                        ? readWholeIndex(file, r, records, region, vertexRegion, part.bytesRead)
                        : readIndexSummary(file, r, records, region, vertexRegion, part.bytesRead);
  if (frameCrc != index.frameCrc)
    r.corrupt("the checksum of the CRS, the counts and the features does not match");
  part.bytesRead += kTinHeaderSize;
  const std::size_t perBlock = index.perBlock;

  const auto checkBlock = [&](BlockSection s, std::size_t b, std::uint32_t crc,
                              const std::uint8_t* section, std::size_t recordSize) {
    const std::size_t first = b * perBlock;
    const std::span<const std::uint8_t> bytes(section + first * recordSize,
                                              std::min(perBlock, records[s] - first) * recordSize);
    if (crc32(bytes) != crc)
      r.corrupt(std::string(kBlockSectionNames[s]) + " block " + std::to_string(b) +
                " does not match its checksum");
    part.bytesRead += bytes.size();
  };
  std::vector<char> vertexBlockChecked(blockCount(nv, perBlock), 0);
  const auto vertexAt = [&](std::uint32_t v) {
    const std::size_t b = v / perBlock;
    if (!vertexBlockChecked[b]) {
      checkBlock(kVertexBlocks, b, index.vertexBlock(b).crc, vertexRecords, 24);
      vertexBlockChecked[b] = 1;
    }
    const std::uint8_t* p = vertexRecords + std::size_t{24} * v;
    return Point3{getLe<double>(p), getLe<double>(p + 8), getLe<double>(p + 16)};
  };
  const auto eachKept = [&](BlockSection s, auto&& each) {
    for (const PartIndex::KeptBlock& k : index.keptBlocks[s])
      each(k.block, k.crc, k.block * perBlock, std::min(records[s], (k.block + 1) * perBlock));
  };

  // Whether records at these vertices may meet the region: the boxes of
  // their vertices' blocks do (they hold their boxes), asked before the
  // vertices' own blocks are read.
  const auto mayMeet = [&](std::initializer_list<std::uint32_t> vertices) {
    tiles::Rect box{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (const std::uint32_t v : vertices) {
      const std::array<float, 4>& b = index.vertexBlock(v / perBlock).box;
      include(box, {b[0], b[1], 0.0});
      include(box, {b[2], b[3], 0.0});
    }
    return box.overlaps(region);
  };

  std::vector<std::uint32_t> keep;
  eachKept(
      kTriangleBlocks, [&](std::size_t b, std::uint32_t crc, std::size_t first, std::size_t end) {
        checkBlock(kTriangleBlocks, b, crc, triangleRecords, 12);
        for (std::size_t k = first; k < end; ++k) {
          const std::uint8_t* p = triangleRecords + 12 * k;
          const std::array<std::uint32_t, 3> t{getLe<std::uint32_t>(p), getLe<std::uint32_t>(p + 4),
                                               getLe<std::uint32_t>(p + 8)};
          if (t[0] >= nv || t[1] >= nv || t[2] >= nv)
            r.corrupt("triangle " + std::to_string(k) + " refers to a vertex beyond the " +
                      std::to_string(nv) + " vertices");
          if (mayMeet({t[0], t[1], t[2]}) &&
              meetsRegion(region, {vertexAt(t[0]), vertexAt(t[1]), vertexAt(t[2])})) {
            tin.triangles.push_back(t);
            keep.insert(keep.end(), t.begin(), t.end());
          }
        }
      });
  eachKept(kEdgeBlocks, [&](std::size_t b, std::uint32_t crc, std::size_t first, std::size_t end) {
    checkBlock(kEdgeBlocks, b, crc, edgeRecords, 12);
    for (std::size_t k = first; k < end; ++k) {
      const std::uint8_t* p = edgeRecords + 12 * k;
      const TinData::ConstrainedEdge e{getLe<std::uint32_t>(p), getLe<std::uint32_t>(p + 4),
                                       getLe<std::uint32_t>(p + 8)};
      if (e.a >= nv || e.b >= nv)
        r.corrupt("constrained edge " + std::to_string(k) + " refers to a vertex out of range");
      if (mayMeet({e.a, e.b}) && meetsRegion(region, {vertexAt(e.a), vertexAt(e.b)})) {
        tin.constrainedEdges.push_back(e);
        keep.push_back(e.a);
        keep.push_back(e.b);
      }
    }
  });
  for (const std::size_t b : index.vertexRegionBlocks) {
    for (std::size_t v = b * perBlock; v < std::min(nv, (b + 1) * perBlock); ++v)
      if (vertexRegion.contains(vertexAt(static_cast<std::uint32_t>(v)).xy()))
        keep.push_back(static_cast<std::uint32_t>(v));
  }
  renumberPart(tin, std::move(keep), vertexAt);
  part.vertices = nv;
  part.triangles = nt;
  return part;
}

}  // namespace

TinData readTinFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  requireReadableFile(path, name);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw inputError("cannot open the .tin file for reading", fileLocation(name),
                     "check permissions");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw inputError("cannot read the .tin file: " + ec.message(), fileLocation(name));
  std::string bytes(size, '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(size)))
    throw inputError("cannot read the .tin file", fileLocation(name), "check permissions");
  return decodeTin(bytes, name);
}

TinFileHeader readTinFileHeader(const std::filesystem::path& path) {
  const std::string name = path.string();
  requireReadableFile(path, name);
  const MappedFile file(path, name);
  const CheckedPayload payload = checkedPayload(file.bytes(), name);
  PayloadReader r(payload.bytes.data(), payload.bytes.size(), name);
  return {payload.version, payload.fileCrc, r.getString("CRS text")};
}

TinFileHeader requireCurrentTinFormat(const std::filesystem::path& path) {
  TinFileHeader header = readTinFileHeader(path);
  if (header.version < kTinFormatVersion)
    throw inputError(".tin format version " + std::to_string(header.version) +
                         " is older than the format " + std::to_string(kTinFormatVersion) +
                         " the shards of a tiling job read their parts of",
                     fileLocation(path.string()),
                     "rewrite it in this format with `tinsmith export " + path.string() +
                         " --format tin -o NEW.tin`, then tile NEW.tin in shards");
  return header;
}

TinPart readTinFilePart(const std::filesystem::path& path, const tiles::Rect& region,
                        const tiles::Rect& vertexRegion) {
  const std::string name = path.string();
  requireReadableFile(path, name);
  const MappedFile file(path, name);
  const CheckedPayload payload = checkedPayload(file.bytes(), name);
  TinPart part = payload.version < 2 ? readPartThrough(file, payload, name, region, vertexRegion)
                                     : readPartByBlocks(file, payload, name, region, vertexRegion);
  part.fileCrc = payload.fileCrc;
  checkTinContract(part.tin, name, false);
  return part;
}

}  // namespace tinsmith::ingest
