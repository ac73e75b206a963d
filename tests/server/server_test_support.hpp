// Support for the server's tests: a small tile store made in code (a
// synthetic TIN through the tiling job), a TileServer running on an
// ephemeral loopback port in a background thread, and a tiny HTTP/1.1 client
// over a plain socket — so every test speaks real HTTP, bytes on the wire
// included. Every socket read has a timeout, so no test can hang.
#pragma once

#include <arpa/inet.h>
#include <brotli/decode.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "core/cdt/cdt.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "server/app/tile_server.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::test {

/// A hill with a ridge, over 1.2 km × 1.2 km at UTM 12N coordinates.
inline double hillZ(double x, double y) {
  return 1600 + 80 * std::exp(-((x - 500) * (x - 500) + (y - 700) * (y - 700)) / 4e4) +
         15 * std::sin(x / 90.0) * std::cos(y / 70.0);
}

/// The synthetic TIN the test store is built from (EPSG:26912).
inline TinData testTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  std::vector<Point3> points;
  for (int j = 0; j <= 40; ++j)
    for (int i = 0; i <= 40; ++i) {
      // Jittered inside, straight edges (the hull is the square).
      const bool inside = i > 0 && i < 40 && j > 0 && j < 40;
      const double x = i * 30.0 + (inside ? (i % 3) * 1.7 : 0), y = j * 30.0 + (inside ? (j % 4) * 1.3 : 0);
      points.push_back({430000 + x, 4515000 + y, hillZ(x, y)});
    }
  cdt.insertPoints(points, spots);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  tin.crs = "EPSG:26912";
  return tin;
}

/// A directory (per process) holding "hill.tin" and "hill.3dtiles", the
/// archive tiled from testTin(); built on first use.
inline std::filesystem::path testStoreDir() {
  static const std::filesystem::path dir = [] {
    const auto d = scratchDir("server-store-" + std::to_string(::getpid()));
    const TinData tin = testTin();
    ingest::writeTinFile(d / "hill.tin", tin);
    ingest::TileJobOptions options;
    options.tiler.tolerance = 0.25;
    options.tiler.maxTriangles = 512;
    options.tiler.maxZoom = 3;
    ingest::runTileJob(tin, (d / "hill.tin").string(), d / "hill.3dtiles", options);
    return d;
  }();
  return dir;
}

/// "hill-coarse.3dtiles" beside testStoreDir()'s archive: the same TIN
/// tiled at another tolerance, so its files differ; built on first use.
inline std::filesystem::path coarseStore() {
  static const std::filesystem::path path = [] {
    const auto p = testStoreDir() / "hill-coarse.3dtiles";
    ingest::TileJobOptions options;
    options.tiler.tolerance = 2;
    options.tiler.maxTriangles = 512;
    options.tiler.maxZoom = 2;
    ingest::runTileJob(testTin(), (testStoreDir() / "hill.tin").string(), p, options);
    return p;
  }();
  return path;
}

/// A copy of the test store written as `name` (its kind from the name: an
/// archive for ".3dtiles", else a directory) in a fresh scratch directory
/// `scratch`, with the keys `keep` accepts (all by default).
inline std::filesystem::path testStoreCopy(const std::string& scratch, const std::string& name,
                                           bool (*keep)(const std::string&) = nullptr) {
  const auto source = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  std::vector<std::string> keys;
  for (const auto& k : source->keys())
    if (!keep || keep(k)) keys.push_back(k);
  const auto target = scratchDir(scratch + "-" + std::to_string(::getpid())) / name;
  store::writeStore(*source, keys, target);
  return target;
}

/// A TileServer on 127.0.0.1, an ephemeral port, serving in a background
/// thread until destroyed (or stopped).
class RunningServer {
 public:
  explicit RunningServer(server::TileServerOptions options = defaults())
      : server_(std::make_unique<server::TileServer>(std::move(options))),
        thread_([this] { server_->run(); }) {}
  ~RunningServer() {
    if (!thread_.joinable()) return;
    server_->stop();
    thread_.join();
  }
  static server::TileServerOptions defaults() {
    server::TileServerOptions o;
    o.stores = {testStoreDir() / "hill.3dtiles"};
    o.http.port = 0;
    o.http.threads = 2;
    o.http.limits.readTimeout = std::chrono::milliseconds(3000);
    o.http.limits.idleTimeout = std::chrono::milliseconds(5000);
    o.http.limits.shutdownGrace = std::chrono::milliseconds(5000);
    o.log = nullptr;
    o.notices = nullptr;
    return o;
  }
  [[nodiscard]] unsigned short port() const { return server_->port(); }
  [[nodiscard]] server::TileServer& server() { return *server_; }
  /// Stops and waits for run() to return.
  void stopAndJoin() {
    server_->stop();
    thread_.join();
  }

 private:
  std::unique_ptr<server::TileServer> server_;
  std::thread thread_;
};

struct HttpResponse {
  int status = 0;                             ///< 0: no (complete) response
  std::map<std::string, std::string> headers;  ///< names lower-cased
  std::string body;
  [[nodiscard]] std::string header(const std::string& name) const {
    const auto it = headers.find(name);
    return it == headers.end() ? std::string() : it->second;
  }
};

