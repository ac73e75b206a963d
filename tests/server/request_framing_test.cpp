// The framing rules of a request head, and absolute-form targets, as pure
// functions (server/http/request_framing.hpp); the hostile HTTP suite
// checks them over sockets.
#include "server/http/request_framing.hpp"

#include <gtest/gtest.h>

namespace tinsmith::server {
namespace {

RequestHead head(int version, std::vector<std::string_view> codings, std::size_t lengths = 0,
                 std::size_t hosts = 1) {
  return RequestHead{version, std::move(codings), lengths, hosts};
}

int statusOf(const RequestHead& h) {
  const auto refusal = checkFraming(h);
  return refusal ? refusal->status : 0;
}

TEST(RequestFraming, PlainAndChunkedRequestsPass) {
  EXPECT_EQ(statusOf(head(11, {})), 0);
  EXPECT_EQ(statusOf(head(11, {}, 1)), 0);
  EXPECT_EQ(statusOf(head(11, {"chunked"})), 0);
  EXPECT_EQ(statusOf(head(11, {"Chunked"})), 0);
  EXPECT_EQ(statusOf(head(11, {" chunked\t"})), 0);
  EXPECT_EQ(statusOf(head(11, {"chunked, "})), 0);  // empty list elements do not count
  EXPECT_EQ(statusOf(head(10, {}, 1, 0)), 0);       // HTTP/1.0 needs no Host
}

TEST(RequestFraming, HttpOneOneNeedsExactlyOneHost) {
  EXPECT_EQ(statusOf(head(11, {}, 0, 0)), 400);
  EXPECT_EQ(statusOf(head(11, {}, 0, 2)), 400);
  EXPECT_NE(checkFraming(head(11, {}, 0, 2))->message.find("exactly one Host"), std::string::npos);
}

TEST(RequestFraming, AnyCodingButChunkedAloneIsRefused) {
  for (const std::string_view coding :
       {"gzip", "identity", "xchunked", "chunkedx", "chunked;ext=1", "chunked, gzip",
        "gzip, chunked", "chunked, chunked", ",", ""})
    EXPECT_EQ(statusOf(head(11, {coding})), 501) << coding;
  EXPECT_EQ(statusOf(head(11, {"chunked", "gzip"})), 501);  // over two header lines
  EXPECT_EQ(statusOf(head(11, {"gzip", "chunked"})), 501);
  const auto refusal = checkFraming(head(11, {"chunked, gzip"}));
  ASSERT_TRUE(refusal);
  EXPECT_NE(refusal->message.find("'chunked, gzip'"), std::string::npos) << refusal->message;
}

TEST(RequestFraming, AmbiguousFramingIsABadRequest) {
  EXPECT_EQ(statusOf(head(11, {"chunked"}, 1)), 400);     // with Content-Length
  EXPECT_EQ(statusOf(head(10, {"chunked"}, 0, 0)), 400);  // in HTTP/1.0
}

TEST(RequestFraming, AClientsBytesAreQuotedPrintably) {
  const std::string nasty = "gz\x01ip\r\n" + std::string(200, 'a');
  const auto refusal = checkFraming(head(11, {nasty}));
  ASSERT_TRUE(refusal);
  EXPECT_EQ(refusal->message.find('\x01'), std::string::npos);
  EXPECT_EQ(refusal->message.find('\r'), std::string::npos);
  EXPECT_LT(refusal->message.size(), 200u);
}

TEST(RequestFraming, AbsoluteFormBecomesOriginForm) {
  EXPECT_EQ(originForm("/tilesets?x=1"), "/tilesets?x=1");
  EXPECT_EQ(originForm("*"), "*");
  EXPECT_EQ(originForm("http://127.0.0.1:8080/tilesets/rb/tileset.json"),
            "/tilesets/rb/tileset.json");
  EXPECT_EQ(originForm("HTTPS://example.org/a/b?q=1"), "/a/b?q=1");
  EXPECT_EQ(originForm("http://example.org"), "/");
  EXPECT_EQ(originForm("http://example.org?q=1"), "/?q=1");
  EXPECT_EQ(originForm("http://user@example.org:80/x"), "/x");
  EXPECT_EQ(originForm("ftp://example.org/x"), std::nullopt);
  EXPECT_EQ(originForm("http:///x"), std::nullopt);
  EXPECT_EQ(originForm("http://"), std::nullopt);
  EXPECT_EQ(originForm("tilesets"), "tilesets");  // not absolute-form: the route parser refuses it
}

}  // namespace
}  // namespace tinsmith::server
