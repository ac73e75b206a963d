// The request-target parser, the route matcher and the representation rules
// (ETag, If-None-Match, Range, Accept-Encoding) without sockets.
#include <gtest/gtest.h>

#include "server/http/representation.hpp"
#include "server/http/request_target.hpp"
#include "server/http/route.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::server {
namespace {

TEST(RequestTarget, DecodesSegmentsAndQueryOnce) {
  const auto t = parseRequestTarget("/tilesets/a%20b/x?lon=-111.5&lat=40%2E7&q=a+b&flag");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->segments, (std::vector<std::string>{"tilesets", "a b", "x"}));
  EXPECT_EQ(t->parameter("lat"), "40.7");
  EXPECT_EQ(t->parameter("q"), "a b");
  EXPECT_EQ(t->parameter("flag"), "");
  EXPECT_FALSE(t->parameter("nope"));
  // Double encoding stays literal text after one decode.
  const auto d = parseRequestTarget("/tilesets/%252e%252e/tileset.json");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->segments[1], "%2e%2e");
}

TEST(RequestTarget, RefusesTraversalEscapesAndControlBytes) {
  for (const char* bad :
       {"", "tilesets", "*", "http://x/", "/..", "/tilesets/../etc/passwd", "/a/./b", "/%2e%2e/x",
        "/%2E%2e/x", "/%2e/x", "/a%2fb", "/a%2Fb", "/a%5cb", "/a\\b", "/a%00b", "/a%0d%0ab",
        "/a//b", "/%", "/%4", "/%zz", "/a?x=%00", "/a?x=%", "/a?%0a=1", "/a\x01"}) {
    EXPECT_FALSE(parseRequestTarget(bad)) << bad;
  }
  std::string deep;
  for (std::size_t i = 0; i <= kMaxSegments; ++i) deep += "/a";
  EXPECT_FALSE(parseRequestTarget(deep));
  std::string many = "/a?";
  for (std::size_t i = 0; i <= kMaxParameters; ++i) many += "p=1&";
  EXPECT_FALSE(parseRequestTarget(many));
}

TEST(RequestTarget, NumbersAreStrict) {
  EXPECT_EQ(parseFiniteDouble("-111.25"), -111.25);
  EXPECT_EQ(parseFiniteDouble("+4.5e6"), 4.5e6);
  for (const char* bad : {"", " 1", "1 ", "inf", "nan", "0x10", "1e999", "1,5", "--1", "1e"})
    EXPECT_FALSE(parseFiniteDouble(bad)) << bad;
  EXPECT_EQ(parseBoundedUnsigned("0", 5), 0u);
  EXPECT_EQ(parseBoundedUnsigned("5", 5), 5u);
  for (const char* bad : {"", "6", "-1", "+1", "01", "1a", "18446744073709551616", "99999999999999999999"})
    EXPECT_FALSE(parseBoundedUnsigned(bad, 5)) << bad;
}

Route routeOf(const std::string& target) {
  const auto t = parseRequestTarget(target);
  EXPECT_TRUE(t) << target;
  auto r = matchRoute(*t);
  EXPECT_TRUE(std::holds_alternative<Route>(r)) << target;
  return std::get<Route>(r);
}

std::string errorParameter(const std::string& target) {
  const auto r = matchRoute(*parseRequestTarget(target));
  return std::holds_alternative<RouteError>(r) ? std::get<RouteError>(r).parameter : "";
}

TEST(Route, MatchesEveryRouteAsTypedValues) {
  EXPECT_EQ(routeOf("/").kind, RouteKind::Index);
  EXPECT_EQ(routeOf("/health").kind, RouteKind::Health);
  EXPECT_EQ(routeOf("/metrics").kind, RouteKind::Metrics);
  EXPECT_EQ(routeOf("/tilesets").kind, RouteKind::Tilesets);
  EXPECT_EQ(routeOf("/tilesets/rb/tileset.json").kind, RouteKind::TilesetJson);
  EXPECT_EQ(routeOf("/tilesets/rb/elevation?x=1&y=2").kind, RouteKind::Elevation);
  EXPECT_EQ(routeOf("/tilesets/rb/profile").kind, RouteKind::Profile);
  const Route tile = routeOf("/tilesets/red-butte_2/tiles/3/7/5.glb");
  EXPECT_EQ(tile.kind, RouteKind::Tile);
  EXPECT_EQ(tile.tileset, "red-butte_2");
  EXPECT_EQ(tile.tile, (tiles::TileId{3, 7, 5}));
  EXPECT_FALSE(tile.outsidePyramid);
  const Route ext = routeOf("/tilesets/rb/tilesets/4/1/2.json");
  EXPECT_EQ(ext.kind, RouteKind::ExternalTileset);
  EXPECT_EQ(ext.tile, (tiles::TileId{4, 1, 2}));
  for (const char* none : {"/tilesets/", "/tilesets/rb", "/tilesets/rb/x", "/tilesets/.rb/tileset.json",
                           "/tilesets/r%20b/tileset.json", "/health/", "/tilesets/rb/tiles/1/0/0.png/x"})
    EXPECT_EQ(routeOf(none).kind, RouteKind::Unknown) << none;
}

