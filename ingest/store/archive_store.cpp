// The archive store: one SQLite file with the table 3d-tiles-tools reads,
// media(key TEXT PRIMARY KEY, content BLOB).
//
// Threads: every member of an ArchiveStore may be called from several threads
// at once. Each call leases a connection from a small pool (a SQLite
// connection and its prepared statements are used by one thread at a time):
// a store opened for reading grows to kMaxReaders connections, so get() calls
// from server threads run side by side; a store opened for writing has one
// read-write connection, so its calls take turns.
//
// A staging archive (openStoreForWriting) is in WAL mode while its store
// lives, each put its own transaction, so readers in other connections or
// processes see a tile whole or not at all; closing the store switches it back
// to a rollback journal when no one else has it open. A final archive (writeStore) is written in
// one transaction with a fixed page size and no journal, then renamed into place; its bytes depend
// only on the keys, their order and their bytes (and the SQLite file format version, which is in
// the header).
#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <condition_variable>
#include <cstring>
#include <mutex>
#include <optional>
#include <vector>

#include "core/base/error.hpp"
#include "ingest/store/store_detail.hpp"

namespace tinsmith::store::detail {

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxReaders = 16;
constexpr int kBusyTimeoutMs = 10000;
constexpr const char* kCreateMedia = "CREATE TABLE media (key TEXT PRIMARY KEY, content BLOB)";
constexpr const char* kLayout =
    "PRAGMA page_size = 4096; PRAGMA auto_vacuum = NONE; PRAGMA encoding = 'UTF-8';";

struct DbCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
struct StmtFinalizer {
  void operator()(sqlite3_stmt* stmt) const { sqlite3_finalize(stmt); }
};
using Db = std::unique_ptr<sqlite3, DbCloser>;
using Stmt = std::unique_ptr<sqlite3_stmt, StmtFinalizer>;

// Leaves a statement ready for its next use however the step ended.
class StepScope {
 public:
  explicit StepScope(sqlite3_stmt* stmt) : stmt_(stmt) {}
  StepScope(const StepScope&) = delete;
  StepScope& operator=(const StepScope&) = delete;
  ~StepScope() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }

 private:
  sqlite3_stmt* stmt_;
};

std::string message(sqlite3* db) {
  return db ? sqlite3_errmsg(db) : "out of memory";
}

Db openDb(const fs::path& path, int flags, int& rc) {
  sqlite3* raw = nullptr;
  rc = sqlite3_open_v2(path.c_str(), &raw, flags | SQLITE_OPEN_NOMUTEX, nullptr);
  Db db(raw);
  if (rc == SQLITE_OK) {
    sqlite3_extended_result_codes(db.get(), 1);
    sqlite3_busy_timeout(db.get(), kBusyTimeoutMs);
  }
  return db;
}

Stmt prepare(sqlite3* db, const char* sql, int& rc) {
  sqlite3_stmt* raw = nullptr;
  rc = sqlite3_prepare_v2(db, sql, -1, &raw, nullptr);
  return Stmt(raw);
}

void bindText(sqlite3_stmt* stmt, int index, std::string_view text) {
  sqlite3_bind_text64(stmt, index, text.data(), text.size(), SQLITE_STATIC, SQLITE_UTF8);
}

/// SQLite's result: a value over its length limit (10⁹ bytes) is refused
/// (SQLITE_TOOBIG), and the statement would then store NULL in its place.
[[nodiscard]] int bindBlob(sqlite3_stmt* stmt, int index, std::string_view bytes) {
  // A null pointer would bind NULL; an empty tile is an empty blob.
  if (bytes.empty()) return sqlite3_bind_zeroblob(stmt, index, 0);
  return sqlite3_bind_blob64(stmt, index, bytes.data(), bytes.size(), SQLITE_STATIC);
}

/// The error for a value that could not be bound under `key`.
Error bindFailure(int rc, std::string_view key, std::size_t bytes, const fs::path& archive) {
  return ioError("cannot write the key '" + std::string(key) + "': " + sqlite3_errstr(rc) + " (" +
                     std::to_string(bytes) + " bytes; an archive's value holds at most 10^9)",
                 fileLocation(archive), "write a folder store instead (a name without .3dtiles)");
}

struct BlobCloser {
  void operator()(sqlite3_blob* blob) const { sqlite3_blob_close(blob); }
};
using Blob = std::unique_ptr<sqlite3_blob, BlobCloser>;

