// The .tin file: exact round trips, deterministic bytes, and every kind of
// damage refused with an error that names the file — and no partial output.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

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
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].x), std::bit_cast<std::uint64_t>(b.vertices[i].x));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].y), std::bit_cast<std::uint64_t>(b.vertices[i].y));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.vertices[i].z), std::bit_cast<std::uint64_t>(b.vertices[i].z));
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
                                        (5 + tin.features[1].source.size()) + 8 + 12 * 3;
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
