// Tile stores, both kinds: keys in and out, keys that could escape the root
// refused, stores that are not stores named in the error, deterministic
// writeStore output, resume, failed writes that leave nothing behind, and
// reads from several threads at once.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/base/error.hpp"
#include "ingest/store/store_detail.hpp"
#include "ingest/store/stored_tin.hpp"
#include "ingest/store/tile_store.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::store {
namespace {

namespace fs = std::filesystem;

// Bytes that are not text: every byte value, a NUL in the middle, and sizes
// around a SQLite page so that overflow pages are used.
std::string tileBytes(int seed, std::size_t size) {
  std::string bytes(size, '\0');
  std::uint32_t state = 2463534242u + static_cast<std::uint32_t>(seed);
  for (char& c : bytes) {
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    c = static_cast<char>(state & 0xFF);
  }
  return bytes;
}

struct Sample {
  std::vector<std::string> keys;
  std::vector<std::string> bytes;
};

// Deliberately not sorted: writeStore keeps the given order.
Sample sampleTiles() {
  Sample s;
  s.keys = {"tileset.json",         "tiles/0/0/0.glb", "tiles/1/1/0.glb",     "tiles/1/0/0.glb",
            "tinsmith/terrain.tin", "empty.bin",       "tiles/10/5/7%20x.glb"};
  const std::size_t sizes[] = {120, 5000, 4096, 1, 70000, 0, 333};
  for (std::size_t i = 0; i < s.keys.size(); ++i)
    s.bytes.push_back(tileBytes(static_cast<int>(i), sizes[i]));
  s.bytes[0] = R"({"asset":{"version":"1.1"}})";
  return s;
}

void fill(TileStore& store, const Sample& s) {
  for (std::size_t i = 0; i < s.keys.size(); ++i) store.put(s.keys[i], s.bytes[i]);
}

// Kind of an error thrown by `f`, and its message.
struct Thrown {
  std::optional<ErrorKind> kind;
  std::string message;
};
template <class F>
Thrown thrownBy(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return {e.kind(), e.what()};
  }
  return {};
}

// Every path under `dir`, relative, sorted.
std::vector<std::string> treeOf(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    out.push_back(entry.path().lexically_relative(dir).generic_string());
  std::sort(out.begin(), out.end());
  return out;
}

std::string nameFor(StoreKind kind) {
  return kind == StoreKind::Archive ? "t.3dtiles" : "t";
}

class TileStoreTest : public ::testing::TestWithParam<StoreKind> {
 protected:
  fs::path scratch(const std::string& name) {
    return test::scratchDir(std::string("store-") + name + "-" +
                            (GetParam() == StoreKind::Archive ? "archive" : "directory"));
  }
};

TEST(StoreKey, TheKeyRule) {
  for (const char* good : {"tileset.json", "tiles/3/2/5.glb", "a", "a/b/c", "%2e%2e/x", "a..b",
                           ".hidden", "a/.b", "a b/ü.glb"})
    EXPECT_TRUE(isValidKey(good)) << good;
  for (const std::string& bad :
       std::vector<std::string>({"../x", "a/../b", "/abs", "a\\b", "a//b", "", "a/./b", ".", "..",
                                 "a/", "a/..", std::string("a\0b", 3)}))
    EXPECT_FALSE(isValidKey(bad)) << bad;
}

TEST(StoreKind, ComesFromTheSuffix) {
  EXPECT_EQ(storeKindFor("out/site.3dtiles"), StoreKind::Archive);
  EXPECT_EQ(storeKindFor("SITE.3DTiles"), StoreKind::Archive);
  EXPECT_EQ(storeKindFor("out/site"), StoreKind::Directory);
  EXPECT_EQ(storeKindFor("site.3dtiles.d"), StoreKind::Directory);
  EXPECT_EQ(storeKindFor("site.mbtiles"), StoreKind::Directory);
}

TEST_P(TileStoreTest, PutGetContainsKeys) {
  const fs::path path = scratch("basic") / nameFor(GetParam());
  const Sample s = sampleTiles();
  {
    auto store = openStoreForWriting(path, false);
    EXPECT_EQ(store->kind(), GetParam());
    EXPECT_EQ(store->path(), path);
    EXPECT_TRUE(store->keys().empty());
    fill(*store, s);
    store->put("tiles/1/0/0.glb", "replaced");
    EXPECT_EQ(store->get("tiles/1/0/0.glb"), "replaced");
    EXPECT_EQ(store->get("tileset.json"), s.bytes[0]);
    EXPECT_FALSE(store->get("tiles/9/9/9.glb"));
    EXPECT_FALSE(store->get("tiles"));  // a folder in a directory store, not a key
  }
  auto store = openStoreForReading(path);
  EXPECT_EQ(store->kind(), GetParam());
  std::vector<std::string> sorted = s.keys;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(store->keys(), sorted);
  for (std::size_t i = 0; i < s.keys.size(); ++i) {
    EXPECT_TRUE(store->contains(s.keys[i])) << s.keys[i];
    const auto bytes = store->get(s.keys[i]);
    ASSERT_TRUE(bytes) << s.keys[i];
    EXPECT_EQ(*bytes, s.keys[i] == "tiles/1/0/0.glb" ? "replaced" : s.bytes[i]) << s.keys[i];
  }
  EXPECT_FALSE(store->contains("tiles/0/0"));
  EXPECT_FALSE(store->contains("nothing"));
}