// Inserts `key` through `insert` (INSERT … (key, content) VALUES (?1, ?2))
// with `size` zero bytes (SQLite writes them without holding them), then
// writes the value over them a piece at a time from `fill`: no copy of the
// whole value is held, by SQLite or here. Returns the insert's result; the
// pieces are written only after SQLITE_DONE. Throws ioError when a piece
// cannot be written, and what `fill` throws. The caller's transaction makes
// it atomic.
int insertInPieces(sqlite3* db, sqlite3_stmt* insert, std::string_view key, std::uint64_t size,
                   const TileStore::PieceFiller& fill, const fs::path& archive) {
  {
    const StepScope scope(insert);
    bindText(insert, 1, key);
    if (const int rc = sqlite3_bind_zeroblob64(insert, 2, size); rc != SQLITE_OK)
      throw bindFailure(rc, key, size, archive);
    if (const int rc = sqlite3_step(insert); rc != SQLITE_DONE) return rc;
  }
  sqlite3_blob* opened = nullptr;
  const int rc =
      sqlite3_blob_open(db, "main", "media", "content", sqlite3_last_insert_rowid(db), 1, &opened);
  const Blob blob(opened);
  auto failure = [&] {
    return ioError("cannot write the key '" + std::string(key) + "': " + message(db),
                   fileLocation(archive), "check free disk space and permissions");
  };
  if (rc != SQLITE_OK) throw failure();
  copyPieces(size, fill, [&](std::uint64_t offset, std::span<const char> piece) {
    if (sqlite3_blob_write(blob.get(), piece.data(), static_cast<int>(piece.size()),
                           static_cast<int>(offset)) != SQLITE_OK)
      throw failure();
  });
  return SQLITE_DONE;
}

// One SQLite connection with the statements every store call uses.
struct Connection {
  Db db;
  Stmt get, contains, keys, put, size;
  Stmt rowid;  // null when the media table has no rowid (a value is then read whole)
};

bool isWritable(Access access) {
  return access != Access::Read;
}

// Opens a connection and checks the file is an archive; for a writable store,
// creates the media table in an empty database. Failures are inputError for a
// store opened for reading (the archive is the input) and ioError otherwise.
std::unique_ptr<Connection> connect(const fs::path& path, Access access) {
  auto fail = [&](const std::string& problem, const std::string& hint) -> Error {
    return isWritable(access) ? ioError(problem, fileLocation(path), hint)
                              : inputError(problem, fileLocation(path), hint);
  };
  const int flags =
      isWritable(access) ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY;
  auto connection = std::make_unique<Connection>();
  int rc = SQLITE_OK;
  connection->db = openDb(path, flags, rc);
  sqlite3* db = connection->db.get();
  if (rc != SQLITE_OK)
    throw fail("cannot open the archive: " + message(db), "check the path and its permissions");

  // The first statement reads the header: a file that is not SQLite fails here.
  int tables = 0;
  int media = 0;
  {
    Stmt probe = prepare(
        db, "SELECT count(*), total(type = 'table' AND name = 'media') FROM sqlite_master", rc);
    if (rc == SQLITE_OK) rc = sqlite3_step(probe.get());
    if ((rc & 0xFF) == SQLITE_NOTADB)
      throw fail("not a .3dtiles archive (the file is not a SQLite database)",
                 isWritable(access) ? "remove it or choose another output path"
                                    : "give a .3dtiles file written by tinsmith or 3d-tiles-tools");
    if (rc != SQLITE_ROW)
      throw fail("cannot read the archive: " + message(db), "check permissions");
    tables = sqlite3_column_int(probe.get(), 0);
    media = sqlite3_column_int(probe.get(), 1);
  }
  if (media == 0 && (!isWritable(access) || tables > 0))
    throw fail("not a .3dtiles archive: the SQLite database has no media table",
               isWritable(access) ? "remove it or choose another output path"
                                  : "give a .3dtiles file written by tinsmith or 3d-tiles-tools");
  if (isWritable(access)) {
    const std::string setup =
        (media == 0 ? std::string(kLayout) + kCreateMedia + ";" : std::string()) +
        "PRAGMA journal_mode = WAL; PRAGMA synchronous = NORMAL;";
    char* error = nullptr;
    rc = sqlite3_exec(db, setup.c_str(), nullptr, nullptr, &error);
    const std::string reason = error ? error : message(db);
    sqlite3_free(error);
    if (rc != SQLITE_OK)
      throw fail("cannot prepare the archive for writing: " + reason, "check permissions");
  }

  const std::pair<Stmt*, const char*> statements[] = {
      {&connection->get, "SELECT content FROM media WHERE key = ?1"},
      {&connection->contains, "SELECT 1 FROM media WHERE key = ?1"},
      {&connection->keys, "SELECT key FROM media ORDER BY key"},
      {&connection->size,
       "SELECT length(content), typeof(content) = 'text' FROM media WHERE key = ?1"},
      {&connection->put, isWritable(access)
                             ? "INSERT OR REPLACE INTO media (key, content) VALUES (?1, ?2)"
                             : nullptr}};
  for (const auto& [stmt, sql] : statements) {
    if (!sql) continue;
    *stmt = prepare(db, sql, rc);
    if (rc != SQLITE_OK)
      throw fail(
          "not a .3dtiles archive: the media table is not media(key, content): " + message(db),
          "give a .3dtiles file written by tinsmith or 3d-tiles-tools");
  }
  connection->rowid = prepare(db, "SELECT rowid FROM media WHERE key = ?1", rc);
  if (rc != SQLITE_OK) connection->rowid.reset();
  return connection;
}

