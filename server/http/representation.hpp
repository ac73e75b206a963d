// HTTP representation rules the routes share: strong ETags from content,
// If-None-Match matching (RFC 9110 13.1.2), single byte ranges (RFC 9110 14),
// Accept-Encoding, gzip (zlib) and brotli.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tinsmith::server {

/// A strong ETag of `bytes`: a quoted 64-bit FNV-1a hash and the length, in
/// hex ("\"9f3c…-2a1\""). Equal bytes give equal tags on every machine.
std::string strongEtag(std::string_view bytes);

/// Whether an If-None-Match value matches `etag` ("*", or one of a comma
/// list; weak comparison, so W/"x" matches "x").
bool ifNoneMatchMatches(std::string_view ifNoneMatch, std::string_view etag);

/// The outcome of a Range header against a representation of `size` bytes.
struct RangeRequest {
  enum class Kind { Full, Partial, Unsatisfiable } kind = Kind::Full;
  std::size_t first = 0, last = 0;  ///< inclusive, for Partial
};

/// A single "bytes=a-b", "bytes=a-" or "bytes=-n" range. A missing,
/// malformed or multi-range header gives Full (RFC 9110 lets a server ignore
/// Range); a range that starts at or past `size` (or a zero suffix) gives
/// Unsatisfiable; `last` is clamped to size - 1.
RangeRequest parseRange(std::string_view header, std::size_t size);

/// Whether Accept-Encoding accepts the content coding `name` (listed, or
/// "*", with q > 0; an explicit entry decides over "*").
bool acceptsCoding(std::string_view acceptEncoding, std::string_view name);
bool acceptsGzip(std::string_view acceptEncoding);    ///< "gzip"
bool acceptsBrotli(std::string_view acceptEncoding);  ///< "br"

/// `bytes` compressed as gzip (RFC 1952) at zlib's default level. Throws
/// internalError when zlib fails.
std::string gzipCompress(std::string_view bytes);

/// The quantized-mesh extensions an Accept header asks for (CesiumJS:
/// "application/vnd.quantized-mesh;extensions=octvertexnormals-watermask-metadata";
/// 3d-tiles-renderer: "…,application/octet-stream;q=0.9;extensions=…"):
/// their ids (1 octvertexnormals, 2 watermask, 4 metadata), ascending, each
/// once, from an `extensions` parameter on any media range; none without
/// one. Unknown names are ignored.
std::vector<std::uint8_t> quantizedMeshExtensionsAccepted(std::string_view accept);

/// `bytes` compressed as brotli (RFC 7932), quality 5. Throws internalError
/// when the encoder fails.
std::string brotliCompress(std::string_view bytes);

}  // namespace tinsmith::server