TEST_P(TileStoreTest, InvalidKeysAreRefusedAndNothingIsWrittenOutsideTheRoot) {
  const fs::path dir = scratch("keys");
  const fs::path path = dir / "inner" / nameFor(GetParam());
  auto store = openStoreForWriting(path, false);
  const auto before = treeOf(dir);
  for (const std::string& key :
       std::vector<std::string>({"../x", "a/../b", "/abs", "a\\b", "a//b", "", "a/./b",
                                 std::string("a\0b", 3), "../../escaped", "/tmp/escaped"})) {
    const Thrown put = thrownBy([&] { store->put(key, "bytes"); });
    EXPECT_EQ(put.kind, ErrorKind::Input) << key << ": " << put.message;
    EXPECT_NE(put.message.find(path.string()), std::string::npos) << put.message;
    EXPECT_EQ(thrownBy([&] { (void)store->get(key); }).kind, ErrorKind::Input) << key;
    EXPECT_EQ(thrownBy([&] { (void)store->contains(key); }).kind, ErrorKind::Input) << key;
  }
  EXPECT_EQ(treeOf(dir), before);
  EXPECT_FALSE(fs::exists("/abs"));
  EXPECT_TRUE(store->keys().empty());
}

TEST_P(TileStoreTest, KeepExistingResumesAndFalseEmpties) {
  const fs::path path = scratch("resume") / nameFor(GetParam());
  {
    auto first = openStoreForWriting(path, false);
    first->put(kStoreMarkerKey, "{}");
    first->put("tiles/a.glb", "first");
  }
  {
    auto resumed = openStoreForWriting(path, true);
    EXPECT_EQ(resumed->get("tiles/a.glb"), "first");
    resumed->put("tiles/b/c.glb", "second");
  }
  EXPECT_EQ(openStoreForReading(path)->keys(),
            (std::vector<std::string>{"tiles/a.glb", "tiles/b/c.glb", "tinsmith/build.json"}));
  EXPECT_TRUE(openStoreForWriting(path, false)->keys().empty());
  EXPECT_TRUE(openStoreForReading(path)->keys().empty());
}

TEST_P(TileStoreTest, KeepExistingRefusesAStoreWithoutTheMarker) {
  const fs::path path = scratch("resume-foreign") / nameFor(GetParam());
  openStoreForWriting(path, false)->put("tiles/a.glb", "not marked");
  const Thrown thrown = thrownBy([&] { (void)openStoreForWriting(path, true); });
  EXPECT_EQ(thrown.kind, ErrorKind::Io) << thrown.message;
  EXPECT_NE(thrown.message.find("tinsmith/build.json"), std::string::npos) << thrown.message;
  EXPECT_EQ(openStoreForReading(path)->get("tiles/a.glb"), "not marked");
}

TEST_P(TileStoreTest, KeepExistingCreatesAMissingStoreAndItsParents) {
  const fs::path path = scratch("create") / "x" / "y" / nameFor(GetParam());
  openStoreForWriting(path, true)->put("k", "v");
  EXPECT_EQ(openStoreForReading(path)->get("k"), "v");
}

TEST_P(TileStoreTest, PutOnAStoreOpenedForReadingIsAUsageError) {
  const fs::path path = scratch("readonly") / nameFor(GetParam());
  openStoreForWriting(path, false)->put("k", "v");
  auto store = openStoreForReading(path);
  EXPECT_EQ(thrownBy([&] { store->put("k", "w"); }).kind, ErrorKind::Usage);
  EXPECT_EQ(store->get("k"), "v");
}

TEST_P(TileStoreTest, WritingUnderARegularFileIsAnIoError) {
  const fs::path dir = scratch("under-file");
  std::ofstream(dir / "plain.txt") << "a file, not a folder\n";
  const fs::path path = dir / "plain.txt" / "sub" / nameFor(GetParam());
  const Thrown open = thrownBy([&] { (void)openStoreForWriting(path, false); });
  EXPECT_EQ(open.kind, ErrorKind::Io) << open.message;
  EXPECT_NE(open.message.find(path.string()), std::string::npos) << open.message;

  const fs::path source = dir / "source.3dtiles";
  openStoreForWriting(source, false)->put("k", "v");
  const std::vector<std::string> keys = {"k"};
  const Thrown write = thrownBy([&] { writeStore(*openStoreForReading(source), keys, path); });
  EXPECT_EQ(write.kind, ErrorKind::Io) << write.message;
  EXPECT_NE(write.message.find(path.string()), std::string::npos) << write.message;
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"plain.txt", "source.3dtiles"}));
}

