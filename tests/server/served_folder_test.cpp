// What a served folder's names make of the catalog: a tile job's staging
// names (X.partial.3dtiles, a folder X.partial, X.tmp-PID-N) are never
// served, at start or on a reload, so a job running in the folder never
// shows up as a store; a store whose file name is not UTF-8 is served under
// an id of its ASCII bytes (every other byte a '-'), its "name" in the list
// showing those bytes as \xNN (the list used to answer 500 to everyone).
// And a method other than GET or HEAD whose If-None-Match matches gets 412
// (RFC 9110 13.1.2), not 304.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> listedIds(unsigned short port) {
  const auto r = httpGet(port, "/tilesets");
  EXPECT_EQ(r.status, 200) << r.body;
  const auto json = nlohmann::json::parse(r.body, nullptr, false);
  std::vector<std::string> ids;
  if (!json.is_object()) return ids;
  for (const auto& t : json["tilesets"]) ids.push_back(t["id"].get<std::string>());
  return ids;
}

/// Writes the test store at `target` (an archive or a folder, by its name).
void storeAt(const fs::path& target) {
  const auto source = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  const auto keys = source->keys();
  if (store::storeKindFor(target) == store::StoreKind::Archive) {
    fs::copy_file(testStoreDir() / "hill.3dtiles", target);
    return;
  }
  // A folder whatever its name says (a staging folder ends in .partial or
  // .tmp-N-N, which writeStore would not take as a folder store's name).
  fs::create_directories(target);
  for (const auto& key : keys) {
    fs::create_directories((target / key).parent_path());
    std::ofstream(target / key, std::ios::binary) << source->get(key).value();
  }
}

TEST(ServedFolder, ATileJobsStagingNamesAreNeverServed) {
  const auto dir = scratchDir("served-staging-" + std::to_string(::getpid()));
  storeAt(dir / "site.3dtiles");
  storeAt(dir / "site.partial.3dtiles");  // an archive job's stage
  storeAt(dir / "plain.partial");         // a folder job's stage
  storeAt(dir / "plain.tmp-4242-0");      // a folder store being moved in
  auto options = RunningServer::defaults();
  options.stores = {dir};
  options.reloadInterval = std::chrono::milliseconds(0);
  RunningServer server(options);
  EXPECT_EQ(listedIds(server.port()), std::vector<std::string>{"site"});

  storeAt(dir / "other.tmp-4242-7");  // an old store moved aside
  storeAt(dir / "other.partial");
  storeAt(dir / "done");  // a finished folder store: served
  for (const auto& line : server.server().reload())
    EXPECT_EQ(line.find("tmp-"), std::string::npos) << line;
  EXPECT_EQ(listedIds(server.port()), (std::vector<std::string>{"site", "done"}));
}

TEST(ServedFolder, AStoreWhoseNameIsNotUtf8IsServedAndListed) {
  const auto dir = scratchDir("served-latin1-" + std::to_string(::getpid()));
  storeAt(dir / "caf\xff\xfe.3dtiles");
  storeAt(dir / "ok.3dtiles");
  auto options = RunningServer::defaults();
  options.stores = {dir};
  RunningServer server(options);
  const auto r = httpGet(server.port(), "/tilesets");
  ASSERT_EQ(r.status, 200) << r.body;
  const auto json = nlohmann::json::parse(r.body);
  ASSERT_EQ(json["tilesets"].size(), 2u);
  EXPECT_EQ(json["tilesets"][0]["id"], "caf--");
  EXPECT_EQ(json["tilesets"][0]["name"], "caf\\xff\\xfe.3dtiles");
  EXPECT_EQ(json["tilesets"][1]["id"], "ok");
  EXPECT_EQ(httpGet(server.port(), "/tilesets/caf--/tileset.json").status, 200);
  EXPECT_EQ(httpGet(server.port(), "/").status, 200);
  EXPECT_EQ(httpGet(server.port(), "/health").status, 200);
}

TEST(Preconditions, AMatchingIfNoneMatchIs412ForPostAnd304ForGet) {
  RunningServer server;
  HttpConnection c(server.port());
  const std::string body = R"({"points": [[430500, 4515700]]})";
  const auto first = c.request("/tilesets/hill/elevation", "", "POST", body);
  ASSERT_EQ(first.status, 200) << first.body;
  const std::string etag = first.header("etag");
  ASSERT_FALSE(etag.empty());
  const auto again =
      c.request("/tilesets/hill/elevation", "If-None-Match: " + etag + "\r\n", "POST", body);
  EXPECT_EQ(again.status, 412) << again.body;
  EXPECT_EQ(again.header("content-type"), "application/json");
  EXPECT_EQ(c.request("/tilesets/hill/elevation", "If-None-Match: *\r\n", "POST", body).status,
            412);
  EXPECT_EQ(
      c.request("/tilesets/hill/elevation", "If-None-Match: \"other\"\r\n", "POST", body).status,
      200);
  // GET and HEAD still revalidate.
  const auto tileset = c.request("/tilesets/hill/tileset.json");
  const std::string match = "If-None-Match: " + tileset.header("etag") + "\r\n";
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json", match).status, 304);
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json", match, "HEAD").status, 304);
  const std::string metrics = c.request("/metrics").body;
  EXPECT_NE(metrics.find("status=\"412\""), std::string::npos);
}

}  // namespace
}  // namespace tinsmith::test
