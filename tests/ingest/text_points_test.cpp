// readers.text: delimiter and header detection, column choice, errors with lines.
#include "ingest/readers/text_points.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "core/base/error.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

std::filesystem::path writeText(const std::string& dirName, const std::string& name,
                                const std::string& text) {
  const auto dir = test::scratchDir(dirName);
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Runs `f` expecting a tinsmith::Error; returns it.
template <typename F>
Error expectError(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no tinsmith::Error thrown";
  return internalError("none");
}

TEST(TextPoints, CommaWithHeader) {
  const auto t = parseTextPoints("x,y,elevation\n1.5,2.5,100\n3,4,101.25\n", "a.csv");
  EXPECT_EQ(t.delimiter, TextDelimiter::Comma);
  EXPECT_TRUE(t.hasHeader);
  ASSERT_EQ(t.points.size(), 2u);
  EXPECT_EQ(t.points[0], (Point3{1.5, 2.5, 100}));
  EXPECT_EQ(t.points[1], (Point3{3, 4, 101.25}));
  EXPECT_EQ(t.lines[1], 3);
}

TEST(TextPoints, SemicolonTabWhitespace) {
  const auto s = parseTextPoints("1;2;3\n4;5;6\n", "s.csv");
  EXPECT_EQ(s.delimiter, TextDelimiter::Semicolon);
  EXPECT_FALSE(s.hasHeader);
  EXPECT_EQ(s.points[1], (Point3{4, 5, 6}));

  const auto t = parseTextPoints("x\ty\tz\n1\t2\t3\n", "t.tsv");
  EXPECT_EQ(t.delimiter, TextDelimiter::Tab);
  EXPECT_EQ(t.points[0], (Point3{1, 2, 3}));

  const auto w = parseTextPoints("# survey\n  1   2  3\n\n4 5 6   \r\n", "w.xyz");
  EXPECT_EQ(w.delimiter, TextDelimiter::Whitespace);
  ASSERT_EQ(w.points.size(), 2u);
  EXPECT_EQ(w.points[1], (Point3{4, 5, 6}));
  EXPECT_EQ(w.lines[0], 2);
  EXPECT_EQ(w.lines[1], 4);
}

TEST(TextPoints, HeaderNamesInAnyOrder) {
  const auto t = parseTextPoints("id,Elevation,Northing,Easting\n7,100,2000,1000\n", "a.csv");
  EXPECT_EQ(t.points[0], (Point3{1000, 2000, 100}));
  EXPECT_EQ(t.xIndex, 3);
  EXPECT_EQ(t.zIndex, 1);

  const auto g = parseTextPoints("\"lat\",\"lon\",\"alt\"\n44.5,-71.5,900\n", "g.csv");
  EXPECT_TRUE(g.geographicNames);
  EXPECT_EQ(g.points[0], (Point3{-71.5, 44.5, 900}));
}

TEST(TextPoints, ConfigurableColumns) {
  TextPointOptions byName;
  byName.xColumn = "px";
  byName.yColumn = "py";
  byName.zColumn = "ground";
  const auto t = parseTextPoints("ground,px,py\n5,1,2\n", "a.csv", byName);
  EXPECT_EQ(t.points[0], (Point3{1, 2, 5}));

  TextPointOptions byIndex;
  byIndex.xIndex = 1;
  byIndex.yIndex = 2;
  byIndex.zIndex = 3;
  const auto u = parseTextPoints("9 1 2 3\n", "a.xyz", byIndex);
  EXPECT_EQ(u.points[0], (Point3{1, 2, 3}));

  TextPointOptions fixed;
  fixed.fixedZ = 0.0;
  const auto f = parseTextPoints("1,2\n3,4\n", "a.csv", fixed);
  EXPECT_EQ(f.points[1], (Point3{3, 4, 0}));

  const auto e = expectError([&] { parseTextPoints("a,b,c\n1,2,3\n", "a.csv", byName); });
  EXPECT_NE(std::string(e.what()).find("'px'"), std::string::npos) << e.what();
}

TEST(TextPoints, ErrorsNameTheLine) {
  auto e = expectError([] { parseTextPoints("x,y,z\n1,2,3\n1,2,nan\n", "bad.csv"); });
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_EQ(e.where().line, 3);
  EXPECT_EQ(e.where().file, "bad.csv");
  EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();

  e = expectError([] { parseTextPoints("x,y,z\n1,2,inf\n", "bad.csv"); });
  EXPECT_EQ(e.where().line, 2);

  e = expectError([] { parseTextPoints("x,y,z\n1,2,3\n\n1,2,abc\n", "bad.csv"); });
  EXPECT_EQ(e.where().line, 4);
  EXPECT_NE(std::string(e.what()).find("'abc' is not a number"), std::string::npos) << e.what();

  e = expectError([] { parseTextPoints("1,2,3\n1,2\n", "bad.csv"); });
  EXPECT_EQ(e.where().line, 2);
  EXPECT_NE(std::string(e.what()).find("found 2"), std::string::npos) << e.what();

  e = expectError([] { parseTextPoints("x,y,z\n# nothing\n", "empty.csv"); });
  EXPECT_NE(std::string(e.what()).find("no points"), std::string::npos) << e.what();
}

// A text long enough to be parsed in pieces: blank and comment lines, CRLF
// line ends, a header, and lines of different lengths.
std::string longText(std::size_t points) {
  std::string text = "# survey\r\nE N H\r\n";
  for (std::size_t i = 0; i < points; ++i) {
    if (i % 997 == 0) text += "\n# a comment\n";
    text += std::to_string(430000 + i % 1000) + "." + std::to_string(i % 7) + " " +
            std::to_string(4510000 + i / 1000) + " " + std::to_string(1500.25 + i % 300) +
            (i % 3 ? "\r\n" : "\n");
  }
  return text;
}

TEST(TextPoints, PlainAndUnusualFieldsReadAlike) {
  // Most lines take the one-scan path; quotes, '+', blanks around fields,
  // extra columns and trailing separators take the general one. Both agree.
  const auto t = parseTextPoints(
      "1,2,3\n"
      "\"4\",5,+6\n"
      " 7 , 8 ,9 ,extra\n"
      "10,11,12,\r\n"
      "-1.5e2,2.5E-1,0\n",
      "mixed.csv");
  ASSERT_EQ(t.points.size(), 5u);
  EXPECT_EQ(t.points[0], (Point3{1, 2, 3}));
  EXPECT_EQ(t.points[1], (Point3{4, 5, 6}));
  EXPECT_EQ(t.points[2], (Point3{7, 8, 9}));
  EXPECT_EQ(t.points[3], (Point3{10, 11, 12}));
  EXPECT_EQ(t.points[4], (Point3{-150, 0.25, 0}));
  const auto w = parseTextPoints("1 2 3 4\n\t5\t 6 7\r\n8 9 +10\n", "mixed.xyz");
  ASSERT_EQ(w.points.size(), 3u);
  EXPECT_EQ(w.points[1], (Point3{5, 6, 7}));
  EXPECT_EQ(w.points[2], (Point3{8, 9, 10}));
  // Not-quite numbers are refused by either path with the general wording.
  for (const std::string bad : {"1,2,3e\n", "1,2,0x10\n", "1,2,3 4\n", "1,,3\n", "1 2 3x\n"}) {
    const std::string first = bad.find(',') != std::string::npos ? "1,2,3\n" : "1 2 3\n";
    const auto e = expectError([&] { parseTextPoints(first + bad, "bad.csv"); });
    EXPECT_NE(std::string(e.what()).find("is not a number"), std::string::npos) << bad << ": " << e.what();
  }
}

TEST(TextPoints, PiecesParsedInParallelGiveTheSameTable) {
  const std::string text = longText(120000);  // ~3 MB: parsed in pieces
  TextPointOptions one, four;
  one.threads = 1;
  four.threads = 4;
  const auto a = parseTextPoints(text, "long.xyz", one);
  const auto b = parseTextPoints(text, "long.xyz", four);
  ASSERT_EQ(a.points.size(), 120000u);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.lines, b.lines);
  // Line numbers count the header, the blank and the comment lines.
  EXPECT_EQ(a.lines.front(), 5);  // comment block before the first point: lines 3 and 4
  EXPECT_EQ(a.points.back(), (Point3{430999.5, 4510119, 1500.25 + 119999 % 300}));
  EXPECT_EQ(a.lines.back(), static_cast<std::int64_t>(2 + 120000 + 2 * (119999 / 997 + 1)));
}