// Connections handed to one thread at a time; grows on demand up to `capacity`.
//
// Every connection is on the file the first one opened: an archive renamed
// over the path meanwhile (a new version of the store) is not read by a
// store opened on the old one, so no reader mixes the two versions. A new
// connection is kept only when the path still names the first one's file
// after it opened (SQLite opens its file in sqlite3_open_v2; the old file
// cannot come back under the name, since its entry was replaced); otherwise
// it is closed and the pool stops growing: later calls take turns on the
// connections it has.
class ConnectionPool {
 public:
  ConnectionPool(fs::path path, Access access, std::size_t capacity)
      : path_(std::move(path)), access_(access), capacity_(capacity) {
    // The identity is taken before and after the first connection: equal,
    // the connection is on that file. A file replaced in between is taken
    // as it is now (its first reader defines the store's version).
    for (int attempt = 0;; ++attempt) {
      const auto before = fileIdentity(path_);
      auto first = connect(path_, access_);
      const auto after = fileIdentity(path_);
      if ((before && after && *before == *after) || attempt == 3) {
        identity_ = after;
        idle_.push_back(std::move(first));
        break;
      }
    }
    opened_ = 1;
  }

  class Lease {
   public:
    Lease(const ConnectionPool& pool, std::unique_ptr<Connection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    ~Lease() { pool_.giveBack(std::move(connection_)); }
    Connection* operator->() const { return connection_.get(); }

   private:
    const ConnectionPool& pool_;
    std::unique_ptr<Connection> connection_;
  };

  Lease acquire() const {
    std::unique_lock lock(mutex_);
    return acquireLocked(lock);
  }

 private:
  Lease acquireLocked(std::unique_lock<std::mutex>& lock) const {
    freed_.wait(lock, [&] { return !idle_.empty() || opened_ < capacity_; });
    if (!idle_.empty()) {
      std::unique_ptr<Connection> connection = std::move(idle_.back());
      idle_.pop_back();
      return {*this, std::move(connection)};
    }
    ++opened_;
    lock.unlock();
    std::unique_ptr<Connection> connection;
    try {
      connection = connect(path_, access_);
    } catch (...) {
      // What is under the name now may not be an archive at all (half
      // copied): this store's own file is still readable.
      const bool replaced = fileIdentity(path_) != identity_;
      lock.lock();
      --opened_;
      if (!replaced) {
        freed_.notify_one();
        throw;
      }
      capacity_ = opened_;
      return acquireLocked(lock);
    }
    if (identity_ && fileIdentity(path_) == identity_) return {*this, std::move(connection)};
    // Another file under the name (or none): not this store's. Closed, and
    // the pool keeps the connections it has.
    connection.reset();
    lock.lock();
    --opened_;
    capacity_ = opened_;
    return acquireLocked(lock);
  }

  void giveBack(std::unique_ptr<Connection> connection) const {
    {
      std::lock_guard lock(mutex_);
      idle_.push_back(std::move(connection));
    }
    freed_.notify_one();
  }

