// Little-endian bytes whatever the host, for tinsmith's own small binary
// formats (the tiling plan, a tile's surface): a writer that appends values
// and a reader that takes them back in order, refusing bytes that end early.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace tinsmith::ingest {

namespace detail {
template <class T>
using LeBits = std::conditional_t<sizeof(T) == 8, std::uint64_t,
                                  std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint8_t>>;
}  // namespace detail

/// Appends 1-, 4- and 8-byte values (integers, float, double) to `bytes`.
class LeWriter {
 public:
  template <class T>
  void put(T value) {
    const auto bits = std::bit_cast<detail::LeBits<T>>(value);
    for (std::size_t i = 0; i < sizeof(T); ++i) bytes.push_back(static_cast<char>(bits >> (8 * i)));
  }
  std::string bytes;
};

/// Reads what a LeWriter wrote. `fail` is called with why the bytes are
/// not the format's, and must throw (the format's error, naming its file).
class LeReader {
 public:
  using Fail = std::function<void(const std::string& why)>;
  LeReader(std::string_view bytes, Fail fail) : bytes_(bytes), fail_(std::move(fail)) {}

  template <class T>
  T get() {
    need(sizeof(T));
    detail::LeBits<T> bits = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      bits |= static_cast<detail::LeBits<T>>(
          static_cast<detail::LeBits<T>>(static_cast<std::uint8_t>(bytes_[at_ + i])) << (8 * i));
    at_ += sizeof(T);
    return std::bit_cast<T>(bits);
  }
  /// The next n bytes.
  std::string_view take(std::size_t n) {
    need(n);
    const std::string_view v = bytes_.substr(at_, n);
    at_ += n;
    return v;
  }
  /// A u64 count of elements of `each` bytes that the rest can hold.
  std::size_t count(std::size_t each) {
    const auto n = get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / each) fail("a count is larger than the bytes that follow");
    return static_cast<std::size_t>(n);
  }
  void need(std::size_t n) const {
    if (bytes_.size() - at_ < n) fail("it ends early");
  }
  [[nodiscard]] std::size_t at() const { return at_; }
  [[nodiscard]] bool atEnd() const { return at_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& why) const {
    fail_(why);
    std::terminate();  // fail_ throws
  }

 private:
  std::string_view bytes_;
  Fail fail_;
  std::size_t at_ = 0;
};

}  // namespace tinsmith::ingest