TEST(TextPoints, AnErrorDeepInALongFileNamesItsLineForAnyThreads) {
  std::string text = longText(120000);
  // Break the 100 000th point's height, and a later one: the first is reported.
  const auto lineStart = [&](std::int64_t line) {
    std::size_t pos = 0;
    for (std::int64_t l = 1; l < line; ++l) pos = text.find('\n', pos) + 1;
    return pos;
  };
  const auto table = parseTextPoints(text, "long.xyz");
  const std::int64_t bad = table.lines[99999], later = table.lines[110000];
  text.insert(text.find('\n', lineStart(later)) - 1, "x");
  text.insert(text.find('\n', lineStart(bad)) - 1, "x");
  for (unsigned threads : {1u, 2u, 4u}) {
    TextPointOptions options;
    options.threads = threads;
    const auto e = expectError([&] { parseTextPoints(text, "long.xyz", options); });
    EXPECT_EQ(e.where().line, bad) << threads << " threads: " << e.what();
    EXPECT_NE(std::string(e.what()).find("is not a number"), std::string::npos) << e.what();
  }
}

TEST(TextPoints, FileErrors) {
  auto e = expectError([] { readTextPoints("/nonexistent/points.csv"); });
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_NE(std::string(e.what()).find("/nonexistent/points.csv"), std::string::npos);
  EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos);

  const auto binary = writeText("text_points_binary", "b.csv", std::string("1,2,3\n\0\0\x01", 9));
  e = expectError([&] { readTextPoints(binary); });
  EXPECT_NE(std::string(e.what()).find("not a text file"), std::string::npos) << e.what();
}

