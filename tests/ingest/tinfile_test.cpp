// The .tin file: exact round trips, deterministic bytes, and every kind of
// damage refused with an error that names the file — and no partial output.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "core/base/error.hpp"
#include "core/mesh/mesh.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_summary.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

TinData sampleTin() {
  TinData tin;
  tin.crs = "EPSG:26912";
  // UTM-sized coordinates with sub-millimetre detail and awkward doubles.
  tin.vertices = {{431000.125, 4512000.0000001, 1580.5},
                  {431010.0, 4512000.0, 1581.0 / 3.0},
                  {431010.0, 4512010.0, -0.0},
                  {431000.0, 4512010.0, std::nextafter(2000.0, 3000.0)},
                  {431005.0, 4512005.0, 1e-300}};
  tin.triangles = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  tin.features = {{FeatureKind::Road, "road.geojson, feature 0"},
                  {FeatureKind::River, "streams.geojson, feature 3 — ünïcode"}};
  tin.constrainedEdges = {{0, 4, 0}, {2, 4, 0}, {2, 4, 1}};
  return tin;
}

void expectSame(const TinData& a, const TinData& b) {
  EXPECT_EQ(a.crs, b.crs);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    // Bit-for-bit, including the sign of zero.
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].x),
              std::bit_cast<std::uint64_t>(b.vertices[i].x));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].y),
              std::bit_cast<std::uint64_t>(b.vertices[i].y));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].z),
              std::bit_cast<std::uint64_t>(b.vertices[i].z));
  }
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.constrainedEdges, b.constrainedEdges);
  ASSERT_EQ(a.features.size(), b.features.size());
  for (std::size_t i = 0; i < a.features.size(); ++i) {
    EXPECT_EQ(a.features[i].kind, b.features[i].kind);
    EXPECT_EQ(a.features[i].source, b.features[i].source);
  }
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TinFile, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32(std::string_view("123456789")), 0xCBF43926u);
  EXPECT_EQ(crc32(std::string_view("")), 0u);
  // Continuing a CRC equals computing it in one go.
  EXPECT_EQ(crc32(std::string_view("6789"), crc32(std::string_view("12345"))), 0xCBF43926u);
}

TEST(TinFile, RoundTripsExactlyThroughAFile) {
  const auto dir = test::scratchDir("tinfile-roundtrip");
  const TinData tin = sampleTin();
  writeTinFile(dir / "a.tin", tin);
  expectSame(readTinFile(dir / "a.tin"), tin);
  // No temp file is left next to the output.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
}

TEST(TinFile, EmptyTinRoundTrips) {
  const TinData empty;
  expectSame(decodeTin(encodeTin(empty), "empty"), empty);
}

TEST(TinFile, BytesAreDeterministicAndMatchTheDocumentedLayout) {
  const TinData tin = sampleTin();
  const auto dir = test::scratchDir("tinfile-layout");
  writeTinFile(dir / "a.tin", tin);
  writeTinFile(dir / "b.tin", tin);
  const std::string a = test::readFile(dir / "a.tin");
  EXPECT_EQ(a, test::readFile(dir / "b.tin"));
  EXPECT_EQ(a, encodeTin(tin));
  ASSERT_GE(a.size(), kTinHeaderSize);
  EXPECT_EQ(a.substr(0, 8), std::string("\x89TIN\r\n\x1a\n", 8));
  EXPECT_EQ(static_cast<unsigned char>(a[8]), kTinFormatVersion);  // little-endian u32
  const std::uint64_t expectedPayload = 4 + tin.crs.size() + 8 + 24 * 5 + 8 + 12 * 4 + 8 +
                                        (5 + tin.features[0].source.size()) +
                                        (5 + tin.features[1].source.size()) + 8 + 12 * 3 +
                                        // the block index: one block a section,
                                        4 + 4 + 3 * (8 + 36) +
                                        // its summary: one group a section
                                        4 + 3 * (8 + 36) + 4 + 4;
  EXPECT_EQ(a.size(), kTinHeaderSize + expectedPayload);
  std::uint32_t storedCrc = 0;
  for (int i = 3; i >= 0; --i) storedCrc = (storedCrc << 8) | static_cast<unsigned char>(a[24 + i]);
  EXPECT_EQ(storedCrc, crc32(std::string_view(a).substr(kTinHeaderSize)));
  // The first payload field is the CRS length, little-endian.
  EXPECT_EQ(static_cast<unsigned char>(a[32]), tin.crs.size());
  EXPECT_EQ(a.substr(36, tin.crs.size()), tin.crs);
}

