// core/base/parallel.hpp: the split of the work depends on the input size and
// the part count only, every item is visited once, and a worker's exception
// reaches the caller after all parts have finished.
#include "core/base/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <utility>
#include <vector>

namespace tinsmith {
namespace {

std::vector<std::pair<std::size_t, std::size_t>> ranges(std::size_t n, unsigned parts, unsigned threads) {
  std::vector<std::pair<std::size_t, std::size_t>> r(parts);
  parallelParts(n, parts, threads, [&](std::size_t b, std::size_t e, unsigned part) { r[part] = {b, e}; });
  return r;
}

TEST(Parallel, ThePartsDependOnTheSizeAndPartCountNotOnTheThreads) {
  for (const std::size_t n : {0u, 1u, 7u, 100u, 100001u}) {
    for (const unsigned parts : {1u, 2u, 3u, 8u}) {
      const auto one = ranges(n, parts, 1);
      EXPECT_EQ(ranges(n, parts, 2), one);
      EXPECT_EQ(ranges(n, parts, 16), one);
      std::size_t next = 0;  // contiguous, in order, covering [0, n)
      for (const auto& [b, e] : one) {
        EXPECT_EQ(b, next);
        EXPECT_LE(b, e);
        next = e;
      }
      EXPECT_EQ(next, n);
    }
  }
}

TEST(Parallel, EveryItemIsVisitedOnce) {
  std::vector<std::atomic<int>> seen(50000);
  parallelParts(seen.size(), 7, 4, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t i = b; i < e; ++i) ++seen[i];
  });
  for (const auto& s : seen) ASSERT_EQ(s.load(), 1);
}

TEST(Parallel, TheFirstPartsExceptionIsRethrownAfterAllParts) {
  std::atomic<int> finished{0};
  try {
    parallelParts(1000, 4, 4, [&](std::size_t, std::size_t, unsigned part) {
      ++finished;
      if (part >= 2) throw std::runtime_error("part " + std::to_string(part));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "part 2");
  }
  EXPECT_EQ(finished.load(), 4);
}

TEST(Parallel, RunWorkersRethrowsAndZeroThreadsMeansEveryCore) {
  EXPECT_GE(resolveThreads(0), 1u);
  EXPECT_EQ(resolveThreads(-3), resolveThreads(0));
  EXPECT_EQ(resolveThreads(5), 5u);
  std::atomic<int> ran{0};
  EXPECT_THROW(runWorkers(3,
                          [&] {
                            if (++ran == 2) throw std::logic_error("worker");
                          }),
               std::logic_error);
  EXPECT_EQ(ran.load(), 3);
}

}  // namespace
}  // namespace tinsmith