TEST_P(TileStoreTest, WriteStoreIsDeterministicAndKeepsTheGivenKeys) {
  const fs::path dir = scratch("write");
  const Sample s = sampleTiles();
  // Two sources of either kind, filled in different orders, with an extra key
  // that is not copied.
  const fs::path sourceA = dir / "a.3dtiles";
  const fs::path sourceB = dir / "b";
  {
    auto a = openStoreForWriting(sourceA, false);
    fill(*a, s);
    a->put("extra", "not copied");
    auto b = openStoreForWriting(sourceB, false);
    for (std::size_t i = s.keys.size(); i-- > 0;) b->put(s.keys[i], s.bytes[i]);
  }
  const fs::path first = dir / ("first-" + nameFor(GetParam()));
  const fs::path second = dir / "out" / ("second-" + nameFor(GetParam()));
  writeStore(*openStoreForReading(sourceA), s.keys, first);
  writeStore(*openStoreForReading(sourceB), s.keys, second);

  auto out = openStoreForReading(first);
  std::vector<std::string> sorted = s.keys;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(out->keys(), sorted);
  for (std::size_t i = 0; i < s.keys.size(); ++i) EXPECT_EQ(out->get(s.keys[i]), s.bytes[i]);
  if (GetParam() == StoreKind::Archive) {
    EXPECT_EQ(test::readFile(first), test::readFile(second));
  } else {
    EXPECT_EQ(treeOf(first), treeOf(second));
    for (const std::string& key : s.keys)
      EXPECT_EQ(test::readFile(first / key), test::readFile(second / key)) << key;
  }
  // Nothing but the outputs and the sources: no temporary files or folders,
  // no SQLite journals.
  const auto namesIn = [](const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  };
  EXPECT_EQ(namesIn(dir),
            (std::vector<std::string>{"a.3dtiles", "b", first.filename().string(), "out"}));
  EXPECT_EQ(namesIn(dir / "out"), (std::vector<std::string>{second.filename().string()}));
}

TEST_P(TileStoreTest, WriteStoreReplacesAnExistingTarget) {
  const fs::path dir = scratch("replace");
  const fs::path source = dir / "s.3dtiles";
  openStoreForWriting(source, false)->put("tiles/new.glb", "new");
  const fs::path target = dir / nameFor(GetParam());
  {
    auto old = openStoreForWriting(target, false);
    old->put(kStoreMarkerKey, "{}");
    old->put("tiles/old.glb", "old");
  }
  const std::vector<std::string> keys = {"tiles/new.glb"};
  writeStore(*openStoreForReading(source), keys, target);
  EXPECT_EQ(openStoreForReading(target)->keys(), keys);
  EXPECT_EQ(treeOf(dir).size(), GetParam() == StoreKind::Archive ? 2u : 4u);
}

TEST_P(TileStoreTest, NothingButAStoreIsEverReplacedOrEmptied) {
  const fs::path dir = scratch("foreign");
  const fs::path source = dir / "s.3dtiles";
  openStoreForWriting(source, false)->put("tiles/new.glb", "new");
  const std::vector<std::string> keys = {"tiles/new.glb"};
  // A store's keys but no marker; a marker and a user's file as well.
  for (const bool marked : {false, true}) {
    const fs::path target = dir / ((marked ? "marked-" : "plain-") + nameFor(GetParam()));
    {
      auto st = openStoreForWriting(target, false);
      st->put("tiles/old.glb", "old");
      if (marked) {
        st->put(kStoreMarkerKey, "{}");
        st->put("notes.txt", "the user's");
      }
    }
    const auto before = treeOf(dir);
    const std::string archiveBefore =
        GetParam() == StoreKind::Archive ? test::readFile(target) : std::string();
    for (const Thrown& t :
         {thrownBy([&] { writeStore(*openStoreForReading(source), keys, target); }),
          thrownBy([&] { (void)openStoreForWriting(target, false); }),
          thrownBy([&] { requireReplaceable(target); })}) {
      EXPECT_EQ(t.kind, ErrorKind::Io) << t.message;
      EXPECT_NE(t.message.find(target.string()), std::string::npos) << t.message;
      EXPECT_NE(t.message.find(marked ? "notes.txt" : "tinsmith/build.json"), std::string::npos)
          << t.message;
    }
    EXPECT_EQ(treeOf(dir), before);
    if (GetParam() == StoreKind::Archive) {
      EXPECT_EQ(test::readFile(target), archiveBefore);
    }
    EXPECT_EQ(openStoreForReading(target)->get("tiles/old.glb"), "old");
  }
}

TEST_P(TileStoreTest, WriteStoreWithAMissingKeyIsAnInputErrorAndLeavesNoTarget) {
  const fs::path dir = scratch("missing-key");
  const fs::path source = dir / "s";
  openStoreForWriting(source, false)->put("here.glb", "x");
  const fs::path target = dir / nameFor(GetParam());
  const std::vector<std::string> keys = {"here.glb", "gone.glb"};
  const Thrown thrown = thrownBy([&] { writeStore(*openStoreForReading(source), keys, target); });
  EXPECT_EQ(thrown.kind, ErrorKind::Input) << thrown.message;
  EXPECT_NE(thrown.message.find("gone.glb"), std::string::npos) << thrown.message;
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"s", "s/here.glb"}));

  const std::vector<std::string> twice = {"here.glb", "here.glb"};
  EXPECT_EQ(thrownBy([&] { writeStore(*openStoreForReading(source), twice, target); }).kind,
            ErrorKind::Input);
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"s", "s/here.glb"}));
}