TEST(TinFile, TheChecksumOnASecondThreadWritesTheSameBytes) {
  // Arrays large enough (over 4 MiB) for their checksum to run beside the write.
  TinData tin = sampleTin();
  const std::uint32_t n = 250000;
  for (std::uint32_t i = 0; i < n; ++i)
    tin.vertices.push_back({431000.0 + i % 500, 4512000.0 + i / 500, 1500.0 + (i % 97) / 7.0});
  for (std::uint32_t i = 0; i + 2 < n; i += 3) tin.triangles.push_back({5 + i, 6 + i, 7 + i});
  const auto dir = test::scratchDir("tinfile-threads");
  writeTinFile(dir / "one.tin", tin, 1);
  writeTinFile(dir / "two.tin", tin, 2);
  writeTinFile(dir / "mesh.tin", Mesh::fromTinData(tin), 0);
  const std::string one = test::readFile(dir / "one.tin");
  EXPECT_EQ(one, encodeTin(tin));
  EXPECT_EQ(one, test::readFile(dir / "two.tin"));
  EXPECT_EQ(one, test::readFile(dir / "mesh.tin"));
  expectSame(readTinFile(dir / "two.tin"), tin);
}

TEST(TinFile, Crc32CombineIsTheCrcOfBothStrings) {
  std::mt19937 rng(5);
  std::string text(70000, '\0');
  for (char& c : text) c = static_cast<char>(rng());
  for (const std::size_t cut : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{32},
                                std::size_t{4095}, std::size_t{69999}, text.size()}) {
    const std::string_view first = std::string_view(text).substr(0, cut);
    const std::string_view second = std::string_view(text).substr(cut);
    EXPECT_EQ(crc32Combine(crc32(first), crc32(second), second.size()), crc32(text)) << cut;
  }
}

