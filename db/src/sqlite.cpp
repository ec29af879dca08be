#include "pintag/db/sqlite.hpp"

#include <sqlite3.h>
#include <sys/stat.h>

#include <unordered_map>

namespace pintag::db {

/// The compiled statements of one connection, by SQL text. A slot is busy while a Statement holds
/// it. Bounded: the SQL PinTag runs is a fixed set, but a search builds its WHERE from the filters
/// given, and a bound keeps any future dynamic SQL from growing the cache without end.
struct StatementCache {
  static constexpr std::size_t kMaxStatements = 64;
  struct Slot {
    sqlite3_stmt* statement = nullptr;
    bool busy = false;
  };
  // Node-based: a Slot's address stays valid while other slots are added.
  std::unordered_map<std::string, Slot> slots;

  StatementCache() = default;
  StatementCache(const StatementCache&) = delete;
  StatementCache& operator=(const StatementCache&) = delete;
  ~StatementCache() {
    for (auto& [sql, slot] : slots) sqlite3_finalize(slot.statement);
  }
};

namespace {

[[noreturn]] void Throw(sqlite3* db, int code, std::string_view context) {
  std::string message(context);
  message += ": ";
  message += db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(code);
  const int extended = db != nullptr ? sqlite3_extended_errcode(db) : code;
  throw SqliteError(message, code & 0xff, extended, db != nullptr ? sqlite3_system_errno(db) : 0);
}

void Check(sqlite3* db, int code, std::string_view context) {
  if (code != SQLITE_OK) Throw(db, code, context);
}

}  // namespace

void Statement::Release::operator()(sqlite3_stmt* statement) const {
  if (slot_busy == nullptr) {
    sqlite3_finalize(statement);
    return;
  }
  // A failed step's error is repeated by sqlite3_reset; it was reported when it happened.
  sqlite3_reset(statement);
  sqlite3_clear_bindings(statement);
  *slot_busy = false;
}

Statement& Statement::bind(int index, std::int64_t value) {
  Check(db_, sqlite3_bind_int64(statement_.get(), index, value), "bind");
  return *this;
}

Statement& Statement::bind(int index, double value) {
  Check(db_, sqlite3_bind_double(statement_.get(), index, value), "bind");
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  // A non-null pointer even for "", so an empty string binds as '' and not as NULL.
  Check(db_,
        sqlite3_bind_text64(statement_.get(), index, text.empty() ? "" : text.data(), text.size(),
                            SQLITE_TRANSIENT, SQLITE_UTF8),
        "bind");
  return *this;
}

Statement& Statement::bindBlob(int index, const void* data, std::size_t size) {
  Check(db_,
        sqlite3_bind_blob64(statement_.get(), index, size == 0 ? "" : data, size, SQLITE_TRANSIENT),
        "bind");
  return *this;
}

Statement& Statement::bindNull(int index) {
  Check(db_, sqlite3_bind_null(statement_.get(), index), "bind");
  return *this;
}

bool Statement::step() {
  const int code = sqlite3_step(statement_.get());
  if (code == SQLITE_ROW) return true;
  if (code == SQLITE_DONE) return false;
  Throw(db_, code, "step");
}

int Statement::run() {
  while (step()) {
  }
  return sqlite3_changes(db_);
}

void Statement::reset() {
  // sqlite3_reset repeats the last step's error; step() already reported it.
  sqlite3_reset(statement_.get());
}

void Statement::clearBindings() {
  sqlite3_clear_bindings(statement_.get());
}

bool Statement::isNull(int column) const {
  return sqlite3_column_type(statement_.get(), column) == SQLITE_NULL;
}

std::int64_t Statement::getInt64(int column) const {
  return sqlite3_column_int64(statement_.get(), column);
}

double Statement::getDouble(int column) const {
  return sqlite3_column_double(statement_.get(), column);
}

std::string Statement::getText(int column) const {
  const auto* text = sqlite3_column_text(statement_.get(), column);
  const int size = sqlite3_column_bytes(statement_.get(), column);
  return text == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(text), size);
}

std::optional<std::string> Statement::getOptionalText(int column) const {
  if (isNull(column)) return std::nullopt;
  return getText(column);
}

std::string Statement::getBlob(int column) const {
  const void* data = sqlite3_column_blob(statement_.get(), column);
  const int size = sqlite3_column_bytes(statement_.get(), column);
  return data == nullptr ? std::string() : std::string(static_cast<const char*>(data), size);
}

void Connection::Closer::operator()(sqlite3* db) const {
  sqlite3_close_v2(db);
}

Connection::Connection(const std::string& path, const ConnectionOptions& options) : path_(path) {
  int flags = options.read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
  if (options.create && !options.read_only) flags |= SQLITE_OPEN_CREATE;
  // Each Connection is used by one thread at a time (see the header), so SQLite's own
  // per-connection mutex is not needed.
  flags |= SQLITE_OPEN_NOMUTEX | SQLITE_OPEN_EXRESCODE;
  sqlite3* raw = nullptr;
  const int code = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  db_.reset(raw);
  if (code != SQLITE_OK) Throw(raw, code, "cannot open database " + path);
  sqlite3_busy_timeout(raw, options.busy_timeout_ms);
  if (struct stat opened{}; ::stat(path.c_str(), &opened) == 0) {
    file_.emplace(opened.st_dev, opened.st_ino);
  }
  if (!options.read_only && options.wal) execute("PRAGMA journal_mode=WAL");
  // Statement journals in memory: a statement that fires the registry-version triggers (one per
  // row written) would otherwise write a temporary file per row, which made seeding 2x slower.
  execute("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON; PRAGMA temp_store=MEMORY;");
}

