// tinsmith build: the whole job from a small config gives the same bytes as
// tin then tile with the same options (from [tiles] or from flags); --resume
// completes a staging archive; bad input fails clearly before any work and
// leaves nothing under the output's names, nor loses a store built before.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

struct Project {
  fs::path dir, config, out;
};

/// The spot heights of the project: a hill of 31 × 31 points, 25 m apart and
/// slightly irregular, at UTM 12N-sized coordinates.
const std::string kHill =
    "synthetic:grid?nx=31&ny=31&spacing=25&jitter=0.05&x0=430000&y0=4515000&surface=hill"
    "&z0=1600&scale=80";

/// A hill of spot heights and a config whose [tiles] writes out/site.3dtiles.
/// `tilesExtra` is added to [tiles].
Project makeProject(const std::string& name, const std::string& tilesExtra = "") {
  Project p;
  p.dir = scratchDir(name);
  p.out = p.dir / "out";
  fs::create_directories(p.out);
  p.config = p.dir / "site.toml";
  std::ofstream(p.config) << "[project]\ncrs = \"EPSG:26912\"\n\n[[layer]]\npath = \"" << kHill
                          << "\"\nkind = \"points\"\ncrs = \"EPSG:26912\"\nname = \"hill\"\n\n"
                             "[tiles]\ntolerance = 0.5\nmax_triangles = 2048\n"
                             "output = \"out/site.3dtiles\"\n"
                          << tilesExtra;
  return p;
}

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST(BuildCli, TheStoreIsTinThenTileWithTheSameOptions) {
  const auto p = makeProject("build-cli");
  auto built = runTinsmith("build " + p.config.string() + " -q");
  ASSERT_EQ(built.exitCode, 0) << built.err;
  EXPECT_TRUE(built.err.empty()) << built.err;
  const std::string store = readFile(p.out / "site.3dtiles");
  ASSERT_GT(store.size(), 1000u);
  // Only the store and its TIN: no staging archive, no partial TIN.
  EXPECT_EQ(entries(p.out), 2u);

  // The same job in two steps, the [tiles] keys as flags.
  const fs::path ref = p.dir / "ref";
  fs::create_directories(ref);
  auto tin = runTinsmith("tin " + p.config.string() + " -q -o " + (ref / "site.tin").string());
  ASSERT_EQ(tin.exitCode, 0) << tin.err;
  auto tile =
      runTinsmith("tile " + (ref / "site.tin").string() +
                  " --tolerance 0.5 --max-triangles 2048 -q -o " + (ref / "site.3dtiles").string());
  ASSERT_EQ(tile.exitCode, 0) << tile.err;
  EXPECT_EQ(readFile(p.out / "site.tin"), readFile(ref / "site.tin"));
  EXPECT_EQ(store, readFile(ref / "site.3dtiles"));

  // Flags override the config's keys, and -o its output.
  const fs::path other = p.dir / "other";
  fs::create_directories(other);
  auto flagged = runTinsmith("build " + p.config.string() +
                             " --tolerance 2 --compression none --threads 1 --json -o " +
                             (other / "site.3dtiles").string());
  ASSERT_EQ(flagged.exitCode, 0) << flagged.err;
  const auto json = nlohmann::json::parse(flagged.out);
  EXPECT_EQ(json["tin"]["output"], (other / "site.tin").string());
  EXPECT_GT(json["tin"]["report"]["result"]["vertices"].get<int>(), 900);
  EXPECT_EQ(json["tiles"]["output"], (other / "site.3dtiles").string());
  // Zoom 0's tolerance is the finest zoom's, 2 m, doubled per zoom above it.
  EXPECT_EQ(json["tiles"]["zooms"][0]["tolerance"].get<double>(),
            std::ldexp(2.0, json["tiles"]["finestZoom"].get<int>()));
  auto plain = runTinsmith("tile " + (ref / "site.tin").string() +
                           " --tolerance 2 --max-triangles 2048 --compression none -q -o " +
                           (ref / "plain.3dtiles").string());
  ASSERT_EQ(plain.exitCode, 0) << plain.err;
  // The build record names the TIN's file, site.tin in both.
  EXPECT_EQ(readFile(other / "site.3dtiles"), readFile(ref / "plain.3dtiles"));
  EXPECT_NE(readFile(other / "site.3dtiles"), store);
}