TEST_P(TileStoreTest, ATinLargerThanAPieceIsStoredInPiecesAndReadWhole) {
  const fs::path dir = scratch("tin-pieces");
  const std::string small = tileBytes(7, 4096), large = tileBytes(8, 10000);
  auto store = openStoreForWriting(dir / nameFor(GetParam()), false);
  EXPECT_FALSE(holdsTin(*store));
  EXPECT_FALSE(getTin(*store));
  EXPECT_TRUE(storedTinKeys(*store).empty());
  // Within a piece: one value under its own key, as every store had it.
  putTin(*store, small, 4096);
  EXPECT_EQ(store->keys(), std::vector<std::string>{"tinsmith/terrain.tin"});
  EXPECT_EQ(getTin(*store), small);

  auto pieces = openStoreForWriting(dir / ("p-" + nameFor(GetParam())), false);
  putTin(*pieces, large, 4096);
  const std::vector<std::string> keys{"tinsmith/terrain.tin.0000", "tinsmith/terrain.tin.0001",
                                      "tinsmith/terrain.tin.0002"};
  EXPECT_EQ(pieces->keys(), keys);
  EXPECT_EQ(storedTinKeys(*pieces), keys);
  EXPECT_EQ(pieces->get(keys[0]), large.substr(0, 4096));
  EXPECT_EQ(pieces->get(keys[2]), large.substr(8192));
  EXPECT_TRUE(holdsTin(*pieces));
  EXPECT_EQ(getTin(*pieces), large);

  // Copied as stored, into the other kind too.
  for (const std::string name : {"c.3dtiles", "c"}) {
    auto copy = openStoreForWriting(dir / name, false);
    EXPECT_TRUE(copyTin(*pieces, *copy));
    EXPECT_EQ(copy->keys(), keys) << name;
    EXPECT_EQ(getTin(*copy), large) << name;
    EXPECT_FALSE(copyTin(*openStoreForWriting(dir / ("empty-" + name), false), *copy));
  }
}

TEST_P(TileStoreTest, ATinWhosePieceZeroIsMissingIsNoTin) {
  // Piece 0 is written last: a put cut short before it leaves pieces that
  // do not count, and the next put writes them all again.
  const std::string large = tileBytes(9, 9000);
  auto store = openStoreForWriting(scratch("tin-cut") / nameFor(GetParam()), false);
  store->put("tinsmith/terrain.tin.0001", large.substr(4096, 4096));
  store->put("tinsmith/terrain.tin.0002", large.substr(8192));
  EXPECT_FALSE(holdsTin(*store));
  EXPECT_FALSE(getTin(*store));
  EXPECT_TRUE(storedTinKeys(*store).empty());
  putTin(*store, large, 4096);
  EXPECT_EQ(getTin(*store), large);
}