  fs::path path_;
  Access access_;
  mutable std::size_t capacity_;  // lowered to what is open when the path names another file
  std::optional<FileIdentity> identity_;
  mutable std::mutex mutex_;
  mutable std::condition_variable freed_;
  mutable std::vector<std::unique_ptr<Connection>> idle_;
  mutable std::size_t opened_ = 0;
};

class ArchiveStore final : public TileStore {
 public:
  ArchiveStore(fs::path path, Access access)
      : path_(std::move(path)),
        access_(access),
        pool_(path_, access, isWritable(access) ? 1 : kMaxReaders) {}

  ArchiveStore(const ArchiveStore&) = delete;
  ArchiveStore& operator=(const ArchiveStore&) = delete;

  // A staging archive goes back to a rollback journal when its writer is done,
  // so later read-only openers need no -wal or -shm beside it. While another
  // connection has it open the switch fails at once (no busy wait) and the
  // archive stays in WAL mode, which is just as readable.
  ~ArchiveStore() override {
    if (!isWritable(access_)) return;
    try {
      const auto connection = pool_.acquire();
      sqlite3_busy_timeout(connection->db.get(), 0);
      sqlite3_exec(connection->db.get(), "PRAGMA journal_mode = DELETE", nullptr, nullptr, nullptr);
    } catch (...) {
      // A destructor must not throw; the archive is complete either way.
    }
  }

  [[nodiscard]] StoreKind kind() const override { return StoreKind::Archive; }
  [[nodiscard]] const fs::path& path() const override { return path_; }

  [[nodiscard]] std::optional<std::string> get(std::string_view key) const override {
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3_stmt* stmt = connection->get.get();
    const StepScope scope(stmt);
    if (!stepKey(stmt, key, connection->db.get())) return std::nullopt;
    const auto* data = static_cast<const char*>(sqlite3_column_blob(stmt, 0));
    const int size = sqlite3_column_bytes(stmt, 0);
    return data ? std::string(data, static_cast<std::size_t>(size)) : std::string();
  }

  [[nodiscard]] bool contains(std::string_view key) const override {
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3_stmt* stmt = connection->contains.get();
    const StepScope scope(stmt);
    return stepKey(stmt, key, connection->db.get());
  }

  [[nodiscard]] std::vector<std::string> keys() const override {
    const auto connection = pool_.acquire();
    sqlite3_stmt* stmt = connection->keys.get();
    const StepScope scope(stmt);
    std::vector<std::string> keys;
    int rc = SQLITE_OK;
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
      keys.emplace_back(text ? text : "", static_cast<std::size_t>(sqlite3_column_bytes(stmt, 0)));
    }
    if (rc != SQLITE_DONE)
      throw ioError("cannot list the archive's keys: " + message(connection->db.get()),
                    fileLocation(path_));
    return keys;
  }

  void put(std::string_view key, std::string_view bytes) override {
    if (!isWritable(access_))
      throw usageError("put into '" + path_.string() + "', which was opened for reading",
                       "open the store with openStoreForWriting");
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3_stmt* stmt = connection->put.get();
    const StepScope scope(stmt);
    bindText(stmt, 1, key);
    if (const int rc = bindBlob(stmt, 2, bytes); rc != SQLITE_OK)
      throw bindFailure(rc, key, bytes.size(), path_);
    if (sqlite3_step(stmt) != SQLITE_DONE)
      throw ioError(
          "cannot write the key '" + std::string(key) + "': " + message(connection->db.get()),
          fileLocation(path_), "check free disk space and permissions");
  }

  [[nodiscard]] std::optional<std::uint64_t> size(std::string_view key) const override {
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3_stmt* stmt = connection->size.get();
    const StepScope scope(stmt);
    if (!stepKey(stmt, key, connection->db.get())) return std::nullopt;
    // length() counts a text's characters (another tool may store text):
    // its size is then that of the bytes get() gives.
    if (sqlite3_column_int(stmt, 1) == 0)
      return static_cast<std::uint64_t>(sqlite3_column_int64(stmt, 0));  // NULL content: 0
    sqlite3_stmt* text = connection->get.get();
    const StepScope textScope(text);
    if (!stepKey(text, key, connection->db.get())) throw readFailure(key, connection->db.get());
    (void)sqlite3_column_blob(text, 0);  // as bytes, not converted
    return static_cast<std::uint64_t>(sqlite3_column_bytes(text, 0));
  }