TEST(TextPoints, ReadsFromFile) {
  const auto path = writeText("text_points_file", "p.csv", "easting;northing;height\n10;20;30\n");
  const auto points = readTextPoints(path);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0], (Point3{10, 20, 30}));
}

TEST(TextPoints, ChunksGiveTheWholeFilesPointsAndErrors) {
  // A BOM, comments and blank lines before a header, a file without a final
  // newline: every chunk size, down to one byte, reads what the whole does.
  std::string text = "\xEF\xBB\xBF# survey 2024\n\n# crew B\nE,N,H\n";
  for (int i = 0; i < 300; ++i)
    text += std::to_string(431000 + i) + ".25," + std::to_string(4512000 - i) + "," +
            std::to_string(1500 + i % 17) + (i % 50 == 7 ? "\n# a note\n" : "\n");
  text += "431999,4511000,1499";
  const auto path = writeText("text_points_chunks", "p.csv", text);
  const auto whole = readTextPoints(path);
  for (const std::size_t chunk :
       {std::size_t{1}, std::size_t{7}, std::size_t{64}, std::size_t{1} << 20}) {
    std::vector<Point3> read;
    std::size_t calls = 0;
    readTextPointsInChunks(path, {}, chunk, [&](std::span<const Point3> points) {
      ++calls;
      read.insert(read.end(), points.begin(), points.end());
    });
    EXPECT_EQ(read, whole) << "chunks of " << chunk << " bytes";
    if (chunk == 64) {
      EXPECT_GT(calls, 50u);
    }
  }
  // The error names the file's line, not the chunk's.
  const auto bad = writeText("text_points_chunks", "bad.csv",
                             text.substr(0, text.find("431200")) + "431200,x,1\n");
  const std::int64_t badLine =
      std::count(text.begin(), text.begin() + text.find("431200"), '\n') + 1;
  const auto e =
      expectError([&] { readTextPointsInChunks(bad, {}, 100, [](std::span<const Point3>) {}); });
  EXPECT_EQ(e.where().line, badLine) << e.what();
  EXPECT_EQ(expectError([&] { readTextPoints(bad); }).where().line, badLine);
  const auto empty = writeText("text_points_chunks", "empty.csv", "# nothing\n\n");
  EXPECT_NE(std::string(expectError([&] {
                          readTextPointsInChunks(empty, {}, 4, [](std::span<const Point3>) {});
                        }).what())
                .find("holds no points"),
            std::string::npos);
}

TEST(TextPoints, RedButteSpotHeights) {
  const auto t = readTextPointTable(std::filesystem::path(TINSMITH_SHARED_DATA) /
                                    "red-butte/spot-heights.csv");
  EXPECT_EQ(t.points.size(), 400u);
  EXPECT_TRUE(t.hasHeader);
  for (const auto& p : t.points) {
    // NAD83 / UTM 12N around Red Butte Canyon; DEM range 1580–2520 m.
    EXPECT_GT(p.x, 420000);
    EXPECT_LT(p.x, 440000);
    EXPECT_GT(p.y, 4505000);
    EXPECT_LT(p.y, 4525000);
    EXPECT_GE(p.z, 1570);
    EXPECT_LE(p.z, 2530);
  }
}

}  // namespace
}  // namespace tinsmith::ingest
