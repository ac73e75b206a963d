// A quantized-mesh-1.0 reader for the tests, written from the format's text
// (github.com/CesiumGS/quantized-mesh) as a client reads it, not from our
// encoder: the header's fields one by one, zig-zag deltas summed, the
// high-water mark undone, 16- or 32-bit indices past 65 536 vertices with the
// padding before them, the four edge lists, then every extension by id and
// length. Any byte past the end or left over fails the test that reads it.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace tinsmith::test {

struct DecodedQuantizedMesh {
  std::array<double, 3> centre{}, sphereCentre{}, horizonOcclusion{};
  float minHeight = 0, maxHeight = 0;
  double sphereRadius = 0;
  std::vector<std::uint16_t> u, v, height;
  std::vector<std::uint32_t> indices;               ///< three a triangle
  std::array<std::vector<std::uint32_t>, 4> edges;  ///< west, south, east, north
  bool wideIndices = false;
  std::map<int, std::string> extensions;  ///< by id: the extension's bytes
  bool ok = false;                        ///< read to the end exactly
};

inline DecodedQuantizedMesh decodeQuantizedMesh(std::string_view bytes) {
  DecodedQuantizedMesh d;
  std::size_t at = 0;
  bool fine = true;
  auto read = [&](auto& value) {
    if (at + sizeof(value) > bytes.size()) {
      fine = false;
      return;
    }
    std::memcpy(&value, bytes.data() + at, sizeof(value));
    at += sizeof(value);
  };
  for (double& x : d.centre) read(x);
  read(d.minHeight);
  read(d.maxHeight);
  for (double& x : d.sphereCentre) read(x);
  read(d.sphereRadius);
  for (double& x : d.horizonOcclusion) read(x);
  EXPECT_EQ(at, 88u) << "the header is 88 bytes";
  std::uint32_t n = 0;
  read(n);
  if (!fine) return d;
  for (auto* values : {&d.u, &d.v, &d.height}) {
    values->resize(n);
    int value = 0;
    for (std::uint32_t i = 0; i < n && fine; ++i) {
      std::uint16_t code = 0;
      read(code);
      value += (code >> 1) ^ (-(code & 1));
      (*values)[i] = static_cast<std::uint16_t>(value);
    }
  }
  d.wideIndices = n > 65536;
  const std::size_t width = d.wideIndices ? 4 : 2;
  while (at % width != 0) ++at;
  auto readIndex = [&]() -> std::uint32_t {
    if (d.wideIndices) {
      std::uint32_t i = 0;
      read(i);
      return i;
    }
    std::uint16_t i = 0;
    read(i);
    return i;
  };
  std::uint32_t triangles = 0;
  read(triangles);
  std::uint32_t highest = 0;
  for (std::uint64_t k = 0; k < 3ULL * triangles && fine; ++k) {
    const std::uint32_t code = readIndex();
    d.indices.push_back(highest - code);
    if (code == 0) ++highest;
  }
  for (auto& edge : d.edges) {
    std::uint32_t count = 0;
    read(count);
    for (std::uint32_t k = 0; k < count && fine; ++k) edge.push_back(readIndex());
  }
  while (fine && at < bytes.size()) {
    std::uint8_t id = 0;
    std::uint32_t length = 0;
    read(id);
    read(length);
    if (!fine || at + length > bytes.size()) {
      fine = false;
      break;
    }
    d.extensions[id] = std::string(bytes.substr(at, length));
    at += length;
  }
  d.ok = fine && at == bytes.size();
  return d;
}

}  // namespace tinsmith::test