TEST(Route, TileCoordinatesAreIntegersOrErrorsNamingThem) {
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/-1/0/0.glb"), "z");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/a/0/0.glb"), "z");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/99999999999999999999999/0/0.glb"), "z");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/1/0x1/0.glb"), "x");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/1/0/4294967296.glb"), "y");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/1/0/0.png"), "y");
  EXPECT_EQ(errorParameter("/tilesets/rb/tiles/1/0/01.glb"), "y");
  // Integers that name no tile: outside the pyramid (a 404 later).
  EXPECT_TRUE(routeOf("/tilesets/rb/tiles/1/2/0.glb").outsidePyramid);
  EXPECT_TRUE(routeOf("/tilesets/rb/tiles/31/0/0.glb").outsidePyramid);
  EXPECT_TRUE(routeOf("/tilesets/rb/tiles/4294967295/0/0.glb").outsidePyramid);
  EXPECT_TRUE(routeOf("/tilesets/rb/tiles/0/4294967295/0.glb").outsidePyramid);
  EXPECT_FALSE(routeOf("/tilesets/rb/tiles/30/1073741823/0.glb").outsidePyramid);
}

TEST(Representation, EtagsAreStrongAndMatchLists) {
  const std::string a = strongEtag("abc"), b = strongEtag("abd");
  EXPECT_NE(a, b);
  EXPECT_EQ(a, strongEtag("abc"));
  EXPECT_EQ(a.front(), '"');
  EXPECT_TRUE(ifNoneMatchMatches(a, a));
  EXPECT_TRUE(ifNoneMatchMatches(b + ", " + a, a));
  EXPECT_TRUE(ifNoneMatchMatches("W/" + a, a));
  EXPECT_TRUE(ifNoneMatchMatches("*", a));
  EXPECT_FALSE(ifNoneMatchMatches(b, a));
  EXPECT_FALSE(ifNoneMatchMatches("", a));
}

TEST(Representation, RangesFollowRfc9110) {
  using K = RangeRequest::Kind;
  auto r = parseRange("bytes=0-9", 100);
  EXPECT_EQ(r.kind, K::Partial);
  EXPECT_EQ(r.first, 0u);
  EXPECT_EQ(r.last, 9u);
  r = parseRange("bytes=90-", 100);
  EXPECT_EQ(r.kind, K::Partial);
  EXPECT_EQ(r.first, 90u);
  EXPECT_EQ(r.last, 99u);
  r = parseRange("bytes=-10", 100);
  EXPECT_EQ(r.first, 90u);
  r = parseRange("bytes=-1000", 100);
  EXPECT_EQ(r.first, 0u);
  r = parseRange("bytes=50-100000", 100);
  EXPECT_EQ(r.last, 99u);
  EXPECT_EQ(parseRange("bytes=100-", 100).kind, K::Unsatisfiable);
  EXPECT_EQ(parseRange("bytes=-0", 100).kind, K::Unsatisfiable);
  for (const char* ignored : {"", "bytes=5-1", "bytes=a-b", "items=0-1", "bytes=0-1,5-6", "bytes=-",
                              "bytes=99999999999999999999999-"})
    EXPECT_EQ(parseRange(ignored, 100).kind, K::Full) << ignored;
}

TEST(Representation, GzipFollowsAcceptEncodingAndRoundTrips) {
  EXPECT_TRUE(acceptsGzip("gzip"));
  EXPECT_TRUE(acceptsGzip("deflate, GZIP;q=0.5"));
  EXPECT_TRUE(acceptsGzip("*"));
  EXPECT_FALSE(acceptsGzip(""));
  EXPECT_FALSE(acceptsGzip("br, deflate"));
  EXPECT_FALSE(acceptsGzip("gzip;q=0"));
  EXPECT_FALSE(acceptsGzip("gzip;q=0.000, *"));
  EXPECT_FALSE(acceptsGzip("*;q=0"));
  const std::string text(5000, 'z');
  const std::string packed = gzipCompress(text);
  ASSERT_LT(packed.size(), 200u);
  EXPECT_EQ(test::gunzip(packed), text);
}

TEST(Representation, BrotliFollowsAcceptEncodingAndRoundTrips) {
  EXPECT_TRUE(acceptsBrotli("br"));
  EXPECT_TRUE(acceptsBrotli("gzip, deflate, BR;q=0.9"));
  EXPECT_TRUE(acceptsBrotli("*"));
  EXPECT_FALSE(acceptsBrotli("gzip"));
  EXPECT_FALSE(acceptsBrotli("br;q=0, *"));
  EXPECT_FALSE(acceptsBrotli("brotli"));
  const std::string text(5000, 'z');
  const std::string packed = brotliCompress(text);
  ASSERT_LT(packed.size(), 100u);
  EXPECT_EQ(test::unbrotli(packed), text);
  EXPECT_EQ(test::unbrotli(brotliCompress("")), "");
}

}  // namespace
}  // namespace tinsmith::server
