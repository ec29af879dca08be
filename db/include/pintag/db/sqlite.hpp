#pragma once
// A small RAII layer over the SQLite C API: Connection, Statement, Transaction and one exception
// type. It is the only code in PinTag that calls sqlite3_*; <sqlite3.h> stays in db/src.
//
// Thread-safety: a Connection and its Statements must be used by one thread at a time. They are
// opened with SQLITE_OPEN_NOMUTEX (no per-call locking), and statements share the connection's
// error state and transaction anyway. Give each thread its own Connection (or guard one with a
// mutex); WAL lets any number of reader connections run beside the one writer.
//
// Prepared statements are cached per Connection, keyed by their SQL text: compiling a statement
// cost a lookup more than running it. A Statement that ends goes back to the cache reset and
// unbound; two live Statements with the same SQL get separate compiled copies. A Connection must
// outlive its Statements.

#include <sys/types.h>

#include <cerrno>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

struct sqlite3;
struct sqlite3_stmt;

namespace pintag::db {

/// An SQLite failure: the message, SQLite's primary and extended result codes, and the errno of
/// the system call that failed under it (0 when none did).
class SqliteError : public std::runtime_error {
 public:
  SqliteError(const std::string& message, int code, int extended_code, int system_errno = 0)
      : std::runtime_error(message),
        code_(code),
        extended_code_(extended_code),
        system_errno_(system_errno) {}
  int code() const { return code_; }  ///< primary result code, e.g. 5 = SQLITE_BUSY
  int extendedCode() const { return extended_code_; }
  bool isBusy() const { return code_ == 5 || code_ == 6; }  ///< SQLITE_BUSY or SQLITE_LOCKED
  bool isConstraint() const { return code_ == 19; }         ///< SQLITE_CONSTRAINT
  bool isFull() const { return code_ == 13; }               ///< SQLITE_FULL: no room to write
  bool isReadOnly() const { return code_ == 8; }            ///< SQLITE_READONLY
  int systemErrno() const { return system_errno_; }
  /// SQLITE_CANTOPEN because the process (EMFILE) or the system (ENFILE) had no file descriptor
  /// left: the one failure to open that passes by itself.
  bool outOfDescriptors() const {
    return code_ == 14 && (system_errno_ == EMFILE || system_errno_ == ENFILE);
  }

 private:
  int code_;
  int extended_code_;
  int system_errno_;
};

class Connection;
struct StatementCache;

/// A prepared statement. Move-only; returned to its connection's cache (or finalized) in its
/// destructor. Parameters are numbered from 1,
/// columns from 0. Text is bound and read with its length, so embedded NULs survive.
class Statement {
 public:
  Statement(Statement&&) noexcept = default;
  Statement& operator=(Statement&&) noexcept = default;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement() = default;

  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, std::int64_t{value}); }
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view text);  ///< copied by SQLite (SQLITE_TRANSIENT)
  Statement& bind(int index, const char* text) { return bind(index, std::string_view(text)); }
  Statement& bindBlob(int index, const void* data, std::size_t size);
  Statement& bindNull(int index);
  template <typename T>
  Statement& bind(int index, const std::optional<T>& value) {
    return value ? bind(index, *value) : bindNull(index);
  }

  /// Runs one step: true when a row is available, false when done. Throws SqliteError.
  bool step();
  /// Steps to completion, expecting no rows to matter; returns sqlite3_changes afterwards.
  int run();
  /// Rewinds so the statement can run again; bindings are kept.
  void reset();
  void clearBindings();

  bool isNull(int column) const;
  std::int64_t getInt64(int column) const;
  int getInt(int column) const { return static_cast<int>(getInt64(column)); }
  double getDouble(int column) const;
  std::string getText(int column) const;  ///< NULL reads as ""
  std::optional<std::string> getOptionalText(int column) const;
  std::string getBlob(int column) const;

 private:
  friend class Connection;
  /// Where the statement goes when it ends: back to its cache slot (`slot` non-null), else
  /// finalized.
  struct Release {
    bool* slot_busy = nullptr;
    void operator()(sqlite3_stmt* statement) const;
  };
  Statement(sqlite3* db, sqlite3_stmt* statement, bool* slot_busy)
      : db_(db), statement_(statement, Release{slot_busy}) {}

  sqlite3* db_;
  std::unique_ptr<sqlite3_stmt, Release> statement_;
};