/// A jittered grid of n × n vertices at UTM-sized coordinates (two
/// triangles a cell) with a road along a row, diagonal edges off it, and a
/// few vertices in no triangle.
TinData gridTin(std::uint32_t n) {
  TinData tin;
  tin.crs = "EPSG:32612";
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i)
      tin.vertices.push_back({431000.0 + i + jitter(rng), 4512000.0 + j + jitter(rng), 0.5 * i});
  const auto at = [n](std::uint32_t i, std::uint32_t j) { return j * n + i; };
  for (std::uint32_t j = 0; j + 1 < n; ++j) {
    for (std::uint32_t i = 0; i + 1 < n; ++i) {
      tin.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      tin.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  tin.features = {{FeatureKind::Road, "roads.gpkg, layer roads, feature 7"}};
  for (std::uint32_t i = 0; i + 1 < n; ++i)
    tin.constrainedEdges.push_back({at(i, n / 2), at(i + 1, n / 2), 0});
  for (std::uint32_t k = 0; k + 1 < n; ++k)
    tin.constrainedEdges.push_back({at(k, k), at(k + 1, k + 1), 0});
  for (std::uint32_t k = 0; k < 3; ++k)
    tin.vertices.push_back({431000.0 + 10.5 * k, 4512000.0 + n + 5.0, 1.0});
  return tin;
}

/// The part readTinFilePart documents, made from the whole TIN in memory.
TinData expectedPart(const TinData& tin, const tiles::Rect& region, const tiles::Rect& vertices) {
  TinData part;
  part.crs = tin.crs;
  part.features = tin.features;
  std::vector<char> keep(tin.vertices.size(), 0);
  const auto meets = [&](std::initializer_list<std::uint32_t> ids) {
    std::vector<Point3> corners;
    for (const auto v : ids) corners.push_back(tin.vertices[v]);
    return tiles::boundsOf(corners).overlaps(region);
  };
  for (const auto& t : tin.triangles)
    if (meets({t[0], t[1], t[2]}))
      part.triangles.push_back(t), keep[t[0]] = keep[t[1]] = keep[t[2]] = 1;
  for (const auto& e : tin.constrainedEdges)
    if (meets({e.a, e.b})) part.constrainedEdges.push_back(e), keep[e.a] = keep[e.b] = 1;
  std::vector<std::uint32_t> number(tin.vertices.size(), 0);
  for (std::uint32_t v = 0; v < tin.vertices.size(); ++v) {
    if (!keep[v] && !vertices.contains(tin.vertices[v].xy())) continue;
    number[v] = static_cast<std::uint32_t>(part.vertices.size());
    part.vertices.push_back(tin.vertices[v]);
  }
  for (auto& t : part.triangles)
    for (auto& v : t) v = number[v];
  for (auto& e : part.constrainedEdges) e.a = number[e.a], e.b = number[e.b];
  return part;
}

/// The same TIN as a file of an older version: version 1 (no block index)
/// or 2 (a block index of `perBlock` records a block, without its summary).
std::string olderVersionBytes(const TinData& tin, std::uint32_t version,
                              std::uint32_t perBlock = kTinBlockRecords) {
  const std::string v3 = encodeTin(tin, perBlock);
  std::uint64_t payload = 4 + tin.crs.size() + 8 + 24 * tin.vertices.size() + 8 +
                          12 * tin.triangles.size() + 8 + 8 + 12 * tin.constrainedEdges.size();
  for (const auto& f : tin.features) payload += 5 + f.source.size();
  const auto put = [](std::string& bytes, std::size_t at, std::uint64_t value, int size) {
    for (int i = 0; i < size; ++i) bytes[at + i] = static_cast<char>(value >> (8 * i));
  };
  std::string bytes = v3.substr(0, kTinHeaderSize + payload);
  if (version == 2) {
    std::uint64_t index = 4 + 4;
    for (const std::size_t n :
         {tin.vertices.size(), tin.triangles.size(), tin.constrainedEdges.size()})
      index += 8 + 36 * ((n + perBlock - 1) / perBlock);
    bytes += v3.substr(kTinHeaderSize + payload, index);
    bytes += std::string(4, '\0');
    put(bytes, bytes.size() - 4,
        crc32(std::string_view(bytes).substr(kTinHeaderSize + payload, index)), 4);
    payload += index + 4;
  }
  put(bytes, 8, version, 4);
  put(bytes, 16, payload, 8);
  put(bytes, 24, crc32(std::string_view(bytes).substr(kTinHeaderSize)), 4);
  put(bytes, 28, crc32(std::string_view(bytes).substr(0, 28)), 4);
  return bytes;
}
std::string versionOneBytes(const TinData& tin) {
  return olderVersionBytes(tin, 1);
}

TEST(TinFile, AnOlderVersionIsEncodedAsItsFilesHoldIt) {
  const TinData tin = gridTin(40);
  for (const std::uint32_t perBlock : {kTinBlockRecords, 7u}) {
    EXPECT_EQ(encodeTin(tin, perBlock, kTinIndexGroupBlocks, 2),
              olderVersionBytes(tin, 2, perBlock));
    EXPECT_EQ(encodeTin(tin, perBlock, kTinIndexGroupBlocks, 1),
              olderVersionBytes(tin, 1, perBlock));
  }
  EXPECT_THROW((void)encodeTin(tin, kTinBlockRecords, kTinIndexGroupBlocks, kTinFormatVersion + 1),
               Error);
}

TEST(TinFile, APartIsReadThroughTheBlockIndexAsDocumented) {
  const TinData tin = gridTin(300);  // 90 k vertices: 88 vertex blocks, 175 triangle blocks
  const auto dir = test::scratchDir("tinfile-part");
  writeTinFile(dir / "grid.tin", tin);
  std::ofstream(dir / "v1.tin", std::ios::binary) << versionOneBytes(tin);
  std::ofstream(dir / "v2.tin", std::ios::binary) << olderVersionBytes(tin, 2);
  // Small blocks in small groups: a region meets many groups, some in part.
  std::ofstream(dir / "groups.tin", std::ios::binary) << encodeTin(tin, 16, 3);
  expectSame(readTinFile(dir / "groups.tin"), tin);
  expectSame(readTinFile(dir / "v1.tin"), tin);
  expectSame(readTinFile(dir / "v2.tin"), tin);
  const auto size = std::filesystem::file_size(dir / "grid.tin");
  const std::uint32_t fileCrc = crc32(encodeTin(tin));
  const double x = 431000, y = 4512000;
  struct Case {
    tiles::Rect region, vertices;
  };
  const std::vector<Case> cases = {
      {{x + 100.25, y + 40, x + 130, y + 80}, {x + 90, y + 30, x + 140, y + 90}},  // a square
      {{x + 20, y + 140, x + 60, y + 170}, {x, y + 120, x + 100, y + 190}},  // across the road
      {{x - 50, y - 50, x - 10, y - 10}, {x - 50, y - 50, x - 10, y - 10}},  // off the TIN
      {{x, y + 305, x + 30, y + 306}, {x, y + 300, x + 30, y + 310}},        // the lone vertices
      {{-1e9, -1e9, 1e9, 1e9}, {-1e9, -1e9, 1e9, 1e9}},                      // all of it
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << c.region.x0 - x << " " << c.region.y0 - y);
    const TinData expected = expectedPart(tin, c.region, c.vertices);
    const TinPart part = readTinFilePart(dir / "grid.tin", c.region, c.vertices);
    expectSame(part.tin, expected);
    EXPECT_EQ(part.fileCrc, fileCrc);
    EXPECT_EQ(part.vertices, tin.vertices.size());
    EXPECT_EQ(part.triangles, tin.triangles.size());
    if (c.region.x0 > -1e9) {
      EXPECT_LT(part.bytesRead, size / 4);
    } else {
      EXPECT_EQ(part.bytesRead, size);
    }
    // A version 1 file gives the same part, read through.
    const TinPart old = readTinFilePart(dir / "v1.tin", c.region, c.vertices);
    expectSame(old.tin, expected);
    EXPECT_EQ(old.bytesRead, std::filesystem::file_size(dir / "v1.tin"));
    EXPECT_EQ(old.fileCrc, crc32(versionOneBytes(tin)));
    // A version 2 file gives it too, its index read whole.
    const TinPart two = readTinFilePart(dir / "v2.tin", c.region, c.vertices);
    expectSame(two.tin, expected);
    EXPECT_EQ(two.fileCrc, crc32(olderVersionBytes(tin, 2)));
    if (c.region.x0 > -1e9) {
      EXPECT_LT(two.bytesRead, size / 4);
    } else {
      EXPECT_EQ(two.bytesRead, std::filesystem::file_size(dir / "v2.tin"));
    }
    const TinPart grouped = readTinFilePart(dir / "groups.tin", c.region, c.vertices);
    expectSame(grouped.tin, expected);
    if (c.region.x0 <= -1e9) {
      EXPECT_EQ(grouped.bytesRead, std::filesystem::file_size(dir / "groups.tin"));
    }
  }
}

