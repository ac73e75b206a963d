// The one threading convention of tinsmith. Every options struct with a
// `threads` field reads it the same way (0: every core; n: n threads) through
// resolveThreads(), and data-parallel loops run through parallelParts(),
// whose split of the work depends only on the input size and a part count
// the caller fixes — never on how many threads run it — so that results
// combined in part order are the same bytes for any thread count.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tinsmith {

/// The number of threads a `threads` option asks for: 0 (or less) means every
/// core the machine reports (at least 1); a positive value is taken as is.
[[nodiscard]] inline unsigned resolveThreads(long long requested) {
  if (requested > 0) return static_cast<unsigned>(requested);
  return std::max(1u, std::thread::hardware_concurrency());
}

/// Runs f(begin, end, part) for part = 0 … parts − 1 over contiguous ranges
/// of [0, n) of ceil(n / parts) items each (the last ones shorter or empty),
/// on up to `threads` threads, the calling thread included. Below
/// `serialBelow` items everything runs on the calling thread, in part order.
/// If f throws, the first exception (in part order) is rethrown after every
/// part has finished.
template <class F>
void parallelParts(std::size_t n, unsigned parts, unsigned threads, F&& f,
                   std::size_t serialBelow = 0) {
  if (parts == 0) return;
  const std::size_t chunk = (n + parts - 1) / parts;
  auto run = [&](unsigned part) {
    const std::size_t b = std::min(n, chunk * part);
    f(b, std::min(n, b + chunk), part);
  };
  if (threads <= 1 || parts == 1 || n < serialBelow) {
    for (unsigned part = 0; part < parts; ++part) run(part);
    return;
  }
  const unsigned workers = std::min(threads, parts);
  std::vector<std::exception_ptr> errors(parts);
  auto work = [&](unsigned first) {
    for (unsigned part = first; part < parts; part += workers) {
      try {
        run(part);
      } catch (...) {
        errors[part] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (unsigned w = 1; w < workers; ++w) pool.emplace_back(work, w);
  work(0);
  for (auto& t : pool) t.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

/// Runs `work` on `threads` threads at once (the calling thread is one of
/// them), for workers that take their share from a shared counter. If any
/// throws, the first exception caught is rethrown after all have finished.
template <class F>
void runWorkers(unsigned threads, F&& work) {
  std::exception_ptr first;
  std::mutex mutex;
  auto guarded = [&] {
    try {
      work();
    } catch (...) {
      const std::lock_guard lock(mutex);
      if (!first) first = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(guarded);
  guarded();
  for (auto& t : pool) t.join();
  if (first) std::rethrow_exception(first);
}

}  // namespace tinsmith