/// How to open a Connection.
struct ConnectionOptions {
  bool create = true;          ///< create the file when missing (else fail)
  bool read_only = false;      ///< open read-only
  int busy_timeout_ms = 5000;  ///< how long a statement waits for a lock before SQLITE_BUSY
  /// Switch the file to WAL on open (never when read-only). OpenDatabase switches it itself once
  /// it knows the file is its own, so that a file it refuses is left as it was.
  bool wal = true;
};

/// One open database file. Move-only; closed in its destructor. Opening sets WAL (unless
/// read-only or not `wal`), synchronous=NORMAL, busy_timeout and foreign_keys=ON.
class Connection {
 public:
  explicit Connection(const std::string& path, const ConnectionOptions& options = {});
  Connection(Connection&&) noexcept;
  Connection& operator=(Connection&&) noexcept;
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection();

  /// Runs one or more SQL statements without parameters (schema, pragmas). Never user input.
  void execute(std::string_view sql);
  /// A statement for `sql`, compiled once per connection and then taken from its cache. SQL
  /// holding no statement (empty, only a comment) is an error.
  Statement prepare(std::string_view sql);
  /// The single integer a query such as `SELECT count(*) ...` or `PRAGMA user_version` yields.
  std::int64_t queryInt64(std::string_view sql);

  /// Copies this whole database into `destination` with SQLite's online backup API, in one pass
  /// under one read transaction, so the copy is the state of one instant even while other
  /// connections write. `destination`'s previous content is replaced. Throws SqliteError.
  void backupInto(Connection& destination);

  std::int64_t lastInsertRowid() const;
  int changes() const;
  bool inTransaction() const;
  const std::string& path() const { return path_; }

  /// Whether the file at path() is the one this connection opened (its device and inode, taken
  /// at open): false once it was moved, removed or replaced. Another connection opened by the
  /// path then opens the other file, which would take this file's write-ahead log as its own.
  bool fileIsAtPath() const;
  /// This connection's closing checkpoints no write-ahead log, the attached databases' included
  /// (SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE): a connection that only reads another database must not
  /// be the one that writes its log into it, and deletes the log, when it closes last.
  void leaveWriteAheadLogsOnClose();

 private:
  friend class Statement;
  sqlite3* handle() const { return db_.get(); }

  struct Closer {
    void operator()(sqlite3* db) const;
  };
  std::unique_ptr<sqlite3, Closer> db_;
  // Declared after db_, so its statements are finalized before the connection closes.
  std::unique_ptr<StatementCache> statements_;
  std::string path_;
  std::optional<std::pair<dev_t, ino_t>> file_;  ///< the opened file's device and inode
};

/// BEGIN IMMEDIATE in the constructor (takes the write lock up front, so a transaction never
/// fails half-way with SQLITE_BUSY on upgrade); ROLLBACK in the destructor unless commit() ran.
class Transaction {
 public:
  explicit Transaction(Connection& connection);
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();
  void commit();

 private:
  Connection& connection_;
  bool done_ = false;
};

/// BEGIN (deferred) in the constructor, COMMIT in the destructor: the reads between see one
/// state of the database (in WAL mode, the one of their first read), whatever commits meanwhile.
class ReadTransaction {
 public:
  explicit ReadTransaction(Connection& connection);
  ReadTransaction(const ReadTransaction&) = delete;
  ReadTransaction& operator=(const ReadTransaction&) = delete;
  ~ReadTransaction();

 private:
  Connection& connection_;
};

}  // namespace pintag::db
