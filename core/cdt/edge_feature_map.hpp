// Features of the CDT's constrained edges, keyed by their undirected vertex
// pair (edgeKey). Internal to core/cdt.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "core/base/u64_map.hpp"
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
/// immutable list (copy on write, so split halves may share one). A U64Map
/// (16 bytes a slot, at most 7/8 full): terrain inputs constrain about one
/// edge per vertex.
class EdgeFeatureMap {
 public:
  /// An edge's features (empty: not constrained), valid until the map changes.
  using View = std::span<const FeatureId>;

  [[nodiscard]] View find(std::uint64_t key) const {
    const Entry* e = table_.find(key);
    return e ? view(*e) : View{};
  }
  void add(std::uint64_t key, FeatureId f) {
    const auto [e, inserted] = table_.insert(key, {f, kNoList});
    if (inserted) return;
    if (e->list == kNoList) {
      if (e->single == f) return;
      lists_.push_back({e->single, f});
    } else {
      const auto& old = lists_[e->list];
      if (std::find(old.begin(), old.end(), f) != old.end()) return;
      std::vector<FeatureId> l = old;
      l.push_back(f);
      lists_.push_back(std::move(l));
    }
    e->list = static_cast<std::uint32_t>(lists_.size() - 1);
  }
  void erase(std::uint64_t key) { table_.erase(key); }
  /// The edge `from` was split into `a` and `b`: both inherit its features.
  void split(std::uint64_t from, std::uint64_t a, std::uint64_t b) {
    const std::optional<Entry> e = table_.extract(from);
    if (!e) return;
    table_.assign(a, *e);
    table_.assign(b, *e);
  }
  /// Room for n edges without growing (growing holds both tables at once).
  void reserve(std::size_t n) { table_.reserve(n); }
  /// Calls f(key, features) for every edge.
  template <class F>
  void forEach(const F& f) const {
    table_.forEach([&](std::uint64_t key, const Entry& e) { f(key, view(e)); });
  }

 private:
  static constexpr std::uint32_t kNoList = 0xffffffffu;
  struct Entry {
    FeatureId single;
    std::uint32_t list;  // into lists_, or kNoList
  };

  [[nodiscard]] View view(const Entry& e) const {
    if (e.list == kNoList) return {&e.single, 1};
    const auto& l = lists_[e.list];
    return {l.data(), l.size()};
  }

  U64Map<Entry, 7, 8> table_;  // no edgeKey is U64Map's reserved key
  std::vector<std::vector<FeatureId>> lists_;
};

}  // namespace tinsmith::cdt