TEST_P(TileStoreTest, ALargeValueIsWrittenAndReadAPieceAtATime) {
  // A TIN's piece is up to 256 MiB: it is put, copied and written into a
  // finished store a few MiB at a time, never held whole.
  const fs::path dir = scratch("pieces");
  const std::string big = tileBytes(21, 2 * kCopyPieceBytes + 12345);
  const std::string key = "tinsmith/terrain.tin";
  auto store = openStoreForWriting(dir / nameFor(GetParam()), false);
  store->put(kStoreMarkerKey, "{}");
  std::vector<std::uint64_t> offsets;
  const auto fromBig = [&](std::uint64_t offset, std::span<char> piece) {
    offsets.push_back(offset);
    EXPECT_LE(piece.size(), kCopyPieceBytes);
    big.copy(piece.data(), piece.size(), offset);
  };
  store->putInPieces(key, big.size(), fromBig);
  EXPECT_EQ(offsets, (std::vector<std::uint64_t>{0, kCopyPieceBytes, 2 * kCopyPieceBytes}));
  EXPECT_EQ(store->size(key), big.size());
  EXPECT_EQ(store->get(key), big);
  EXPECT_EQ(store->size("tiles/none.glb"), std::nullopt);
  EXPECT_EQ(store->size(kStoreMarkerKey), 2u);
  std::string part(1000, '\0');
  store->read(key, kCopyPieceBytes - 10, part);
  EXPECT_EQ(part, big.substr(kCopyPieceBytes - 10, 1000));
  store->read(key, big.size() - part.size(), part);
  EXPECT_EQ(part, big.substr(big.size() - part.size()));
  const Thrown pastTheEnd = thrownBy([&] { store->read(key, big.size() - 999, part); });
  EXPECT_EQ(pastTheEnd.kind, ErrorKind::Io);
  EXPECT_NE(pastTheEnd.message.find("ends at byte " + std::to_string(big.size())),
            std::string::npos)
      << pastTheEnd.message;
  EXPECT_EQ(thrownBy([&] { store->read("tiles/none.glb", 0, part); }).kind, ErrorKind::Io);

  // A filler that fails half way leaves the old value, and no file of the
  // new one.
  const auto before = GetParam() == StoreKind::Directory ? treeOf(dir / nameFor(GetParam()))
                                                         : std::vector<std::string>{};
  const Thrown failed = thrownBy([&] {
    store->putInPieces(key, big.size(), [&](std::uint64_t offset, std::span<char> piece) {
      if (offset > 0) throw ioError("the source went away");
      std::fill(piece.begin(), piece.end(), 'x');
    });
  });
  EXPECT_EQ(failed.kind, ErrorKind::Io);
  EXPECT_NE(failed.message.find("the source went away"), std::string::npos);
  EXPECT_EQ(store->get(key), big);
  if (GetParam() == StoreKind::Directory) {
    EXPECT_EQ(treeOf(dir / nameFor(GetParam())), before);
  }
  const std::string other = tileBytes(22, kCopyPieceBytes + 1);  // replaces, shorter
  store->putInPieces(key, other.size(), [&](std::uint64_t offset, std::span<char> piece) {
    other.copy(piece.data(), piece.size(), offset);
  });
  EXPECT_EQ(store->get(key), other);
  store->putInPieces(key, big.size(), fromBig);

  // Copied into both kinds, by copyValue and by writeStore (twice: the same
  // bytes), beside small values.
  store->put("tiles/0/0/0.glb", tileBytes(23, 5000));
  const std::vector<std::string> keys{std::string(kStoreMarkerKey), key, "tiles/0/0/0.glb"};
  for (const std::string name : {"c.3dtiles", "c"}) {
    auto copy = openStoreForWriting(dir / name, false);
    for (const std::string& k : keys) copyValue(*store, k, *copy);
    for (const std::string& k : keys) EXPECT_EQ(copy->get(k), store->get(k)) << name << " " << k;
    const fs::path first = dir / ("w1-" + name), second = dir / ("w2-" + name);
    writeStore(*copy, keys, first);
    writeStore(*store, keys, second);
    auto written = openStoreForReading(first);
    EXPECT_EQ(written->get(key), big) << name;
    if (name == "c.3dtiles") {
      EXPECT_EQ(test::readFile(first), test::readFile(second));
    }
  }
  EXPECT_EQ(thrownBy([&] {
              auto copy = openStoreForWriting(dir / "d", false);
              copyValue(*store, "tiles/none.glb", *copy);
            }).kind,
            ErrorKind::Input);
  EXPECT_EQ(thrownBy([&] {
              openStoreForReading(dir / nameFor(GetParam()))->putInPieces(key, 10, fromBig);
            }).kind,
            ErrorKind::Usage);
}

INSTANTIATE_TEST_SUITE_P(Kinds, TileStoreTest,
                         ::testing::Values(StoreKind::Archive, StoreKind::Directory),
                         [](const auto& info) {
                           return info.param == StoreKind::Archive ? "Archive" : "Directory";
                         });

TEST(OpenStore, AMissingPathIsAnInputErrorNamingIt) {
  const fs::path dir = test::scratchDir("store-open-missing");
  for (const fs::path& path : {dir / "none.3dtiles", dir / "none"}) {
    const Thrown thrown = thrownBy([&] { (void)openStoreForReading(path); });
    EXPECT_EQ(thrown.kind, ErrorKind::Input);
    EXPECT_NE(thrown.message.find(path.string()), std::string::npos) << thrown.message;
    EXPECT_NE(thrown.message.find("does not exist"), std::string::npos) << thrown.message;
  }
  EXPECT_TRUE(treeOf(dir).empty());  // reading creates nothing
}

TEST(OpenStore, ATextFileNamedLikeAnArchiveIsAnInputError) {
  const fs::path dir = test::scratchDir("store-open-text");
  const fs::path path = dir / "x.3dtiles";
  std::ofstream(path) << "this is a text file, long enough to have a header's worth of bytes in "
                         "it, and then some more text to be sure.\n";
  const Thrown thrown = thrownBy([&] { (void)openStoreForReading(path); });
  EXPECT_EQ(thrown.kind, ErrorKind::Input);
  EXPECT_NE(thrown.message.find(path.string()), std::string::npos) << thrown.message;
  EXPECT_NE(thrown.message.find("not a SQLite database"), std::string::npos) << thrown.message;
  // Resuming onto it is refused too, and the file is untouched.
  EXPECT_EQ(thrownBy([&] { (void)openStoreForWriting(path, true); }).kind, ErrorKind::Io);
  EXPECT_EQ(test::readFile(path).substr(0, 9), "this is a");
}

