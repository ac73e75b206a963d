#include "ingest/tinfile/tin_file.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <future>
#include <tuple>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

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
    for (std::uint32_t i = 0; i < 256; ++i) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFFu];
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
  for (std::size_t i = 0; i < sizeof(T); ++i) bits |= static_cast<U>(static_cast<U>(in[i]) << (8 * i));
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
  [[nodiscard]] const std::vector<TinData::ConstrainedEdge>& constrainedEdges() const { return edges; }
};

template <class Source>
std::uint64_t payloadSize(const Source& tin) {
  std::uint64_t size = 4 + tin.crs().size();
  size += 8 + 24ull * tin.points().size();
  size += 8 + 12ull * tin.triangleCount();
  size += 8;
  for (const auto& f : tin.features()) size += 1 + 4 + f.source.size();
  size += 8 + 12ull * tin.constrainedEdges().size();
  return size;
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
      auto crc = std::async(std::launch::async,
                            [data, size, before = crc_] { return crc32({data, size}, before); });
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

template <class Source, class Sink>
std::uint32_t writePayload(const Source& tin, Sink& sink, bool overlapChecksum = false) {
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
  w.flush();
  return w.crc();
}

std::array<std::uint8_t, kTinHeaderSize> makeHeader(std::uint64_t payload, std::uint32_t crc) {
  std::array<std::uint8_t, kTinHeaderSize> h{};
  std::memcpy(h.data(), kMagic.data(), kMagic.size());
  putLe(h.data() + 8, kTinFormatVersion);
  putLe(h.data() + 12, std::uint32_t{0});
  putLe(h.data() + 16, payload);
  putLe(h.data() + 24, crc);
  putLe(h.data() + 28, crc32({h.data(), 28}));
  return h;
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
  [[nodiscard]] std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  [[nodiscard]] const std::uint8_t* position() const { return p_; }
  [[noreturn]] void corrupt(const std::string& what) const {
    throw inputError("corrupt .tin file: " + what, fileLocation(name_),
                     "the file is damaged; write it again with `tinsmith tin`");
  }

 private:
  void need(std::size_t n, const char* what) const {
    if (static_cast<std::size_t>(end_ - p_) < n)
      corrupt(std::string("it ends inside the ") + what);
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

std::string_view featureKindName(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::Other: return "other";
    case FeatureKind::SpotHeight: return "spot-height";
    case FeatureKind::Contour: return "contour";
    case FeatureKind::Road: return "road";
    case FeatureKind::River: return "river";
    case FeatureKind::Lake: return "lake";
    case FeatureKind::Boundary: return "boundary";
    case FeatureKind::Hole: return "hole";
    case FeatureKind::Raster: return "raster";
    case FeatureKind::BreakLine: return "breakline";
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
    throw inputError("corrupt .tin file: " + what, fileLocation(name),
                     "the file is damaged; write it again with `tinsmith tin`");
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
      bad("triangle " + std::to_string(t) + " refers to a vertex beyond the " +
          std::to_string(nv) + " vertices");
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

std::string encodeTin(const TinData& tin) {
  checkTinContract(tin, "(memory)", true);
  std::string out;
  const TinSource source{{tin}};
  const std::uint64_t size = payloadSize(source);
  out.reserve(kTinHeaderSize + size);
  out.resize(kTinHeaderSize);
  auto sink = [&out](const std::uint8_t* data, std::size_t n) {
    out.append(reinterpret_cast<const char*>(data), n);
  };
  const std::uint32_t crc = writePayload(source, sink);
  const auto header = makeHeader(size, crc);
  std::memcpy(out.data(), header.data(), header.size());
  return out;
}

namespace {

template <class Source>
void writeFile(const std::filesystem::path& path, const Source& tin, unsigned threads) {
  checkContract(tin, path.string(), true);
  AtomicFile file(path);
  const std::uint64_t size = payloadSize(tin);
  const auto placeholder = makeHeader(size, 0);
  file.write(placeholder.data(), placeholder.size());
  auto sink = [&file](const std::uint8_t* data, std::size_t n) { file.write(data, n); };
  const std::uint32_t crc = writePayload(tin, sink, resolveThreads(threads) > 1);
  const auto header = makeHeader(size, crc);
  file.writeAt(0, header.data(), header.size());
  file.commit();
}

}  // namespace

void writeTinFile(const std::filesystem::path& path, const TinData& tin, unsigned threads) {
  writeFile(path, TinSource{{tin}}, threads);
}

void writeTinFile(const std::filesystem::path& path, const Mesh& mesh, unsigned threads) {
  writeFile(path, MeshSource(mesh), threads);
}

namespace {

/// Checks the header of a .tin file's bytes (all of them): the payload's span
/// after it.
std::span<const std::uint8_t> checkedPayload(std::span<const std::uint8_t> bytes,
                                             const std::string& name) {
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
    throw inputError("corrupt .tin file: the header checksum does not match", fileLocation(name),
                     "the file is damaged; write it again with `tinsmith tin`");
  if (version > kTinFormatVersion)
    throw inputError(".tin format version " + std::to_string(version) +
                         " is newer than this tinsmith reads (version " +
                         std::to_string(kTinFormatVersion) + ")",
                     fileLocation(name), "use a newer tinsmith to read it");
  if (version == 0) throw inputError("corrupt .tin file: format version 0", fileLocation(name));
  const auto payload = getLe<std::uint64_t>(data + 16);
  const std::uint64_t have = bytes.size() - kTinHeaderSize;
  if (have < payload)
    throw inputError("truncated .tin file: the header announces " + std::to_string(payload) +
                         " payload bytes but only " + std::to_string(have) + " follow",
                     fileLocation(name),
                     "the file is incomplete; write it again with `tinsmith tin`");
  if (have > payload)
    throw inputError("corrupt .tin file: " + std::to_string(have - payload) +
                         " unexpected bytes after the payload",
                     fileLocation(name), "the file is damaged; write it again with `tinsmith tin`");
  return {data + kTinHeaderSize, payload};
}

[[noreturn]] void payloadChecksumMismatch(const std::string& name) {
  throw inputError("corrupt .tin file: the payload checksum does not match", fileLocation(name),
                   "the file is damaged; write it again with `tinsmith tin`");
}

/// Reads a payload's sections into `tin`: all of it, or with `region` every
/// vertex and feature, the triangles whose boxes meet it and the constrained
/// edges at their vertices. `pace()` runs every 65 536 records of the large
/// sections. Returns the file's triangle count.
template <class Pace>
std::size_t readSections(PayloadReader& r, TinData& tin, const tiles::Rect* region, Pace&& pace) {
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
  std::vector<char> used(region ? nv : 0, 0);
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
    const std::array<Point3, 3> corners{tin.vertices[t[0]], tin.vertices[t[1]],
                                        tin.vertices[t[2]]};
    if (tiles::boundsOf(corners).overlaps(*region)) {
      tin.triangles.push_back(t);
      used[t[0]] = used[t[1]] = used[t[2]] = 1;
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
    if (region && (e.a >= nv || e.b >= nv))
      r.corrupt("constrained edge " + std::to_string(k) + " refers to a vertex out of range");
    if (!region || used[e.a] || used[e.b]) tin.constrainedEdges.push_back(e);
  }
  if (r.remaining() != 0) r.corrupt("bytes left over after the last section");
  return triangles;
}

}  // namespace

TinData decodeTin(std::string_view bytes, const std::string& name) {
  const std::span<const std::uint8_t> body =
      checkedPayload({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, name);
  if (crc32(body) != getLe<std::uint32_t>(body.data() - kTinHeaderSize + 24))
    payloadChecksumMismatch(name);

  PayloadReader r(body.data(), body.size(), name);
  TinData tin;
  readSections(r, tin, nullptr, [] {});
  checkTinContract(tin, name, false);
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
      ::madvise(m, size_, MADV_SEQUENTIAL);
    }
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile() {
    if (data_) ::munmap(const_cast<std::uint8_t*>(data_), size_);
    ::close(fd_);
  }
  [[nodiscard]] std::span<const std::uint8_t> bytes() const { return {data_, size_}; }
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

TinPart readTinFilePart(const std::filesystem::path& path, const tiles::Rect& region) {
  const std::string name = path.string();
  requireReadableFile(path, name);
  const MappedFile file(path, name);
  const std::span<const std::uint8_t> body = checkedPayload(file.bytes(), name);
  const std::uint8_t* header = file.bytes().data();
  // The checksums follow the reader a window at a time, and what they have
  // passed is given back: the file is never all in memory.
  std::uint32_t payloadCrc = 0;
  std::uint32_t fileCrc = crc32({header, kTinHeaderSize});
  const std::uint8_t* checked = body.data();
  const auto checkUpTo = [&](const std::uint8_t* to) {
    const std::span<const std::uint8_t> chunk(checked, static_cast<std::size_t>(to - checked));
    payloadCrc = crc32(chunk, payloadCrc);
    fileCrc = crc32(chunk, fileCrc);
    checked = to;
    file.release(to);
  };
  constexpr std::ptrdiff_t kWindow = std::ptrdiff_t{8} << 20;
  PayloadReader r(body.data(), body.size(), name);
  const auto keepUp = [&] {
    if (r.position() - checked >= kWindow) checkUpTo(r.position());
  };

  TinPart part;
  part.triangles = readSections(r, part.tin, &region, keepUp);
  checkUpTo(body.data() + body.size());
  if (payloadCrc != getLe<std::uint32_t>(header + 24)) payloadChecksumMismatch(name);
  part.fileCrc = fileCrc;
  checkTinContract(part.tin, name, false);
  return part;
}

}  // namespace tinsmith::ingest
