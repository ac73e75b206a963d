// Progress reporting for long ingest and TIN stages. Library code never
// prints: it calls the callback the caller supplies (the CLI turns it into a
// progress bar when stderr is a terminal, and passes nothing otherwise).
//
// Contract: for each stage the library calls report(stage, 0, total) once at
// the start, then report(stage, done, total) with non-decreasing `done` from
// time to time (at most every ~1% of the work), then report(stage, total,
// total) at the end. `total` is 0 when unknown. Stage names are dotted and
// stable ("readers.ogr", "filters.reproject", "filters.clean"); `detail`
// names what is being worked on (a layer's name) and may be empty. The
// callback runs on the calling thread; it must not throw.
#pragma once

#include <cstdint>
#include <functional>
#include <string_view>

namespace tinsmith::ingest {

struct Progress {
  using Callback = std::function<void(std::string_view stage, std::string_view detail,
                                      std::uint64_t done, std::uint64_t total)>;
  Callback callback;

  void report(std::string_view stage, std::string_view detail, std::uint64_t done,
              std::uint64_t total) const {
    if (callback) callback(stage, detail, done, total);
  }
};

/// Calls `progress` (which may be null) — the form library code uses.
inline void reportProgress(const Progress* progress, std::string_view stage,
                           std::string_view detail, std::uint64_t done, std::uint64_t total) {
  if (progress) progress->report(stage, detail, done, total);
}

/// Reports a loop of `total` steps about every 1%: call step(i) each iteration.
class ProgressTicker {
 public:
  ProgressTicker(const Progress* progress, std::string_view stage, std::string_view detail,
                 std::uint64_t total)
      : progress_(progress),
        stage_(stage),
        detail_(detail),
        total_(total),
        every_(total / 100 ? total / 100 : 1) {
    reportProgress(progress_, stage_, detail_, 0, total_);
  }
  void step(std::uint64_t done) {
    if (progress_ && done >= next_) {
      next_ = done + every_;
      progress_->report(stage_, detail_, done, total_);
    }
  }
  void finish() { reportProgress(progress_, stage_, detail_, total_, total_); }

 private:
  const Progress* progress_;
  std::string_view stage_;
  std::string_view detail_;
  std::uint64_t total_;
  std::uint64_t every_;
  std::uint64_t next_ = 0;
};

}  // namespace tinsmith::ingest
