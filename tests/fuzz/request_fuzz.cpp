// libFuzzer target for what the server parses from a client before any route
// runs: the request-target (path segments, query), the route matcher, and
// the Range, If-None-Match and Accept-Encoding rules, the framing rules of a
// head and the absolute-form rewrite. Whatever the bytes,
// no crash, no sanitizer report, and the parser's promises hold: no decoded
// segment is "." or "..", holds '/', '\\' or a control byte; tile ids are
// inside their zoom's grid; a range lies inside the representation; a
// rewritten absolute-form target is a path; a refusal is a 4xx or 501 and
// its message holds no control byte.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "server/http/representation.hpp"
#include "server/http/request_framing.hpp"
#include "server/http/request_target.hpp"
#include "server/http/route.hpp"

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

bool hasForbiddenByte(std::string_view s, bool inPath) {
  for (unsigned char c : s)
    if (c < 0x20 || c == 0x7f || (inPath && (c == '/' || c == '\\'))) return true;
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace tinsmith::server;
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  if (const auto target = parseRequestTarget(text)) {
    require(target->segments.size() <= kMaxSegments && target->query.size() <= kMaxParameters);
    for (const auto& s : target->segments)
      require(!s.empty() && s != "." && s != ".." && !hasForbiddenByte(s, true));
    for (const auto& [name, value] : target->query) {
      require(!hasForbiddenByte(name, false) && !hasForbiddenByte(value, false));
      if (const auto number = parseFiniteDouble(value)) require(*number - *number == 0);
    }
    const auto route = matchRoute(*target);
    if (const auto* r = std::get_if<Route>(&route)) {
      if (r->kind == RouteKind::Tile || r->kind == RouteKind::ExternalTileset) {
        require(isValidTilesetId(r->tileset));
        if (!r->outsidePyramid) {
          require(r->tile.z >= 0 && r->tile.z <= kMaxZoom);
          require((static_cast<std::uint64_t>(r->tile.x) >> r->tile.z) == 0);
          require((static_cast<std::uint64_t>(r->tile.y) >> r->tile.z) == 0);
        }
      }
    }
  }

  const std::size_t length = size % 4096;
  const auto range = parseRange(text, length);
  if (range.kind == RangeRequest::Kind::Partial) require(range.first <= range.last && range.last < length);
  (void)ifNoneMatchMatches(text, strongEtag(text.substr(0, size / 2)));
  (void)acceptsGzip(text);
  (void)acceptsBrotli(text);

  if (const auto origin = originForm(text);
      origin && text.find("://") != std::string_view::npos && !text.empty() && text.front() != '/')
    require(!origin->empty() && origin->front() == '/');
  RequestHead head;
  head.version = size % 2 == 0 ? 11 : 10;
  head.hosts = size % 3;
  head.contentLengths = size % 5 == 0 ? 1 : 0;
  for (std::size_t at = 0; at < text.size() && head.transferEncodings.size() < 4;
       at += 1 + text.size() / 4)
    head.transferEncodings.push_back(text.substr(at, 1 + text.size() / 4));
  if (const auto refusal = checkFraming(head)) {
    require(refusal->status == 400 || refusal->status == 501);
    require(!hasForbiddenByte(refusal->message, false));
  }
  return 0;
}