  void read(std::string_view key, std::uint64_t offset, std::span<char> out) const override {
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3* db = connection->db.get();
    // `end`: where the value ends; none when it is not there.
    const auto shortValue = [&](std::optional<std::uint64_t> end) {
      return ioError("cannot read the key '" + std::string(key) + "': " +
                         (end ? "it ends at byte " + std::to_string(*end) + ", before " +
                                    std::to_string(offset + out.size())
                              : std::string("it is not in the archive")),
                     fileLocation(path_));
    };
    if (!connection->rowid) {  // a media table without rowids: the value whole
      sqlite3_stmt* stmt = connection->get.get();
      const StepScope scope(stmt);
      if (!stepKey(stmt, key, db)) throw shortValue(std::nullopt);
      const auto* data = static_cast<const char*>(sqlite3_column_blob(stmt, 0));  // then its size
      const auto size = static_cast<std::uint64_t>(sqlite3_column_bytes(stmt, 0));
      if (size < offset + out.size()) throw shortValue(size);
      if (!out.empty()) std::memcpy(out.data(), data + offset, out.size());
      return;
    }
    sqlite3_int64 rowid = 0;
    {
      sqlite3_stmt* stmt = connection->rowid.get();
      const StepScope scope(stmt);
      if (!stepKey(stmt, key, db)) throw shortValue(std::nullopt);
      rowid = sqlite3_column_int64(stmt, 0);
    }
    sqlite3_blob* opened = nullptr;
    const int rc = sqlite3_blob_open(db, "main", "media", "content", rowid, 0, &opened);
    const Blob blob(opened);
    if (rc != SQLITE_OK) throw readFailure(key, db);
    const auto size = static_cast<std::uint64_t>(sqlite3_blob_bytes(blob.get()));
    if (size < offset + out.size()) throw shortValue(size);
    if (sqlite3_blob_read(blob.get(), out.data(), static_cast<int>(out.size()),
                          static_cast<int>(offset)) != SQLITE_OK)
      throw readFailure(key, db);
  }

  void putInPieces(std::string_view key, std::uint64_t size, const PieceFiller& fill) override {
    if (!isWritable(access_))
      throw usageError("put into '" + path_.string() + "', which was opened for reading",
                       "open the store with openStoreForWriting");
    requireValidKey(key, path_);
    const auto connection = pool_.acquire();
    sqlite3* db = connection->db.get();
    const auto failure = [&] {
      return ioError("cannot write the key '" + std::string(key) + "': " + message(db),
                     fileLocation(path_), "check free disk space and permissions");
    };
    // One transaction: readers see the value whole or not at all, and a
    // failure leaves what was there.
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) != SQLITE_OK)
      throw failure();
    try {
      if (insertInPieces(db, connection->put.get(), key, size, fill, path_) != SQLITE_DONE)
        throw failure();
      if (sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) throw failure();
    } catch (...) {
      sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  }

 private:
  // Binds `key` as ?1 of `stmt` and steps it: true on a row, false when the
  // key is not there; throws readFailure otherwise. The caller's StepScope
  // resets it.
  bool stepKey(sqlite3_stmt* stmt, std::string_view key, sqlite3* db) const {
    bindText(stmt, 1, key);
    const int rc = sqlite3_step(stmt);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) throw readFailure(key, db);
    return rc == SQLITE_ROW;
  }

  Error readFailure(std::string_view key, sqlite3* db) const {
    return ioError("cannot read the key '" + std::string(key) + "': " + message(db),
                   fileLocation(path_));
  }

  fs::path path_;
  Access access_;
  ConnectionPool pool_;
};

// The files SQLite may keep beside a database. A stale one beside a new file
// would be replayed into it, so they go before a fresh archive takes the name.
void removeSidecars(const fs::path& path) {
  for (const char* suffix : {"-journal", "-wal", "-shm"}) {
    std::error_code ec;
    fs::path sidecar = path;
    sidecar += suffix;
    fs::remove(sidecar, ec);
    if (ec)
      throw ioError(
          "cannot remove the stale '" + sidecar.filename().string() + "': " + ec.message(),
          fileLocation(path), "check permissions");
  }
}

