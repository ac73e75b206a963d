#include "server/app/work_pool.hpp"

#include <signal.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "core/base/parallel.hpp"

namespace tinsmith::server {

WorkPool::WorkPool(std::size_t workers, std::size_t queueLimit) : queueLimit_(queueLimit) {
  const unsigned count = resolveThreads(static_cast<long long>(workers));
  // The workers inherit the mask in force here: every signal blocked.
  sigset_t all, previous;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, &previous);
  try {
    for (unsigned i = 0; i < count; ++i) workers_.emplace_back([this] { work(); });
  } catch (...) {
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    shutdown();
    throw;
  }
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
}

WorkPool::~WorkPool() {
  shutdown();
}

bool WorkPool::trySubmit(std::function<void()> task) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || queue_.size() >= idle_ + queueLimit_) {
      ++rejected_;
      return false;
    }
    queue_.push_back(std::move(task));
    ++queued_;
  }
  ready_.notify_one();
  return true;
}

void WorkPool::shutdown() {
  std::deque<std::function<void()>> dropped;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    dropped.swap(queue_);
  }
  ready_.notify_all();
  dropped.clear();  // outside the lock: a task's captures may do anything when destroyed
  for (auto& w : workers_)
    if (w.joinable() && w.get_id() != std::this_thread::get_id()) w.join();
}

WorkPool::Stats WorkPool::stats() const {
  std::lock_guard lock(mutex_);
  return {workers_.size(), queueLimit_, queue_.size(), running_, queued_, rejected_};
}

void WorkPool::work() {
  // Linux keeps a nice value per thread (and threads a task starts inherit
  // it): this one's, not the process's. Best effort.
  const auto self = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int nice = ::getpriority(PRIO_PROCESS, self);
  if (errno == 0) ::setpriority(PRIO_PROCESS, self, std::min(nice + kWorkerNice, 19));
  std::unique_lock lock(mutex_);
  for (;;) {
    ++idle_;
    ready_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    --idle_;
    if (stopping_) return;
    std::function<void()> task = std::move(queue_.front());
    queue_.pop_front();
    ++running_;
    lock.unlock();
    try {
      task();
    } catch (...) {  // the contract says tasks do not throw; a worker outlives one that does
    }
    task = nullptr;  // its captures are released before the next task is taken
    lock.lock();
    --running_;
  }
}

}  // namespace tinsmith::server