TEST(OpenStore, ASqliteFileWithoutMediaIsAnInputError) {
  const fs::path dir = test::scratchDir("store-open-nomedia");
  const fs::path path = dir / "other.3dtiles";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE tiles (x INTEGER)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const Thrown thrown = thrownBy([&] { (void)openStoreForReading(path); });
  EXPECT_EQ(thrown.kind, ErrorKind::Input);
  EXPECT_NE(thrown.message.find(path.string()), std::string::npos) << thrown.message;
  EXPECT_NE(thrown.message.find("no media table"), std::string::npos) << thrown.message;
  EXPECT_EQ(thrownBy([&] { (void)openStoreForWriting(path, true); }).kind, ErrorKind::Io);
}

TEST(ArchiveStore, AnotherToolsTextValueAndATableWithoutRowidsAreSizedAndReadInBytes) {
  // length() counts a text's characters; a WITHOUT ROWID table has no blob
  // handles: both are still sized and read by the byte.
  const fs::path dir = test::scratchDir("store-text");
  const std::string text = "\xC3\xA9\xE2\x82\xACx";  // "é€x": 3 characters, 6 bytes
  for (const std::string table :
       {"CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB)",
        "CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB) WITHOUT ROWID"}) {
    const fs::path path = dir / (table.ends_with("ROWID") ? "norowid.3dtiles" : "rowid.3dtiles");
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    const std::string sql = table + "; INSERT INTO media VALUES ('tileset.json', '" + text +
                            "'), ('tiles/0/0/0.glb', x'00ff10');";
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
    auto store = openStoreForReading(path);
    EXPECT_EQ(store->size("tileset.json"), 6u) << path;
    EXPECT_EQ(store->size("tiles/0/0/0.glb"), 3u) << path;
    std::string part(4, '\0');
    store->read("tileset.json", 2, part);
    EXPECT_EQ(part, text.substr(2)) << path;
    EXPECT_EQ(thrownBy([&] { store->read("tileset.json", 3, part); }).kind, ErrorKind::Io);
    auto copy = openStoreForWriting(dir / (path.stem().string() + "-copy"), false);
    copyValue(*store, "tileset.json", *copy);
    EXPECT_EQ(copy->get("tileset.json"), text) << path;
  }
}

TEST(OpenStore, AFileWhereAFolderStoreIsExpectedIsAnInputError) {
  const fs::path dir = test::scratchDir("store-open-file");
  std::ofstream(dir / "tiles.zip") << "zip?";
  const Thrown thrown = thrownBy([&] { (void)openStoreForReading(dir / "tiles.zip"); });
  EXPECT_EQ(thrown.kind, ErrorKind::Input);
  EXPECT_NE(thrown.message.find("tiles.zip"), std::string::npos) << thrown.message;
}

// The final archive: the schema 3d-tiles-tools reads, rows in the given order,
// a rollback-journal header (not WAL), and no files beside it.
TEST(ArchiveStore, AValueOverSqlitesLimitIsAnErrorNotANull) {
  // 10⁹ + 1 bytes of untouched anonymous memory (no page is read: SQLite
  // refuses the length first). The archive used to store NULL in its place
  // and go on: a 22 M-vertex TIN left an empty tinsmith/terrain.tin.
  const std::size_t size = 1'000'000'001;
  void* pages = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(pages, MAP_FAILED);
  const fs::path path = test::scratchDir("store-too-big") / "t.3dtiles";
  auto store = openStoreForWriting(path, false);
  const Thrown thrown = thrownBy([&] {
    store->put("tinsmith/terrain.tin", {static_cast<const char*>(pages), size});
  });
  munmap(pages, size);
  EXPECT_EQ(thrown.kind, ErrorKind::Io);
  EXPECT_NE(thrown.message.find("tinsmith/terrain.tin"), std::string::npos) << thrown.message;
  EXPECT_NE(thrown.message.find("too big"), std::string::npos) << thrown.message;
  EXPECT_FALSE(store->contains("tinsmith/terrain.tin"));
}

TEST(ArchiveStore, WriteStoreMakesAPlainArchive) {
  const fs::path dir = test::scratchDir("store-archive-plain");
  const Sample s = sampleTiles();
  const fs::path staging = dir / "staging.3dtiles";
  fill(*openStoreForWriting(staging, false), s);
  const fs::path target = dir / "final.3dtiles";
  writeStore(*openStoreForReading(staging), s.keys, target);

  const std::string bytes = test::readFile(target);
  ASSERT_GE(bytes.size(), 100u);
  EXPECT_EQ(bytes.substr(0, 16), std::string("SQLite format 3\0", 16));
  EXPECT_EQ(static_cast<unsigned char>(bytes[16]) * 256 + static_cast<unsigned char>(bytes[17]),
            4096);
  EXPECT_EQ(bytes[18], 1);  // write version: legacy, not WAL
  EXPECT_EQ(bytes[19], 1);
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"final.3dtiles", "staging.3dtiles"}));

  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(target.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT sql FROM sqlite_master WHERE name = 'media'", -1, &stmt,
                               nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0)),
               "CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB)");
  sqlite3_finalize(stmt);
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT key, typeof(content) FROM media ORDER BY rowid", -1,
                               &stmt, nullptr),
            SQLITE_OK);
  std::vector<std::string> order;
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    order.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0)));
    EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1)), "blob");
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  EXPECT_EQ(order, s.keys);
}

