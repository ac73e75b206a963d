// AtomicFile and AtomicPath: the target appears whole or not at all, a temp
// file never outlives its writer, and two writers of one target each get
// their own temp file.
#include "ingest/base/atomic_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <set>

#include "core/base/error.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

TEST(AtomicPath, CommitRenamesTheTempFileOntoTheTarget) {
  const auto dir = test::scratchDir("atomic_path_commit");
  const auto target = dir / "out.tif";
  std::ofstream(target) << "old";
  AtomicPath out(target);
  EXPECT_EQ(out.temp().parent_path(), dir);
  EXPECT_TRUE(fs::exists(out.temp()));  // reserved: created empty
  EXPECT_EQ(test::readFile(target), "old");
  std::ofstream(out.temp(), std::ios::binary) << "new";
  out.commit();
  EXPECT_EQ(test::readFile(target), "new");
  EXPECT_EQ(test::filesIn(dir), 1u);
  EXPECT_THROW(out.commit(), Error);
}

TEST(AtomicPath, WithoutCommitTheTempFileGoesAndTheTargetStays) {
  const auto dir = test::scratchDir("atomic_path_abandon");
  const auto target = dir / "out.exr";
  std::ofstream(target) << "old";
  {
    AtomicPath out(target);
    std::ofstream(out.temp(), std::ios::binary) << "half";
  }
  EXPECT_EQ(test::readFile(target), "old");
  EXPECT_EQ(test::filesIn(dir), 1u);
  AtomicPath discarded(target);
  discarded.discard();
  EXPECT_FALSE(fs::exists(discarded.temp()));
}

TEST(AtomicPath, TwoWritersOfOneTargetDoNotCollide) {
  const auto dir = test::scratchDir("atomic_path_two");
  const auto target = dir / "out.tif";
  AtomicPath first(target);
  AtomicPath second(target);
  EXPECT_NE(first.temp(), second.temp());
  std::ofstream(first.temp(), std::ios::binary) << "first";
  std::ofstream(second.temp(), std::ios::binary) << "second";
  second.commit();
  EXPECT_EQ(test::readFile(target), "second");
  first.commit();  // the last to finish wins, whole
  EXPECT_EQ(test::readFile(target), "first");
  EXPECT_EQ(test::filesIn(dir), 1u);
}

TEST(AtomicPath, AKilledWritersTempIsRemovedByTheNextWriterOnItsHost) {
  const auto dir = test::scratchDir("atomic_path_killed");
  const auto target = dir / "site.tin";
  // A writer killed halfway (SIGKILL: no destructor runs).
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    AtomicFile file(target);
    file.write("half a tin");
    ::kill(::getpid(), SIGKILL);
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_EQ(test::filesIn(dir), 1u) << "the killed writer's temp";
  // What the next writer must leave: a temp from another host, one named the
  // old way (its writer unknown), and the temps of other targets.
  std::ofstream(dir / ".site.tin.other-host-1.a1b2c3.part") << "x";
  std::ofstream(dir / ".site.tin.q1w2e3.part") << "x";
  std::ofstream(dir / (".other.tin." + std::string("x-") + std::to_string(child) + ".a1b2c3.part"))
      << "x";
  AtomicPath next(target);
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  EXPECT_EQ(names.size(), 4u);
  EXPECT_TRUE(names.count(next.temp().filename().string()));
  EXPECT_TRUE(names.count(".site.tin.other-host-1.a1b2c3.part"));
  EXPECT_TRUE(names.count(".site.tin.q1w2e3.part"));
  // A live writer's temp (this process's) is kept by the writer after it.
  AtomicPath after(target);
  EXPECT_TRUE(fs::exists(next.temp()));
  EXPECT_TRUE(fs::exists(after.temp()));
}

TEST(AtomicPath, ARenameThatFailsRemovesTheTempFile) {
  const auto dir = test::scratchDir("atomic_path_rename");
  const auto target = dir / "taken";
  fs::create_directories(target / "inside");  // a non-empty directory: rename fails
  AtomicPath out(target);
  std::ofstream(out.temp(), std::ios::binary) << "bytes";
  try {
    out.commit();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_EQ(e.where().file, target.string());
  }
  EXPECT_EQ(test::filesIn(dir), 1u);
  EXPECT_TRUE(fs::is_directory(target));
}

TEST(AtomicPath, AMissingDirectoryIsAnIoErrorNamingIt) {
  const auto dir = test::scratchDir("atomic_path_missing");
  try {
    AtomicPath out(dir / "no-such-dir" / "out.tif");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_NE(std::string(e.what()).find("no-such-dir' does not exist"), std::string::npos)
        << e.what();
  }
}

TEST(AtomicFile, WritesWholeOrNothing) {
  const auto dir = test::scratchDir("atomic_file");
  const auto target = dir / "report.json";
  {
    AtomicFile file(target);
    file.write("{\"a\": 1}");
    EXPECT_EQ(test::filesIn(dir), 1u);  // only the temp file
    EXPECT_FALSE(fs::exists(target));
  }
  EXPECT_EQ(test::filesIn(dir), 0u);
  AtomicFile file(target);
  file.write("{\"a\": 2}");
  file.writeAt(6, "3", 1);
  file.commit();
  EXPECT_EQ(test::readFile(target), "{\"a\": 3}");
  EXPECT_EQ(test::filesIn(dir), 1u);
}

}  // namespace
}  // namespace tinsmith::ingest
