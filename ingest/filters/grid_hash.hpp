// A uniform-grid spatial hash over x, y for the cleaning filters: open
// addressing from cell to the head of a singly linked list of item indices.
// Insert and query are O(1) expected; memory is ~16 bytes per item plus the
// table. Cells are `cell` metres wide; a query for neighbours within r <= cell
// looks at the 3 x 3 block around the query's cell.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace tinsmith::ingest {

class GridHash {
 public:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  /// `cell` > 0 in metres; `expectedItems` sizes the table.
  GridHash(double originX, double originY, double cell, std::size_t expectedItems)
      : originX_(originX), originY_(originY), inverseCell_(1.0 / cell) {
    std::size_t size = 16;
    while (size < expectedItems * 2) size <<= 1;
    keys_.assign(size, kEmpty);
    heads_.assign(size, kNone);
    next_.reserve(expectedItems);
    mask_ = size - 1;
  }

  [[nodiscard]] std::int64_t cellX(double x) const { return static_cast<std::int64_t>(std::floor((x - originX_) * inverseCell_)); }
  [[nodiscard]] std::int64_t cellY(double y) const { return static_cast<std::int64_t>(std::floor((y - originY_) * inverseCell_)); }

  /// Adds item `index` (must be the number of items inserted so far) at x, y.
  void insert(double x, double y) {
    const std::size_t slot = slotFor(key(cellX(x), cellY(y)));
    next_.push_back(heads_[slot]);
    heads_[slot] = static_cast<std::uint32_t>(next_.size() - 1);
  }

  /// Adds the next item to cell (cx, cy) — for items covering several cells.
  void insertInCell(std::int64_t cx, std::int64_t cy) {
    const std::size_t slot = slotFor(key(cx, cy));
    next_.push_back(heads_[slot]);
    heads_[slot] = static_cast<std::uint32_t>(next_.size() - 1);
  }

  /// Calls f(first, next) for every occupied cell: the cell's items are
  /// first, next[first], … until kNone (in the reverse order of insertion).
  template <typename F>
  void forEachCell(F&& f) const {
    for (std::size_t slot = 0; slot < keys_.size(); ++slot) {
      if (keys_[slot] != kEmpty) f(heads_[slot], next_);
    }
  }

  /// Calls f(index) for every item in cell (cx, cy).
  template <typename F>
  void forEachInCell(std::int64_t cx, std::int64_t cy, F&& f) const {
    const std::size_t slot = findSlot(key(cx, cy));
    if (slot == kNoSlot) return;
    for (std::uint32_t i = heads_[slot]; i != kNone; i = next_[i]) f(i);
  }

  /// Calls f(index) for every item in the 3 x 3 cells around x, y.
  template <typename F>
  void forEachNear(double x, double y, F&& f) const {
    const auto cx = cellX(x);
    const auto cy = cellY(y);
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      for (std::int64_t dx = -1; dx <= 1; ++dx) forEachInCell(cx + dx, cy + dy, f);
    }
  }

  [[nodiscard]] std::size_t size() const { return next_.size(); }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static constexpr std::size_t kNoSlot = ~std::size_t{0};

  static std::uint64_t key(std::int64_t cx, std::int64_t cy) {
    return (static_cast<std::uint64_t>(cx) << 32) ^ (static_cast<std::uint64_t>(cy) & 0xffffffffu);
  }

  static std::size_t hash(std::uint64_t k) {
    std::uint64_t h = k * 0x9E3779B97F4A7C15ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }

  std::size_t findSlot(std::uint64_t k) const {
    for (std::size_t slot = hash(k) & mask_;; slot = (slot + 1) & mask_) {
      if (keys_[slot] == k) return slot;
      if (keys_[slot] == kEmpty) return kNoSlot;
    }
  }

  std::size_t slotFor(std::uint64_t k) {
    for (std::size_t slot = hash(k) & mask_;; slot = (slot + 1) & mask_) {
      if (keys_[slot] == k) return slot;
      if (keys_[slot] == kEmpty) {
        if (2 * (used_ + 1) > keys_.size()) {
          grow();
          return slotFor(k);
        }
        keys_[slot] = k;
        ++used_;
        return slot;
      }
    }
  }

  void grow() {
    std::vector<std::uint64_t> oldKeys;
    std::vector<std::uint32_t> oldHeads;
    oldKeys.swap(keys_);
    oldHeads.swap(heads_);
    keys_.assign(oldKeys.size() * 2, kEmpty);
    heads_.assign(oldKeys.size() * 2, kNone);
    mask_ = keys_.size() - 1;
    used_ = 0;
    for (std::size_t i = 0; i < oldKeys.size(); ++i) {
      if (oldKeys[i] == kEmpty) continue;
      const std::size_t slot = slotFor(oldKeys[i]);
      heads_[slot] = oldHeads[i];
    }
  }

  double originX_, originY_, inverseCell_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> heads_;
  std::vector<std::uint32_t> next_;
  std::size_t mask_ = 0;
  std::size_t used_ = 0;
};

}  // namespace tinsmith::ingest