TEST(TinFile, APartOfATinWithoutTrianglesOrVerticesIsRead) {
  // Sections with no blocks have no groups in the summary.
  const auto dir = test::scratchDir("tinfile-part-empty");
  TinData points;
  points.crs = "EPSG:32612";
  points.vertices = {{431000, 4512000, 1}, {431005, 4512003, 2}, {431100, 4512100, 3}};
  TinData none;
  none.crs = "EPSG:32612";
  const tiles::Rect region{431000, 4512000, 431010, 4512010};
  for (const TinData& tin : {points, none}) {
    for (const std::uint32_t version : {2u, 3u}) {
      SCOPED_TRACE(testing::Message() << tin.vertices.size() << " vertices, version " << version);
      const auto file = dir / "t.tin";
      std::ofstream(file, std::ios::binary | std::ios::trunc)
          << encodeTin(tin, kTinBlockRecords, kTinIndexGroupBlocks, version);
      const TinPart part = readTinFilePart(file, region, region);
      expectSame(part.tin, expectedPart(tin, region, region));
      EXPECT_EQ(part.tin.vertices.size(), tin.vertices.empty() ? 0u : 2u);
    }
  }
}

/// Flips a bit `at` bytes into a file's payload, in place.
void damage(const std::filesystem::path& file, std::size_t at) {
  std::string bytes = test::readFile(file);
  bytes[kTinHeaderSize + at] = static_cast<char>(bytes[kTinHeaderSize + at] ^ 0x04);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(TinFile, AStreamWrittenTinHasTheWholeTinsBytes) {
  // In uneven pieces, with small blocks whose ends fall inside the pieces,
  // and with none: the bytes encodeTin gives the whole TIN.
  const auto dir = test::scratchDir("tinfile-stream");
  TinData tin = gridTin(60);
  tin.constrainedEdges.clear();
  for (const std::uint32_t perBlock : {kTinBlockRecords, 7u, 1u}) {
    for (const std::size_t piece : {std::size_t{1}, std::size_t{333}, std::size_t{100000}}) {
      const auto path =
          dir / ("stream-" + std::to_string(perBlock) + "-" + std::to_string(piece) + ".tin");
      TinStreamWriter writer(path, tin.crs, perBlock);
      for (std::size_t i = 0; i < tin.vertices.size(); i += piece) {
        const std::size_t n = std::min(piece, tin.vertices.size() - i);
        writer.addVertices({tin.vertices.data() + i, n});
      }
      std::vector<Point3> corners;
      for (std::size_t t = 0; t < tin.triangles.size(); t += piece) {
        const std::size_t n = std::min(piece, tin.triangles.size() - t);
        corners.clear();
        for (std::size_t k = t; k < t + n; ++k)
          for (const std::uint32_t v : tin.triangles[k]) corners.push_back(tin.vertices[v]);
        writer.addTriangles({tin.triangles.data() + t, n}, corners);
      }
      EXPECT_EQ(writer.vertexCount(), tin.vertices.size());
      EXPECT_EQ(writer.triangleCount(), tin.triangles.size());
      EXPECT_FALSE(std::filesystem::exists(path)) << "visible before commit";
      writer.commit(tin.features);
      EXPECT_EQ(test::readFile(path), encodeTin(tin, perBlock))
          << perBlock << " records a block, pieces of " << piece;
    }
  }
  // No triangles at all, and a writer never committed leaves nothing.
  TinData points;
  points.crs = "EPSG:4978";
  points.vertices = {{1, 2, 3}, {4, 5, 6}};
  {
    TinStreamWriter writer(dir / "points.tin", points.crs);
    writer.addVertices(points.vertices);
    writer.commit({});
  }
  EXPECT_EQ(test::readFile(dir / "points.tin"), encodeTin(points));
  {
    TinStreamWriter writer(dir / "dropped.tin", "");
    writer.addVertices(points.vertices);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "dropped.tin"));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().extension(), ".tin") << "a temp file was left: " << entry.path();
}

