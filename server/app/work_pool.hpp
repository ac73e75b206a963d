// The worker threads that run a request's slow part (an on-demand tile
// build, a large elevation batch) so the I/O threads keep answering the
// cheap requests (cached tiles, /health) meanwhile: a fixed number of
// workers over one bounded queue. A task that finds the queue full is
// refused at once, and its request answered 503 with Retry-After (see
// TileService), so an overloaded server sheds work instead of piling it up.
//
// Threads: every member may be called from any thread. The workers are
// started with every signal blocked, so a process that waits for its signals
// with sigwait (tinsmith serve) still gets them all on its own thread. They
// run kWorkerNice steps nicer than the process (and so do the threads a
// build starts): on a busy machine the scheduler gives the I/O threads the
// cores first, and a cached tile is not kept waiting behind a fit.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace tinsmith::server {

class WorkPool {
 public:
  static constexpr int kWorkerNice = 10;

  struct Stats {
    std::size_t workers = 0;
    std::size_t queueLimit = 0;
    std::size_t waiting = 0;     ///< queued, not started
    std::size_t running = 0;     ///< on a worker now
    std::uint64_t queued = 0;    ///< tasks taken, ever
    std::uint64_t rejected = 0;  ///< tasks refused: the queue was full, or the pool shut down
  };

  /// `workers` 0: one per core. `queueLimit`: tasks that may wait for a
  /// worker (0: none wait; a task is taken only when a worker is idle).
  WorkPool(std::size_t workers, std::size_t queueLimit);
  /// shutdown().
  ~WorkPool();
  WorkPool(const WorkPool&) = delete;
  WorkPool& operator=(const WorkPool&) = delete;

  /// Queues `task` for a worker. False (and `task` destroyed unrun) when
  /// queueLimit tasks already wait beyond the idle workers, or the pool is
  /// shut down. A task must not throw (what escapes it is dropped).
  [[nodiscard]] bool trySubmit(std::function<void()> task);
  /// Takes no more tasks, destroys the waiting ones unrun, and waits for the
  /// running ones to finish. Idempotent.
  void shutdown();

  [[nodiscard]] Stats stats() const;

 private:
  void work();

  std::size_t queueLimit_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> queue_;
  std::size_t idle_ = 0, running_ = 0;
  std::uint64_t queued_ = 0, rejected_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace tinsmith::server