// Removes a half-written temporary archive unless released.
class TempArchive {
 public:
  explicit TempArchive(fs::path path) : path_(std::move(path)) {}
  TempArchive(const TempArchive&) = delete;
  TempArchive& operator=(const TempArchive&) = delete;
  ~TempArchive() {
    if (path_.empty()) return;
    std::error_code ec;
    fs::remove(path_, ec);
    fs::path journal = path_;
    journal += "-journal";
    fs::remove(journal, ec);
  }
  [[nodiscard]] const fs::path& path() const { return path_; }
  void release() { path_.clear(); }

 private:
  fs::path path_;
};

void syncPath(const fs::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

std::unique_ptr<TileStore> openArchive(const fs::path& path, Access access) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    const std::string problem = "is a folder, not a .3dtiles archive";
    if (isWritable(access))
      throw ioError(problem, fileLocation(path), "remove it or choose another output path");
    throw inputError(problem, fileLocation(path),
                     "an archive is one file; a folder store's name must not end in .3dtiles");
  }
  if (sqlite3_threadsafe() == 0)
    throw internalError("SQLite was built without thread support, which the archive store needs");
  if (isWritable(access)) createFolderFor(path.parent_path(), path);
  if (access == Access::Fresh) {
    fs::remove(path, ec);
    if (ec)
      throw ioError("cannot remove the old archive: " + ec.message(), fileLocation(path),
                    "check permissions");
    removeSidecars(path);
  }
  return std::make_unique<ArchiveStore>(path, access);
}

void writeArchive(const TileStore& source, std::span<const std::string> keys,
                  const fs::path& target) {
  createFolderFor(target.parent_path(), target);
  std::error_code ec;
  if (fs::is_directory(target, ec))
    throw ioError("the target is a folder, not a .3dtiles archive", fileLocation(target),
                  "remove it or choose another output path");
  TempArchive temp(tempSibling(target));
  {
    int rc = SQLITE_OK;
    Db db = openDb(temp.path(), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, rc);
    auto fail = [&](const std::string& what) {
      return ioError(what + ": " + message(db.get()), fileLocation(target),
                     "check free disk space and permissions");
    };
    if (rc != SQLITE_OK) throw fail("cannot create the archive");
    // No journal: a failed write leaves a temporary file that is removed, never
    // the target. One transaction, so the change counter in the header is fixed.
    const std::string setup = std::string(kLayout) +
                              "PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; BEGIN; " +
                              kCreateMedia + ";";
    if (sqlite3_exec(db.get(), setup.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK)
      throw fail("cannot create the archive");
    Stmt insert = prepare(db.get(), "INSERT INTO media (key, content) VALUES (?1, ?2)", rc);
    if (rc != SQLITE_OK) throw fail("cannot create the archive");
    for (const std::string& key : keys) {
      const std::uint64_t size = sizeForCopy(source, key);
      if (size > kCopyPieceBytes) {  // a TIN's piece: not held whole
        rc = insertInPieces(
            db.get(), insert.get(), key, size,
            [&](std::uint64_t offset, std::span<char> piece) { source.read(key, offset, piece); },
            target);
      } else {
        const std::string bytes = bytesForCopy(source, key);
        const StepScope scope(insert.get());
        bindText(insert.get(), 1, key);
        if (rc = bindBlob(insert.get(), 2, bytes); rc != SQLITE_OK)
          throw bindFailure(rc, key, bytes.size(), target);
        rc = sqlite3_step(insert.get());
      }
      if (rc == SQLITE_CONSTRAINT_PRIMARYKEY)
        throw inputError("the key '" + key + "' is listed twice for the archive",
                         fileLocation(target), "list each key once");
      if (rc != SQLITE_DONE) throw fail("cannot write the key '" + key + "'");
    }
    insert.reset();
    if (sqlite3_exec(db.get(), "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK)
      throw fail("cannot finish the archive");
    if (sqlite3_close(db.get()) != SQLITE_OK) throw fail("cannot close the archive");
    (void)db.release();
  }
  syncPath(temp.path(), O_RDONLY);
  removeSidecars(target);
  fs::rename(temp.path(), target, ec);
  if (ec)
    throw ioError("cannot move the finished archive into place: " + ec.message(),
                  fileLocation(target), "check that the target folder is writable");
  temp.release();
  syncPath(target.parent_path().empty() ? fs::path(".") : target.parent_path(),
           O_RDONLY | O_DIRECTORY);
}

}  // namespace tinsmith::store::detail