TEST(TinFile, APartRefusesDamageInWhatItReads) {
  const TinData tin = gridTin(300);
  const auto dir = test::scratchDir("tinfile-part-damage");
  const std::filesystem::path file = dir / "grid.tin";
  const double x = 431000, y = 4512000;
  const tiles::Rect nearOrigin{x + 1, y + 1, x + 5, y + 5};  // in the first blocks
  const std::size_t vertices = 4 + tin.crs.size() + 8;       // where the vertex records start
  const std::size_t triangles = vertices + 24 * tin.vertices.size() + 8;
  const std::size_t lastTriangle = triangles + 12 * (tin.triangles.size() - 1);
  const auto partError = [&] {
    return errorOf([&] { (void)readTinFilePart(file, nearOrigin, nearOrigin); });
  };
  struct Case {
    std::size_t at;
    const char* says;  // "" when the part does not read it
  };
  for (const Case c :
       {Case{6, "CRS, the counts and the features"},  // in the CRS text
        Case{vertices + 5, "vertex block 0 does not match"},
        Case{triangles + 30, "triangle block 0 does not match"}, Case{lastTriangle, ""}}) {
    writeTinFile(file, tin);
    damage(file, c.at);
    SCOPED_TRACE(c.at);
    const std::string msg = partError();
    if (*c.says) {
      EXPECT_NE(msg.find(c.says), std::string::npos) << msg;
      EXPECT_NE(msg.find("grid.tin"), std::string::npos) << msg;
    } else {
      EXPECT_EQ(msg, "(no error)");  // a block it does not read: the whole read sees it
    }
    EXPECT_NE(errorOf([&] { (void)readTinFile(file); }).find("checksum"), std::string::npos);
  }
  // The index's summary: its checksum (here in the last group's CRC).
  writeTinFile(file, tin);
  const auto size = std::filesystem::file_size(file);
  damage(file, size - kTinHeaderSize - 10);
  EXPECT_NE(partError().find("block index summary checksum"), std::string::npos) << partError();
  // A version 2 index: its checksum, read whole.
  std::ofstream(file, std::ios::binary | std::ios::trunc) << olderVersionBytes(tin, 2);
  damage(file, std::filesystem::file_size(file) - kTinHeaderSize - 20);
  EXPECT_NE(partError().find("block index checksum"), std::string::npos) << partError();
}

/// Where a section's block entries start in the payload of encodeTin(tin,
/// perBlock), and where its groups' entries start in the index's summary.
struct IndexLayout {
  std::array<std::size_t, 3> entries{}, groups{};
};
IndexLayout indexLayout(const TinData& tin, std::size_t perBlock, std::size_t perGroup) {
  std::size_t at = 4 + tin.crs.size() + 8 + 24 * tin.vertices.size() + 8 +
                   12 * tin.triangles.size() + 8 + 8 + 12 * tin.constrainedEdges.size();
  for (const auto& f : tin.features) at += 5 + f.source.size();
  const std::array<std::size_t, 3> records{tin.vertices.size(), tin.triangles.size(),
                                           tin.constrainedEdges.size()};
  IndexLayout layout;
  std::array<std::size_t, 3> blocks{};
  at += 8;
  for (std::size_t s = 0; s < 3; ++s) {
    blocks[s] = (records[s] + perBlock - 1) / perBlock;
    layout.entries[s] = at + 8;
    at += 8 + 36 * blocks[s];
  }
  at += 4;
  for (std::size_t s = 0; s < 3; ++s) {
    layout.groups[s] = at + 8;
    at += 8 + 36 * ((blocks[s] + perGroup - 1) / perGroup);
  }
  return layout;
}

