// Features of the CDT's constrained edges, keyed by their undirected vertex
// pair (edgeKey). Internal to core/cdt.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/ids.hpp"

namespace tinsmith::cdt {

/// The key of the undirected edge a–b.
inline std::uint64_t edgeKey(VertexId a, VertexId b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a.value) << 32) | b.value;
}
/// The vertices of the edge of key k (the smaller id first).
inline std::pair<VertexId, VertexId> edgeOfKey(std::uint64_t k) {
  return {VertexId(static_cast<std::uint32_t>(k >> 32)), VertexId(static_cast<std::uint32_t>(k))};
}

/// Features of constrained edges, keyed by edgeKey. Most edges carry one
/// feature, stored inline; edges shared by several features point to an
/// immutable list (copy on write, so split halves may share one). An open
/// addressing table (linear probing, 16 bytes a slot, at most 7/8 full):
/// terrain inputs constrain about one edge per vertex.
class EdgeFeatureMap {
 public:
  struct View {
    const FeatureId* data = nullptr;
    std::size_t size = 0;
    [[nodiscard]] const FeatureId* begin() const { return data; }
    [[nodiscard]] const FeatureId* end() const { return data + size; }
    [[nodiscard]] bool empty() const { return size == 0; }
  };

  [[nodiscard]] View find(std::uint64_t key) const {
    const std::size_t i = slotOf(key);
    if (i == kMissing) return {};
    return view(slots_[i].entry);
  }
  void add(std::uint64_t key, FeatureId f) {
    std::size_t i = slotOf(key);
    if (i == kMissing) {
      insertNew(key, {f, kNoList});
      return;
    }
    Entry& e = slots_[i].entry;
    if (e.list == kNoList) {
      if (e.single == f) return;
      lists_.push_back({e.single, f});
    } else {
      const auto& old = lists_[e.list];
      if (std::find(old.begin(), old.end(), f) != old.end()) return;
      std::vector<FeatureId> l = old;
      l.push_back(f);
      lists_.push_back(std::move(l));
    }
    e.list = static_cast<std::uint32_t>(lists_.size() - 1);
  }
  void erase(std::uint64_t key) {
    const std::size_t i = slotOf(key);
    if (i != kMissing) eraseAt(i);
  }
  /// The edge `from` was split into `a` and `b`: both inherit its features.
  void split(std::uint64_t from, std::uint64_t a, std::uint64_t b) {
    const std::size_t i = slotOf(from);
    if (i == kMissing) return;
    const Entry e = slots_[i].entry;
    eraseAt(i);
    set(a, e);
    set(b, e);
  }
  /// Room for n edges without growing (growing holds both tables at once).
  void reserve(std::size_t n) {
    std::size_t capacity = 64;
    while (8 * n > 7 * capacity) capacity *= 2;
    if (capacity > slots_.size()) rehash(capacity);
  }
  /// Calls f(key, features) for every edge.
  template <class F>
  void forEach(const F& f) const {
    for (const Slot& sl : slots_) {
      if (sl.key != kEmpty) f(sl.key, view(sl.entry));
    }
  }

 private:
  static constexpr std::uint32_t kNoList = 0xffffffffu;
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // no edgeKey is this
  static constexpr std::size_t kMissing = ~std::size_t{0};
  struct Entry {
    FeatureId single;
    std::uint32_t list;
  };
  struct Slot {
    std::uint64_t key = kEmpty;
    Entry entry{};
  };

  [[nodiscard]] View view(const Entry& e) const {
    if (e.list == kNoList) return {&e.single, 1};
    const auto& l = lists_[e.list];
    return {l.data(), l.size()};
  }
  [[nodiscard]] std::size_t hash(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  [[nodiscard]] std::size_t slotOf(std::uint64_t key) const {
    if (slots_.empty()) return kMissing;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(key);; i = (i + 1) & mask) {
      if (slots_[i].key == key) return i;
      if (slots_[i].key == kEmpty) return kMissing;
    }
  }
  /// Backward-shift deletion: later entries of the probe run move forward.
  void eraseAt(std::size_t i) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t j = (i + 1) & mask; slots_[j].key != kEmpty; j = (j + 1) & mask) {
      const std::size_t home = hash(slots_[j].key);
      if (((j - home) & mask) >= ((j - i) & mask)) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i].key = kEmpty;
    --size_;
  }
  void set(std::uint64_t key, const Entry& e) {
    const std::size_t i = slotOf(key);
    if (i == kMissing) {
      insertNew(key, e);
    } else {
      slots_[i].entry = e;
    }
  }
  void insertNew(std::uint64_t key, const Entry& e) {
    if (8 * (size_ + 1) > 7 * slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = hash(key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask;
    slots_[i] = {key, e};
    ++size_;
  }
  void grow() { rehash(slots_.empty() ? 64 : 2 * slots_.size()); }
  void rehash(std::size_t capacity) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(capacity, Slot{});
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
    for (const Slot& sl : old) {
      if (sl.key != kEmpty) insertNew(sl.key, sl.entry);
    }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  int shift_ = 64;
  std::vector<std::vector<FeatureId>> lists_;
};


}  // namespace tinsmith::cdt