TEST(BuildCli, ResumeCompletesAStagingArchive) {
  const auto p = makeProject("build-cli-resume");
  auto whole = runTinsmith("build " + p.config.string() + " -q");
  ASSERT_EQ(whole.exitCode, 0) << whole.err;
  const std::string bytes = readFile(p.out / "site.3dtiles");

  // An interrupted run: the staging archive holds only the tiles above zoom 1.
  const fs::path again = p.dir / "again";
  fs::create_directories(again);
  auto top = runTinsmith("tile " + (p.out / "site.tin").string() +
                         " --tolerance 0.5 --max-triangles 2048 --until-zoom 1 -q -o " +
                         (again / "site.partial.3dtiles").string());
  ASSERT_EQ(top.exitCode, 0) << top.err;
  auto resumed = runTinsmith("build " + p.config.string() + " --resume --json -o " +
                             (again / "site.3dtiles").string());
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  const auto json = nlohmann::json::parse(resumed.out);
  EXPECT_GT(json["tiles"]["kept"].get<int>(), 0);
  EXPECT_GT(json["tiles"]["built"].get<int>(), 0);
  EXPECT_EQ(bytes, readFile(again / "site.3dtiles"));
  EXPECT_FALSE(fs::exists(again / "site.partial.3dtiles"));

  // A staging archive of other options is refused, not mixed in.
  fs::copy_file(p.out / "site.3dtiles", again / "x.partial.3dtiles");
  auto other = runTinsmith("build " + p.config.string() + " --resume --tolerance 3 -q -o " +
                           (again / "x.3dtiles").string());
  EXPECT_EQ(other.exitCode, 2) << other.err;
  EXPECT_NE(other.err.find("other options"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(again / "x.3dtiles"));
  EXPECT_FALSE(fs::exists(again / "x.tin"));
}

TEST(BuildCli, BadInputFailsClearlyAndLeavesNothingUnderTheOutputsNames) {
  struct Case {
    std::string what, tilesExtra, replace, by, flags;
    int exitCode;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"a bad config key", "colour = \"red\"\n", "", "", "", 3,
       "site.toml, line 14: unknown key 'colour' in [tiles]"},
      {"a bad config value", "frame = \"enu\"\n", "", "", "", 3,
       "site.toml, line 14: tiles.frame = \"enu\": unknown frame"},
      {"tolerance 0 in the config", "tolerance = 0\n", "tolerance = 0.5\n", "", "", 3,
       "site.toml, line 13: tiles.tolerance = 0: must be greater than 0"},
      {"a missing layer file", "", kHill, "gone.csv", "", 3, "gone.csv"},
      {"a bad synthetic spec", "", "jitter=0.05", "jitter=5", "", 3,
       "jitter = 5 is out of range — jitter must be 0 to 0.5"},
      {"tolerance 0 on the command line", "", "", "", "--tolerance 0", 2,
       "tolerance must be a positive number"},
      {"a bad compression", "", "", "", "--compression zstd", 2,
       "--compression must be draco or none"},
      {"an unknown geoid", "", "", "", "--geoid egm2008", 2, "unknown geoid 'egm2008'"},
      {"heights PROJ cannot convert here", "", "crs = \"EPSG:26912\"\n\n",
       "crs = \"EPSG:26912+5703\"\n\n", "", 3, "PROJ needs the grid us_noaa_"},
  };
  for (const auto& c : cases) {
    auto p = makeProject("build-cli-bad", c.tilesExtra);
    if (!c.replace.empty()) {
      std::string text = readFile(p.config);
      text.replace(text.find(c.replace), c.replace.size(), c.by);
      std::ofstream(p.config) << text;
    }
    auto r = runTinsmith("build " + p.config.string() + " " + c.flags);
    EXPECT_EQ(r.exitCode, c.exitCode) << c.what << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.what << ": " << r.err;
    EXPECT_EQ(entries(p.out), 0u) << c.what;
  }

  auto p = makeProject("build-cli-bad-output");
  // No store named anywhere.
  {
    std::string text = readFile(p.config);
    std::ofstream(p.dir / "nowhere.toml") << text.substr(0, text.find("output = "));
    auto r = runTinsmith("build " + (p.dir / "nowhere.toml").string());
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_NE(r.err.find("nowhere.toml, line 10: no tile store to write"), std::string::npos)
        << r.err;
  }
  // A store that would be its own TIN.
  {
    auto r = runTinsmith("build " + p.config.string() + " -o " + (p.out / "site.tin").string());
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_NE(r.err.find("has the name of the TIN"), std::string::npos) << r.err;
    EXPECT_EQ(entries(p.out), 0u);
  }
  // Unwritable outputs: a folder that does not exist, a file where a folder
  // should be.
  std::ofstream(p.dir / "plain.txt") << "x";
  for (const fs::path& out :
       {p.dir / "missing" / "site.3dtiles", p.dir / "plain.txt" / "site.3dtiles"}) {
    auto r = runTinsmith("build " + p.config.string() + " -o " + out.string());
    EXPECT_EQ(r.exitCode, 5) << out << ": " << r.err;
    EXPECT_NE(r.err.find(out.parent_path().string()), std::string::npos) << r.err;
  }

  // A run that fails after the TIN (the staging archive cannot be opened: a
  // folder has its name) keeps the store and TIN built before, byte for byte,
  // and leaves no partial TIN.
  auto good = runTinsmith("build " + p.config.string() + " -q");
  ASSERT_EQ(good.exitCode, 0) << good.err;
  const std::string store = readFile(p.out / "site.3dtiles");
  const std::string tin = readFile(p.out / "site.tin");
  fs::create_directories(p.out / "site.partial.3dtiles" / "blocker");
  auto late = runTinsmith("build " + p.config.string() + " --tolerance 2 -q");
  EXPECT_NE(late.exitCode, 0) << late.err;
  EXPECT_NE(late.err.find("site.partial.3dtiles"), std::string::npos) << late.err;
  EXPECT_EQ(readFile(p.out / "site.3dtiles"), store);
  EXPECT_EQ(readFile(p.out / "site.tin"), tin);
  EXPECT_FALSE(fs::exists(p.out / "site.partial.tin"));
  fs::remove_all(p.out / "site.partial.3dtiles");
  // And one with a bad option before any work.
  auto early = runTinsmith("build " + p.config.string() + " --max-triangles 10 -q");
  EXPECT_EQ(early.exitCode, 2) << early.err;
  EXPECT_EQ(readFile(p.out / "site.3dtiles"), store);
  EXPECT_EQ(entries(p.out), 2u);
}