TEST(TinFile, APartReadsOnlyTheGroupsOfTheIndexItNeeds) {
  // One record a block: an index (36 bytes a block, 268 k blocks, 9.7 MB)
  // as large as that of a TIN a thousand times larger at 1 024. The part
  // reads the summary and the groups around its region; version 2 reads the
  // whole index.
  const TinData tin = gridTin(300);
  const auto dir = test::scratchDir("tinfile-part-index-groups");
  const std::filesystem::path file = dir / "grid.tin", old = dir / "v2.tin";
  const std::string bytes = encodeTin(tin, 1);
  std::ofstream(file, std::ios::binary) << bytes;
  std::ofstream(old, std::ios::binary) << olderVersionBytes(tin, 2, 1);
  const double x = 431000, y = 4512000;
  const tiles::Rect region{x + 100, y + 150, x + 140, y + 170};
  const tiles::Rect vertices{x + 90, y + 140, x + 150, y + 180};
  const TinData expected = expectedPart(tin, region, vertices);
  const TinPart part = readTinFilePart(file, region, vertices);
  const TinPart whole = readTinFilePart(old, region, vertices);
  expectSame(part.tin, expected);
  expectSame(whole.tin, expected);
  EXPECT_EQ(part.fileCrc, crc32(bytes));
  EXPECT_LT(part.bytesRead, whole.bytesRead / 5)
      << part.bytesRead << " against " << whole.bytesRead;
  // Groups of 7 entries instead of 1 024: the same part, read from more groups.
  std::ofstream(dir / "g7.tin", std::ios::binary) << encodeTin(tin, 1, 7);
  expectSame(readTinFilePart(dir / "g7.tin", region, vertices).tin, expected);
  expectSame(readTinFile(dir / "g7.tin"), tin);

  // Damage in a group of entries the part reads, in one it does not, and in
  // the summary.
  const IndexLayout layout = indexLayout(tin, 1, kTinIndexGroupBlocks);
  const std::size_t insideVertex = 160 * 300 + 120;          // a vertex in the region
  const std::size_t insideTriangle = 2 * (160 * 299 + 120);  // a triangle in it
  struct Case {
    std::size_t at;
    const char* says;  // "" when the part does not read it
  };
  for (const Case c : {Case{layout.entries[0] + 36 * insideVertex + 3, "vertex group"},
                       Case{layout.entries[1] + 36 * insideTriangle + 33, "triangle group"},
                       Case{layout.entries[0] + 36 * 5 + 3, ""},  // row 0
                       Case{layout.groups[1] + 2, "summary checksum"}}) {
    SCOPED_TRACE(c.at);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
    damage(file, c.at);
    const std::string msg = errorOf([&] { (void)readTinFilePart(file, region, vertices); });
    if (*c.says) {
      EXPECT_NE(msg.find(c.says), std::string::npos) << msg;
      EXPECT_NE(msg.find("grid.tin"), std::string::npos) << msg;
    } else {
      EXPECT_EQ(msg, "(no error)");
    }
    EXPECT_NE(errorOf([&] { (void)readTinFile(file); }).find("checksum"), std::string::npos);
  }
}

TEST(TinFile, AVersionTwoPartReadsAnIndexLargerThanItsWindowAndSeesDamageAtItsEnd) {
  // One record a block: the version 2 index (36 bytes a block, 268 k
  // blocks, 9.6 MB) is read through in more than one of the reader's 8 MB
  // windows, its checksum following them; what the part keeps of it is the same.
  const TinData tin = gridTin(300);
  const auto dir = test::scratchDir("tinfile-part-big-index");
  const std::filesystem::path file = dir / "grid.tin";
  std::string bytes = olderVersionBytes(tin, 2, 1);
  ASSERT_GT(bytes.size() - kTinHeaderSize - 24 * tin.vertices.size() - 12 * tin.triangles.size(),
            std::size_t{8} << 20);
  const double x = 431000, y = 4512000;
  const tiles::Rect region{x + 100, y + 150, x + 140, y + 170};
  const tiles::Rect vertices{x + 90, y + 140, x + 150, y + 180};
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
  const TinPart part = readTinFilePart(file, region, vertices);
  expectSame(part.tin, expectedPart(tin, region, vertices));
  EXPECT_EQ(part.fileCrc, crc32(bytes));
  // A byte of the index's last window, in a block the part does not read.
  damage(file, bytes.size() - kTinHeaderSize - 4 - 36 * 3);
  const std::string msg = errorOf([&] { (void)readTinFilePart(file, region, vertices); });
  EXPECT_NE(msg.find("block index checksum"), std::string::npos) << msg;
}