/// One TCP connection to the server; requests over it use keep-alive.
class HttpConnection {
 public:
  explicit HttpConnection(unsigned short port, int timeoutMs = 10000) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    timeval tv{timeoutMs / 1000, (timeoutMs % 1000) * 1000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  }
  ~HttpConnection() { close(); }
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  [[nodiscard]] bool connected() const { return connected_; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  /// Sends raw bytes; false when the connection is gone.
  bool send(const std::string& bytes) {
    std::size_t sent = 0;
    while (sent < bytes.size()) {
      const auto n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) return false;
      sent += static_cast<std::size_t>(n);
    }
    return true;
  }
  /// Reads one response; status 0 when the connection closed or timed out first.
  HttpResponse read(bool head = false) {
    HttpResponse r;
    std::size_t end;
    while ((end = buffer_.find("\r\n\r\n")) == std::string::npos)
      if (!fill()) return r;
    const std::string headText = buffer_.substr(0, end);
    buffer_.erase(0, end + 4);
    std::size_t lineEnd = headText.find("\r\n");
    const std::string statusLine = headText.substr(0, lineEnd);
    if (statusLine.size() < 12) return r;
    const int status = std::atoi(statusLine.c_str() + 9);
    while (lineEnd != std::string::npos) {
      const std::size_t next = headText.find("\r\n", lineEnd + 2);
      const std::string line = headText.substr(lineEnd + 2, next - lineEnd - 2);
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::string name = line.substr(0, colon);
        for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        r.headers[name] = line.substr(line.find_first_not_of(' ', colon + 1));
      }
      lineEnd = next;
    }
    std::size_t length = 0;
    if (!head && status != 304 && status != 204 && r.headers.count("content-length"))
      length = std::stoul(r.headers["content-length"]);
    while (buffer_.size() < length)
      if (!fill()) return r;
    r.body = buffer_.substr(0, length);
    buffer_.erase(0, length);
    r.status = status;
    return r;
  }
  /// Reads up to n raw bytes (fewer when the connection ends first).
  std::string readBytes(std::size_t n) {
    while (buffer_.size() < n)
      if (!fill()) break;
    std::string out = buffer_.substr(0, n);
    buffer_.erase(0, out.size());
    return out;
  }
  /// Whether any byte of an answer has arrived, without waiting.
  bool anyArrived() {
    char c;
    return !buffer_.empty() || ::recv(fd_, &c, 1, MSG_PEEK | MSG_DONTWAIT) > 0;
  }
  /// Closes with a TCP reset (SO_LINGER 0), as a crashed client would.
  void resetAndClose() {
    linger hard{1, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_LINGER, &hard, sizeof hard);
    close();
  }
  /// True when the server closed the connection (read returns 0) before
  /// the timeout, with no more bytes.
  bool closedByServer() {
    char c;
    return buffer_.empty() && ::recv(fd_, &c, 1, 0) == 0;
  }
  /// GET (or another method) with extra header lines ("Name: value\r\n").
  HttpResponse request(const std::string& target, const std::string& headers = "",
                       const std::string& method = "GET", const std::string& body = "") {
    std::string req = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + headers;
    if (!body.empty() || method == "POST") req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
    req += "\r\n" + body;
    if (!send(req)) return {};
    return read(method == "HEAD");
  }

 private:
  bool fill() {
    char chunk[65536];
    const auto n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n <= 0) return false;
    buffer_.append(chunk, static_cast<std::size_t>(n));
    return true;
  }
  int fd_ = -1;
  bool connected_ = false;
  std::string buffer_;
};

/// The bytes of a gzip stream (RFC 1952); "" when it is not one.
inline std::string gunzip(const std::string& packed) {
  std::string out(std::max<std::size_t>(1 << 20, packed.size() * 64), '\0');
  z_stream z{};
  if (inflateInit2(&z, 31) != Z_OK) return {};
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed.data()));
  z.avail_in = static_cast<uInt>(packed.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const bool whole = inflate(&z, Z_FINISH) == Z_STREAM_END;
  out.resize(whole ? z.total_out : 0);
  inflateEnd(&z);
  return out;
}

/// The bytes of a brotli stream (RFC 7932); "" when it is not one.
inline std::string unbrotli(const std::string& packed) {
  std::string out;
  BrotliDecoderState* state = BrotliDecoderCreateInstance(nullptr, nullptr, nullptr);
  std::size_t availableIn = packed.size();
  const auto* next = reinterpret_cast<const std::uint8_t*>(packed.data());
  BrotliDecoderResult result = BROTLI_DECODER_RESULT_NEEDS_MORE_OUTPUT;
  while (result == BROTLI_DECODER_RESULT_NEEDS_MORE_OUTPUT) {
    std::uint8_t chunk[65536];
    std::size_t availableOut = sizeof chunk;
    std::uint8_t* to = chunk;
    result = BrotliDecoderDecompressStream(state, &availableIn, &next, &availableOut, &to, nullptr);
    out.append(reinterpret_cast<const char*>(chunk), sizeof chunk - availableOut);
  }
  BrotliDecoderDestroyInstance(state);
  return result == BROTLI_DECODER_RESULT_SUCCESS ? out : std::string();
}

/// One request on a fresh connection.
inline HttpResponse httpGet(unsigned short port, const std::string& target,
                            const std::string& headers = "") {
  HttpConnection c(port);
  return c.request(target, headers);
}

}  // namespace tinsmith::test