TEST(ArchiveStore, EightThreadsReadOneStoreAtOnce) {
  const fs::path path = test::scratchDir("store-archive-threads") / "t.3dtiles";
  const Sample s = sampleTiles();
  fill(*openStoreForWriting(path, false), s);
  const auto store = openStoreForReading(path);
  std::atomic<int> wrong{0};
  std::atomic<int> reads{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int round = 0; round < 200; ++round) {
        const std::size_t i = static_cast<std::size_t>(t + round) % s.keys.size();
        const auto bytes = store->get(s.keys[i]);
        if (!bytes || *bytes != s.bytes[i]) ++wrong;
        if (store->get("absent/key")) ++wrong;
        ++reads;
      }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(reads.load(), 8 * 200);
}

TEST(ArchiveStore, AReaderSeesPutsOfAStagingArchiveAsTheyCommit) {
  const fs::path dir = test::scratchDir("store-archive-staging");
  const fs::path path = dir / "t.3dtiles";
  {
    auto writer = openStoreForWriting(path, false);
    writer->put("a", "1");
    auto reader = openStoreForReading(path);
    EXPECT_EQ(reader->get("a"), "1");
    writer->put("b", std::string(100000, 'b'));
    EXPECT_EQ(reader->get("b"), std::string(100000, 'b'));
    writer->put("a", "2");
    EXPECT_EQ(reader->get("a"), "2");
  }
  // Closed cleanly: no -wal or -shm left, and it still opens read-only.
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"t.3dtiles"}));
  EXPECT_EQ(openStoreForReading(path)->keys(), (std::vector<std::string>{"a", "b"}));
}

TEST(DirectoryStore, KeysSkipTemporaryFiles) {
  const fs::path root = test::scratchDir("store-directory-temp") / "t";
  auto store = openStoreForWriting(root, false);
  store->put("tiles/a.glb", "a");
  std::ofstream(root / "tiles" / "b.glb.tmp-123-4") << "half";
  fs::create_directories(root / "t.tmp-9-9" / "x");
  std::ofstream(root / "t.tmp-9-9" / "x" / "c.glb") << "staged";
  EXPECT_EQ(store->keys(), (std::vector<std::string>{"tiles/a.glb"}));
  EXPECT_EQ(thrownBy([&] { store->put("z.glb.tmp-1-2", "x"); }).kind, ErrorKind::Input);
  // A put leaves only its file.
  store->put("tiles/b.glb", "b");
  EXPECT_EQ(treeOf(root / "tiles"),
            (std::vector<std::string>{"a.glb", "b.glb", "b.glb.tmp-123-4"}));
}

TEST(StoreKey, StoreKeysAreTheTilesetsTilesTerrainAndTinsmithFolders) {
  for (const char* key :
       {"tileset.json", "tiles/0/0/0.glb", "tilesets/1/0/0.json", "tinsmith/build.json",
        "tinsmith/terrain.tin", "terrain/layer.json", "terrain/0/1/0.terrain"})
    EXPECT_TRUE(isStoreKey(key)) << key;
  for (const char* key : {"index.html", "tiles", "tiles/", "tileset.json.bak", "a/tileset.json",
                          "tinsmithx/build.json", "terrain", "terrain/"})
    EXPECT_FALSE(isStoreKey(key)) << key;
}

TEST(Replaceable, OnlyNothingAnEmptyFolderOrAStoreMayBeReplaced) {
  const fs::path dir = test::scratchDir("replaceable");
  EXPECT_NO_THROW(requireReplaceable(dir / "absent"));
  EXPECT_NO_THROW(requireReplaceable(dir / "absent.3dtiles"));
  fs::create_directories(dir / "empty" / "sub");
  EXPECT_NO_THROW(requireReplaceable(dir / "empty"));
  // Temporary files of a put and a store's own keys.
  fs::create_directories(dir / "store" / "tinsmith");
  fs::create_directories(dir / "store" / "tiles" / "0" / "0");
  std::ofstream(dir / "store" / "tinsmith" / "build.json") << "{}";
  std::ofstream(dir / "store" / "tiles" / "0" / "0" / "0.glb") << "glb";
  std::ofstream(dir / "store" / "tiles" / "0" / "0" / "1.glb.tmp-123-4") << "half";
  EXPECT_NO_THROW(requireReplaceable(dir / "store"));
  EXPECT_NO_THROW(requireReplaceable(dir / "store/"));

  const auto refused = [](const fs::path& path, const std::string& expected) {
    const Thrown t = thrownBy([&] { requireReplaceable(path); });
    EXPECT_EQ(t.kind, ErrorKind::Io) << path;
    EXPECT_NE(t.message.find(expected), std::string::npos) << t.message;
  };
  fs::create_directories(dir / "home" / "photos");
  std::ofstream(dir / "home" / "photos" / "a.jpg") << "a";
  std::ofstream(dir / "home" / "b.txt") << "b";
  std::ofstream(dir / "home" / "c.txt") << "c";
  refused(dir / "home", "and 2 other files");
  fs::create_directory_symlink(dir / "store", dir / "link");
  refused(dir / "link", "symbolic link");
  std::ofstream(dir / "plain") << "a file";
  refused(dir / "plain", "is a file");
  std::ofstream(dir / "text.3dtiles") << "not SQLite";
  refused(dir / "text.3dtiles", "not a tinsmith tile archive");
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "other.3dtiles").c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB);"
                           "INSERT INTO media VALUES ('tileset.json', '{}');",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  }
  refused(dir / "other.3dtiles", "no tinsmith/build.json");
}