TEST(TinFile, NoDamagedByteGivesAWrongPart) {
  // Blocks of 64 records: many blocks, some read and some not. A flipped
  // byte anywhere is refused as damage or lies where the part does not read.
  const TinData tin = gridTin(24);
  // Also blocks of 8 in groups of 3 (many groups of the index's summary),
  // and a version 2 file.
  const double x = 431000, y = 4512000;
  const tiles::Rect region{x + 3, y + 4, x + 9, y + 8}, vertices{x, y, x + 12, y + 12};
  const TinData expected = expectedPart(tin, region, vertices);
  const auto dir = test::scratchDir("tinfile-part-flips");
  const std::filesystem::path file = dir / "flip.tin";
  for (const std::string& bytes :
       {encodeTin(tin, 64), encodeTin(tin, 8, 3), olderVersionBytes(tin, 2, 64)}) {
    std::size_t refused = 0, unread = 0;
    for (std::size_t i = 0; i < bytes.size(); i += 7) {  // every 7th byte, each bit in turn
      std::string damaged = bytes;
      damaged[i] = static_cast<char>(damaged[i] ^ (1 << (i / 7 % 8)));
      std::ofstream(file, std::ios::binary | std::ios::trunc) << damaged;
      try {
        const TinPart part = readTinFilePart(file, region, vertices);
        SCOPED_TRACE(i);
        expectSame(part.tin, expected);
        EXPECT_EQ(part.fileCrc, crc32(bytes));
        ++unread;
      } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Input) << i << ": " << e.what();
        ++refused;
      }
    }
    EXPECT_GT(refused, 0u);
    EXPECT_GT(unread, bytes.size() / 14);  // most blocks lie outside the region
  }
}

TEST(TinFile, AnIndexThatDisagreesWithItsSectionsIsRefused) {
  // Valid checksums over a wrong box: a writer's mistake, not damage in transit.
  const TinData tin = gridTin(20);
  std::string bytes = encodeTin(tin);
  const std::size_t indexAt = bytes.size() - (4 + 4 + 3 * (8 + 36) + 4 + 3 * (8 + 36) + 4 + 4);
  bytes[indexAt + 4 + 4 + 8 + 8 * 2] ^= 0x01;  // the first vertex block's x1
  const auto resum = [&bytes](std::size_t from, std::size_t to, std::size_t at) {
    const std::uint32_t c = crc32(std::string_view(bytes).substr(from, to - from));
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>(c >> (8 * i));
  };
  resum(indexAt, bytes.size() - 4, bytes.size() - 4);
  resum(kTinHeaderSize, bytes.size(), 24);
  resum(0, 28, 28);
  const auto msg = errorOf([&] { (void)decodeTin(bytes, "odd.tin"); });
  EXPECT_NE(msg.find("block index does not match"), std::string::npos) << msg;
}

TEST(TinFile, WrongMagicIsRefusedNamingTheFile) {
  const auto dir = test::scratchDir("tinfile-magic");
  std::ofstream(dir / "x.tin") << "solid ascii\nnot a tin at all, just text\n";
  const auto msg = errorOf([&] { readTinFile(dir / "x.tin"); });
  EXPECT_NE(msg.find("x.tin"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a .tin file"), std::string::npos) << msg;
}

TEST(TinFile, NewerVersionIsRefused) {
  std::string bytes = encodeTin(sampleTin());
  bytes[8] = static_cast<char>(kTinFormatVersion + 1);
  // Keep the header checksum valid so the version check is what fires.
  const std::uint32_t hc = crc32(std::string_view(bytes).substr(0, 28));
  for (int i = 0; i < 4; ++i) bytes[28 + i] = static_cast<char>(hc >> (8 * i));
  const auto msg = errorOf([&] { decodeTin(bytes, "new.tin"); });
  EXPECT_NE(msg.find("new.tin"), std::string::npos) << msg;
  EXPECT_NE(msg.find("newer"), std::string::npos) << msg;
}

TEST(TinFile, TruncationAnywhereIsRefused) {
  const std::string bytes = encodeTin(sampleTin());
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    try {
      decodeTin(bytes.substr(0, len), "cut.tin");
      ADD_FAILURE() << "accepted a file cut to " << len << " bytes";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("cut.tin"), std::string::npos);
      if (len >= kTinHeaderSize) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
      }
    }
  }
}