TEST(BuildCli, ProgressNamesEachStageOnATerminal) {
  const auto p = makeProject("build-cli-progress");
  const std::string build = "build " + p.config.string();
  auto r = runTinsmith(build);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "progress drawn on a non-terminal";
  EXPECT_NE(r.err.find("wrote " + (p.out / "site.3dtiles").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("TIN build summary"), std::string::npos) << r.err;
  if (runCommand("command -v script").exitCode != 0)
    GTEST_SKIP() << "no `script` to make a terminal";
  // `script` runs the command on a pseudo-terminal; its output is the terminal's.
  r = runCommand("script -qec \"" + std::string(TINSMITH_BINARY) + " " + build + "\" /dev/null");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("\r\033[K1/2 TIN builders.tin"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\r\033[K2/2 tiles tiles.zoom"), std::string::npos) << r.out;
}

TEST(BuildCli, HelpNamesTheSharedTileOptionsAndTheTinBesideTheStore) {
  auto r = runTinsmith("build --help");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* option :
       {"--tolerance", "--max-triangles", "--max-zoom", "--lambda", "--compression", "--frame",
        "--geoid", "--threads", "--resume", "--json", "[tiles] tolerance", "STEM.tin"}) {
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  }
}

}  // namespace
}  // namespace tinsmith::test
