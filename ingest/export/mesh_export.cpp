#include "ingest/export/mesh_export.hpp"

#include <charconv>
#include <cstdio>

#include "ingest/base/atomic_file.hpp"

namespace tinsmith::ingest {

namespace {

// Single-line text for a header comment: a WKT CRS may span lines.
std::string oneLine(const std::string& text) {
  std::string out;
  for (char c : text) out += (c == '\n' || c == '\r') ? ' ' : c;
  return out.empty() ? "unknown" : out;
}

void appendIndex(std::string& out, std::uint64_t value) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, r.ptr);
}

// "x y z\n" at full precision.
void appendXyzLine(std::string& buf, const Point3& v) {
  appendG17(buf, v.x);
  buf += ' ';
  appendG17(buf, v.y);
  buf += ' ';
  appendG17(buf, v.z);
  buf += '\n';
}

// "a b c\n" with each index offset by `base`.
void appendIndexLine(std::string& buf, const TinData::Triangle& t, std::uint64_t base) {
  appendIndex(buf, std::uint64_t{t[0]} + base);
  buf += ' ';
  appendIndex(buf, std::uint64_t{t[1]} + base);
  buf += ' ';
  appendIndex(buf, std::uint64_t{t[2]} + base);
  buf += '\n';
}

// Streams text produced in chunks, so a million-vertex export needs no
// file-sized string in memory.
template <class Emit>
void produceObj(const TinData& tin, Emit&& emit) {
  std::string buf;
  buf += "# tinsmith TIN\n# crs: " + oneLine(tin.crs) + "\n# " +
         std::to_string(tin.vertices.size()) + " vertices, " +
         std::to_string(tin.triangles.size()) + " triangles\n";
  for (const auto& v : tin.vertices) {
    buf += "v ";
    appendXyzLine(buf, v);
    if (buf.size() > (1 << 16)) emit(buf);
  }
  for (const auto& t : tin.triangles) {
    buf += "f ";
    appendIndexLine(buf, t, 1);  // OBJ indices are 1-based
    if (buf.size() > (1 << 16)) emit(buf);
  }
  emit(buf);
}

template <class Emit>
void producePly(const TinData& tin, Emit&& emit) {
  std::string buf =
      "ply\nformat ascii 1.0\ncomment tinsmith TIN\ncomment crs " + oneLine(tin.crs) +
      "\nelement vertex " + std::to_string(tin.vertices.size()) +
      "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
      std::to_string(tin.triangles.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  for (const auto& v : tin.vertices) {
    appendXyzLine(buf, v);
    if (buf.size() > (1 << 16)) emit(buf);
  }
  for (const auto& t : tin.triangles) {
    buf += "3 ";
    appendIndexLine(buf, t, 0);
    if (buf.size() > (1 << 16)) emit(buf);
  }
  emit(buf);
}

}  // namespace

void appendG17(std::string& out, double value) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 17);
  out.append(buf, r.ptr);
}

std::string objText(const TinData& tin) {
  std::string out;
  produceObj(tin, [&out](std::string& chunk) {
    out += chunk;
    chunk.clear();
  });
  return out;
}

std::string plyText(const TinData& tin) {
  std::string out;
  producePly(tin, [&out](std::string& chunk) {
    out += chunk;
    chunk.clear();
  });
  return out;
}

void writeObj(const std::filesystem::path& path, const TinData& tin) {
  AtomicFile file(path);
  produceObj(tin, [&file](std::string& chunk) {
    file.write(chunk);
    chunk.clear();
  });
  file.commit();
}

void writePly(const std::filesystem::path& path, const TinData& tin) {
  AtomicFile file(path);
  producePly(tin, [&file](std::string& chunk) {
    file.write(chunk);
    chunk.clear();
  });
  file.commit();
}

}  // namespace tinsmith::ingest