TEST(TinFile, EveryFlippedBitIsCaught) {
  const std::string bytes = encodeTin(sampleTin());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::string damaged = bytes;
    damaged[i] = static_cast<char>(damaged[i] ^ 0x10);
    try {
      decodeTin(damaged, "flip.tin");
      ADD_FAILURE() << "accepted a file with byte " << i << " damaged";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
    }
  }
}

TEST(TinFile, PayloadDamageReportsChecksumMismatch) {
  std::string bytes = encodeTin(sampleTin());
  bytes[bytes.size() - 5] ^= 0x01;
  const auto msg = errorOf([&] { decodeTin(bytes, "crc.tin"); });
  EXPECT_NE(msg.find("checksum"), std::string::npos) << msg;
}

TEST(TinFile, TrailingGarbageIsRefused) {
  const auto msg = errorOf([&] { decodeTin(encodeTin(sampleTin()) + "xx", "tail.tin"); });
  EXPECT_NE(msg.find("unexpected bytes"), std::string::npos) << msg;
}

TEST(TinFile, MissingFileIsAnInputErrorNamingIt) {
  try {
    readTinFile("/nonexistent/dir/none.tin");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("none.tin"), std::string::npos);
  }
}

TEST(TinFile, MalformedTinDataIsNotWrittenAndLeavesNoFile) {
  const auto dir = test::scratchDir("tinfile-bad");
  TinData tin = sampleTin();
  tin.triangles.push_back({0, 1, 99});
  EXPECT_THROW(writeTinFile(dir / "bad.tin", tin), Error);
  tin = sampleTin();
  tin.vertices[2].z = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(writeTinFile(dir / "bad.tin", tin), Error);
  tin = sampleTin();
  tin.constrainedEdges.push_back({0, 1, 7});
  EXPECT_THROW(writeTinFile(dir / "bad.tin", tin), Error);
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(TinFile, UnwritableTargetIsAnIoErrorAndKeepsTheOldFile) {
  const auto dir = test::scratchDir("tinfile-io");
  try {
    writeTinFile(dir / "no-such-dir" / "a.tin", sampleTin());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_NE(std::string(e.what()).find("a.tin"), std::string::npos);
  }
  // A failed rewrite leaves an existing file untouched.
  writeTinFile(dir / "keep.tin", sampleTin());
  const std::string before = test::readFile(dir / "keep.tin");
  TinData bad = sampleTin();
  bad.triangles[0][0] = 1000;
  EXPECT_THROW(writeTinFile(dir / "keep.tin", bad), Error);
  EXPECT_EQ(test::readFile(dir / "keep.tin"), before);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
}

TEST(TinFile, FeatureKindNamesRoundTrip) {
  for (int k = 0; k <= static_cast<int>(FeatureKind::BreakLine); ++k) {
    const auto kind = static_cast<FeatureKind>(k);
    EXPECT_EQ(featureKindFromName(featureKindName(kind)), kind);
  }
  EXPECT_FALSE(featureKindFromName("volcano"));
}

// Writing a Mesh gives exactly the bytes of writing its TinData (the builder
// writes meshes; everything else writes TinData), and the summaries agree.
TEST(TinFile, MeshWritesTheBytesOfItsTinData) {
  const Mesh mesh = Mesh::fromTinData(sampleTin());
  ASSERT_TRUE(mesh.buildProblems().empty());
  const auto dir = test::scratchDir("tinfile-mesh");
  writeTinFile(dir / "mesh.tin", mesh);
  EXPECT_EQ(test::readFile(dir / "mesh.tin"), encodeTin(mesh.toTinData()));
  expectSame(readTinFile(dir / "mesh.tin"), mesh.toTinData());

  const TinSummary a = summariseTin(mesh), b = summariseTin(mesh.toTinData());
  EXPECT_EQ(a.json(), b.json());
  EXPECT_EQ(a.constrainedEdges, 2u);  // the edge 2-4 of two features counts once
}

}  // namespace
}  // namespace tinsmith::ingest
