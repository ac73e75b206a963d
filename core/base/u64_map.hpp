// An open-addressing hash table from 64-bit keys to small values, for the
// hot look-ups of the CDT (edge → features) and the fit (vertex or triangle
// key → dense id). Internal building block of core.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace tinsmith {

/// A map from 64-bit keys to trivially copyable values: linear probing,
/// Fibonacci hashing (the top bits of key × 2^64/φ), backward-shift deletion,
/// a power-of-two capacity of at least 64 slots kept at most LoadNum/LoadDen
/// full (a higher load saves memory, a lower one shortens probes).
/// Deterministic: no per-process hash seed, so the slot order (forEach) is a
/// function of the operations alone.
/// The key ~0 (kEmpty) marks empty slots and is reserved: it is never found,
/// and inserting it stores nothing.
template <class Value, unsigned LoadNum = 7, unsigned LoadDen = 8>
class U64Map {
 public:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

  /// The value of `key`, or nullptr (always for kEmpty). Valid until the
  /// next insertion or erasure.
  [[nodiscard]] const Value* find(std::uint64_t key) const {
    const std::size_t i = slotOf(key);
    return i == kMissing ? nullptr : &slots_[i].value;
  }
  [[nodiscard]] Value* find(std::uint64_t key) {
    const std::size_t i = slotOf(key);
    return i == kMissing ? nullptr : &slots_[i].value;
  }
  /// Inserts key → value unless key is present or kEmpty. Returns the value
  /// stored under key (nullptr for kEmpty; valid until the next insertion or
  /// erasure) and whether it was inserted now.
  std::pair<Value*, bool> insert(std::uint64_t key, const Value& value) {
    if (key == kEmpty) return {nullptr, false};
    const std::size_t i = slotOf(key);
    if (i != kMissing) return {&slots_[i].value, false};
    return {&slots_[insertNew(key, value)].value, true};
  }
  /// Sets key → value, inserted or overwritten (nothing for kEmpty).
  void assign(std::uint64_t key, const Value& value) {
    if (key == kEmpty) return;
    const std::size_t i = slotOf(key);
    if (i == kMissing) {
      insertNew(key, value);
    } else {
      slots_[i].value = value;
    }
  }
  /// Removes key; true when it was there.
  bool erase(std::uint64_t key) { return extract(key).has_value(); }
  /// Removes key and returns its value; nullopt when it was not there.
  std::optional<Value> extract(std::uint64_t key) {
    const std::size_t i = slotOf(key);
    if (i == kMissing) return std::nullopt;
    const Value value = slots_[i].value;
    eraseAt(i);
    return value;
  }
  /// Room for n entries without growing (growing holds both tables at once).
  void reserve(std::size_t n) {
    std::size_t capacity = std::max<std::size_t>(slots_.size(), kMinCapacity);
    while (!fits(n, capacity)) capacity *= 2;
    if (capacity > slots_.size()) rehash(capacity);
  }
  [[nodiscard]] std::size_t size() const { return size_; }
  void clear() {
    slots_.clear();
    size_ = 0;
    shift_ = 64;
  }
  /// Calls f(key, value) for every entry, in slot order.
  template <class F>
  void forEach(const F& f) const {
    for (const Slot& s : slots_) {
      if (s.key != kEmpty) f(s.key, s.value);
    }
  }

 private:
  static constexpr std::size_t kMissing = ~std::size_t{0};
  static constexpr std::size_t kMinCapacity = 64;
  struct Slot {
    std::uint64_t key = kEmpty;
    Value value{};
  };

  static bool fits(std::size_t n, std::size_t capacity) {
    return n * LoadDen <= capacity * LoadNum;
  }
  [[nodiscard]] std::size_t home(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  [[nodiscard]] std::size_t slotOf(std::uint64_t key) const {
    if (slots_.empty() || key == kEmpty) return kMissing;  // kEmpty would match an empty slot
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = home(key);; i = (i + 1) & mask) {
      if (slots_[i].key == key) return i;
      if (slots_[i].key == kEmpty) return kMissing;
    }
  }
  /// Backward-shift deletion: later entries of the probe run move forward.
  void eraseAt(std::size_t i) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t j = (i + 1) & mask; slots_[j].key != kEmpty; j = (j + 1) & mask) {
      if (((j - home(slots_[j].key)) & mask) >= ((j - i) & mask)) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i].key = kEmpty;
    --size_;
  }
  /// Stores key (not present) → value; returns its slot.
  std::size_t insertNew(std::uint64_t key, const Value& value) {
    if (!fits(size_ + 1, slots_.size())) rehash(slots_.empty() ? kMinCapacity : 2 * slots_.size());
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = home(key);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask;
    slots_[i] = {key, value};
    ++size_;
    return i;
  }
  void rehash(std::size_t capacity) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(capacity, Slot{});
    shift_ = 64 - std::countr_zero(capacity);
    size_ = 0;
    for (const Slot& s : old) {
      if (s.key != kEmpty) insertNew(s.key, s.value);
    }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  int shift_ = 64;
};

}  // namespace tinsmith
