#include "server/http/request_framing.hpp"

#include <cctype>

namespace tinsmith::server {

namespace {

bool equalsIgnoringCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// The codings of every Transfer-Encoding line, in order; empty list
/// elements ("chunked,,") are skipped, as RFC 9110 §5.6.1 allows.
std::vector<std::string_view> codings(const std::vector<std::string_view>& lines) {
  std::vector<std::string_view> out;
  for (std::string_view line : lines) {
    for (;;) {
      const std::size_t comma = line.find(',');
      const std::string_view item = trimmed(line.substr(0, comma));
      if (!item.empty()) out.push_back(item);
      if (comma == std::string_view::npos) break;
      line.remove_prefix(comma + 1);
    }
  }
  return out;
}

/// Printable ASCII only, cut to 64 bytes: a client's header in our message.
std::string quoted(std::string_view text) {
  std::string out;
  for (const char c : text.substr(0, 64)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (text.size() > 64) out += "...";
  return "'" + out + "'";
}

}  // namespace

std::optional<Refusal> checkFraming(const RequestHead& head) {
  if (head.version == 11 && head.hosts != 1)
    return Refusal{400,
                   "an HTTP/1.1 request carries exactly one Host header (RFC 9112 section 3.2); "
                   "this one has " +
                       std::to_string(head.hosts)};
  if (head.transferEncodings.empty()) return std::nullopt;
  if (head.version == 10)
    return Refusal{
        400, "an HTTP/1.0 request cannot use Transfer-Encoding; send the body with Content-Length"};
  if (head.contentLengths > 0)
    return Refusal{
        400,
        "the request has both Transfer-Encoding and Content-Length, so where its body ends is "
        "ambiguous; send one of them"};
  const auto list = codings(head.transferEncodings);
  if (list.size() == 1 && equalsIgnoringCase(list.front(), "chunked")) return std::nullopt;
  std::string all;
  for (const auto& line : head.transferEncodings)
    all += (all.empty() ? "" : ", ") + std::string(line);
  return Refusal{501, "Transfer-Encoding " + quoted(all) +
                          " is not supported: send the body with Content-Length, or with "
                          "'Transfer-Encoding: chunked' alone"};
}

std::optional<std::string> originForm(std::string_view target) {
  const std::size_t colon = target.find("://");
  if (target.empty() || target.front() == '/' || target == "*" || colon == std::string_view::npos)
    return std::string(target);
  const std::string_view scheme = target.substr(0, colon);
  if (!equalsIgnoringCase(scheme, "http") && !equalsIgnoringCase(scheme, "https"))
    return std::nullopt;
  const std::string_view rest = target.substr(colon + 3);
  const std::size_t end = rest.find_first_of("/?#");
  if (end == 0 || rest.empty()) return std::nullopt;  // no authority
  if (end == std::string_view::npos) return std::string("/");
  if (rest[end] == '/') return std::string(rest.substr(end));
  return "/" + std::string(rest.substr(end));
}

}  // namespace tinsmith::server