Connection::Connection(Connection&&) noexcept = default;
Connection& Connection::operator=(Connection&& other) noexcept {
  // The cached statements go before the connection they were compiled on.
  statements_.reset();
  db_ = std::move(other.db_);
  statements_ = std::move(other.statements_);
  path_ = std::move(other.path_);
  file_ = other.file_;
  return *this;
}
Connection::~Connection() = default;

Statement Connection::prepare(std::string_view sql) {
  if (!statements_) statements_ = std::make_unique<StatementCache>();
  auto& slots = statements_->slots;
  const std::string key(sql);
  const auto found = slots.find(key);
  if (found != slots.end() && !found->second.busy) {
    found->second.busy = true;
    return Statement(db_.get(), found->second.statement, &found->second.busy);
  }
  const bool cache = found == slots.end() && slots.size() < StatementCache::kMaxStatements;
  sqlite3_stmt* raw = nullptr;
  const int code = sqlite3_prepare_v3(db_.get(), sql.data(), static_cast<int>(sql.size()),
                                      cache ? SQLITE_PREPARE_PERSISTENT : 0, &raw, nullptr);
  // Finalized on any way out until it is handed over (a failed prepare, or a throwing insert).
  std::unique_ptr<sqlite3_stmt, Statement::Release> compiled(raw, Statement::Release{});
  if (code != SQLITE_OK) Throw(db_.get(), code, "prepare");
  if (raw == nullptr)
    throw SqliteError("prepare: no statement in the SQL text", SQLITE_MISUSE, SQLITE_MISUSE);
  if (!cache) return Statement(db_.get(), compiled.release(), nullptr);
  StatementCache::Slot& slot = slots[key];
  slot = {compiled.release(), true};
  return Statement(db_.get(), slot.statement, &slot.busy);
}

void Connection::execute(std::string_view sql) {
  const std::string text(sql);
  char* error = nullptr;
  const int code = sqlite3_exec(db_.get(), text.c_str(), nullptr, nullptr, &error);
  if (code != SQLITE_OK) {
    std::string message = error != nullptr ? error : sqlite3_errstr(code);
    sqlite3_free(error);
    throw SqliteError("execute: " + message, code & 0xff, sqlite3_extended_errcode(db_.get()));
  }
}

std::int64_t Connection::queryInt64(std::string_view sql) {
  Statement statement = prepare(sql);
  return statement.step() ? statement.getInt64(0) : 0;
}

void Connection::backupInto(Connection& destination) {
  sqlite3_backup* backup = sqlite3_backup_init(destination.handle(), "main", handle(), "main");
  if (backup == nullptr) {
    Throw(destination.handle(), sqlite3_errcode(destination.handle()), "backup");
  }
  // -1: every page in one step, so the source is read under a single read transaction. A busy
  // source (a rollback-journal writer) is waited for up to about 5 s.
  int code = SQLITE_OK;
  for (int attempt = 0; attempt < 500; ++attempt) {
    code = sqlite3_backup_step(backup, -1);
    if (code != SQLITE_BUSY && code != SQLITE_LOCKED) break;
    sqlite3_sleep(10);
  }
  sqlite3_backup_finish(backup);
  if (code != SQLITE_DONE) Throw(destination.handle(), code, "backup");
}

std::int64_t Connection::lastInsertRowid() const {
  return sqlite3_last_insert_rowid(db_.get());
}
int Connection::changes() const {
  return sqlite3_changes(db_.get());
}
bool Connection::fileIsAtPath() const {
  struct stat now {};
  return file_ && ::stat(path_.c_str(), &now) == 0 && now.st_dev == file_->first &&
         now.st_ino == file_->second;
}

void Connection::leaveWriteAheadLogsOnClose() {
  const int code = sqlite3_db_config(db_.get(), SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
  if (code != SQLITE_OK) Throw(db_.get(), code, "no checkpoint on close");
}

bool Connection::inTransaction() const {
  return sqlite3_get_autocommit(db_.get()) == 0;
}

Transaction::Transaction(Connection& connection) : connection_(connection) {
  connection_.execute("BEGIN IMMEDIATE");
}

Transaction::~Transaction() {
  if (done_) return;
  try {
    connection_.execute("ROLLBACK");
  } catch (...) {
    // A failed statement may already have rolled the transaction back; nothing else to do.
  }
}

void Transaction::commit() {
  connection_.execute("COMMIT");
  done_ = true;
}

ReadTransaction::ReadTransaction(Connection& connection) : connection_(connection) {
  connection_.execute("BEGIN");
}

ReadTransaction::~ReadTransaction() {
  try {
    connection_.execute("COMMIT");
  } catch (...) {
    // A statement that failed may have ended the transaction already; it wrote nothing, so a
    // rollback loses nothing either.
    try {
      if (connection_.inTransaction()) connection_.execute("ROLLBACK");
    } catch (...) {
      // Left open: the connection's owner sees inTransaction() (ConnectionPool closes it).
    }
  }
}

}  // namespace pintag::db