TEST(MoveStore, AFolderStoreTakesTheNameAndTheOldOneGoes) {
  const fs::path dir = test::scratchDir("move-store");
  const auto makeStore = [](const fs::path& path, const std::string& tile) {
    auto st = openStoreForWriting(path, false);
    st->put(kStoreMarkerKey, "{}");
    st->put("tiles/" + tile + ".glb", tile);
  };
  makeStore(dir / "site", "old");
  makeStore(dir / "site.partial", "new");
  moveStore(dir / "site.partial", dir / "site");
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{"site", "site/tiles", "site/tiles/new.glb",
                                                   "site/tinsmith", "site/tinsmith/build.json"}));
  // A target that is not a store: both stay as they were.
  makeStore(dir / "staged", "newer");
  fs::create_directories(dir / "mine");
  std::ofstream(dir / "mine" / "thesis.tex") << "years of work";
  const Thrown t = thrownBy([&] { moveStore(dir / "staged", dir / "mine"); });
  EXPECT_EQ(t.kind, ErrorKind::Io) << t.message;
  EXPECT_NE(t.message.find("thesis.tex"), std::string::npos) << t.message;
  EXPECT_EQ(test::readFile(dir / "mine" / "thesis.tex"), "years of work");
  EXPECT_EQ(openStoreForReading(dir / "staged")->get("tiles/newer.glb"), "newer");
}

TEST(StaleTemps, OnlyTheLeftoversOfProcessesThatAreGoneAreRemoved) {
  const fs::path dir = test::scratchDir("stale-temps");
  // A pid no process has (above the kernel's pid_max) and init's, which runs.
  const std::string gone = "4194399", alive = "1";
  std::ofstream(dir / "site.3dtiles") << "x";
  for (const std::string& name : std::vector<std::string>{
           "site.3dtiles.tmp-" + gone + "-0", "site.3dtiles.tmp-" + gone + "-0-journal",
           "site.3dtiles.tmp-" + alive + "-3", "other.3dtiles.tmp-" + gone + "-1",
           "site.3dtiles.tmp-x-1"})
    std::ofstream(dir / name) << "x";
  fs::create_directories(dir / ("site.3dtiles.tmp-" + gone + "-7") / "tiles");
  removeStaleTemps(dir / "site.3dtiles");
  EXPECT_EQ(treeOf(dir),
            (std::vector<std::string>{"other.3dtiles.tmp-" + gone + "-1", "site.3dtiles",
                                      "site.3dtiles.tmp-" + alive + "-3", "site.3dtiles.tmp-x-1"}));
}

TEST(StaleTemps, AWriterOnAnotherMachineIsNeverTakenForGone) {
  // On a shared filesystem a process id means a process on the machine that
  // named the file: another machine's writer, whatever its id, may still run.
  const fs::path dir = test::scratchDir("stale-temps-hosts");
  const std::string gone = "4194399", here = detail::thisHostTag();
  const std::string elsewhere = here == "0badf00d" ? "0badf00e" : "0badf00d";
  ASSERT_EQ(here.size(), 8u);
  std::ofstream(dir / "site.3dtiles") << "x";
  for (const std::string& name :
       std::vector<std::string>{"site.3dtiles.tmp-" + gone + "-0." + here,
                                "site.3dtiles.tmp-" + gone + "-0." + here + "-wal",
                                "site.3dtiles.tmp-" + gone + "-1." + elsewhere,
                                "site.3dtiles.tmp-" + gone + "-1." + elsewhere + "-shm"})
    std::ofstream(dir / name) << "x";
  removeStaleTemps(dir / "site.3dtiles");
  EXPECT_EQ(treeOf(dir), (std::vector<std::string>{
                             "site.3dtiles", "site.3dtiles.tmp-" + gone + "-1." + elsewhere,
                             "site.3dtiles.tmp-" + gone + "-1." + elsewhere + "-shm"}));
  // This process names its own temporaries with its machine's tag.
  const auto writer =
      detail::tempWriter(detail::tempSibling(dir / "a.3dtiles").filename().string());
  ASSERT_TRUE(writer);
  EXPECT_EQ(writer->pid, static_cast<long>(::getpid()));
  EXPECT_EQ(writer->host, here);
}

}  // namespace
}  // namespace tinsmith::store
