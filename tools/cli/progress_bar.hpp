// A one-line progress bar on stderr, redrawn in place, for the commands that
// run long (tin, tile, build). Only for terminals: terminalProgress() gives
// nothing when stderr is not one, or with -q.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>

#include "ingest/base/progress.hpp"

namespace tinsmith::cli {

class ProgressBar {
 public:
  ingest::Progress progress() {
    ingest::Progress p;
    p.callback = [this](std::string_view stage, std::string_view detail, std::uint64_t done,
                        std::uint64_t total) { draw(stage, detail, done, total); };
    return p;
  }
  ~ProgressBar() {
    if (drawn_) std::fputs("\r\033[K", stderr);
  }

 private:
  void draw(std::string_view stage, std::string_view detail, std::uint64_t done,
            std::uint64_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (drawn_ && done != total && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    drawn_ = true;
    std::string line = "\r\033[K" + std::string(stage);
    if (!detail.empty()) line += " " + std::string(detail);
    if (total > 0) {
      const int width = 30;
      const int filled =
          static_cast<int>(width * static_cast<double>(done) / static_cast<double>(total));
      line += " [" + std::string(static_cast<std::size_t>(filled), '#') +
              std::string(static_cast<std::size_t>(width - filled), ' ') + "] " +
              std::to_string(100 * done / total) + "%";
    }
    std::fputs(line.c_str(), stderr);
    std::fflush(stderr);
  }
  std::chrono::steady_clock::time_point last_{};
  bool drawn_ = false;
};

/// A bar and its Progress when stderr is a terminal and not `quiet`.
struct TerminalProgress {
  std::unique_ptr<ProgressBar> bar;
  ingest::Progress progress;
  [[nodiscard]] const ingest::Progress* get() const { return bar ? &progress : nullptr; }
};
inline TerminalProgress terminalProgress(bool quiet) {
  TerminalProgress t;
  if (!quiet && ::isatty(STDERR_FILENO)) {
    t.bar = std::make_unique<ProgressBar>();
    t.progress = t.bar->progress();
  }
  return t;
}

}  // namespace tinsmith::cli
