#include "pintag/db/snapshot.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "guard.hpp"
#include "key_continuity.hpp"
#include "pintag/codec/file_output.hpp"
#include "pintag/db/database.hpp"

namespace pintag::db {
namespace {

std::string SystemError(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

/// fsync on a file or a directory; throws std::runtime_error.
void Sync(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_DIRECTORY : 0) | O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(SystemError("cannot open " + path));
  const bool synced = ::fsync(fd) == 0;
  const std::string error = synced ? "" : SystemError("fsync " + path);
  ::close(fd);
  if (!synced) throw std::runtime_error(error);
}

/// A temporary file and the side files SQLite may keep beside it while it is written.
constexpr std::array<const char*, 4> kSideSuffixes = {"", "-journal", "-wal", "-shm"};

/// The temporary files being written, as RemoveSnapshotTemporariesOnSignal reads them. A slot's
/// paths are written before it is marked in use and it is unmarked before they change, so a
/// handler that interrupts either step never reads half a path.
struct PendingTemporary {
  static constexpr std::size_t kMaxPath = 4096;
  std::atomic<bool> in_use{false};
  std::array<std::array<char, kMaxPath>, kSideSuffixes.size()> files{};
};
std::array<PendingTemporary, 4> g_pending;
std::mutex g_pending_claims;  // between threads only: a signal handler never takes it
static_assert(std::atomic<bool>::is_always_lock_free);

/// A slot holding `path`, or nullptr when all are taken or the path is too long (the file is
/// then only removed by TemporaryBeside, as before).
PendingTemporary* Register(const std::string& path) {
  if (path.size() + std::strlen("-journal") >= PendingTemporary::kMaxPath) return nullptr;
  const std::lock_guard lock(g_pending_claims);
  for (PendingTemporary& slot : g_pending) {
    if (slot.in_use.load(std::memory_order_acquire)) continue;
    for (std::size_t i = 0; i < kSideSuffixes.size(); ++i) {
      const std::string file = path + kSideSuffixes[i];
      std::copy(file.begin(), file.end(), slot.files[i].begin());
      slot.files[i][file.size()] = '\0';
    }
    slot.in_use.store(true, std::memory_order_release);
    return &slot;
  }
  return nullptr;
}

void Unregister(PendingTemporary* slot) {
  if (slot == nullptr) return;
  const std::lock_guard lock(g_pending_claims);
  slot->in_use.store(false, std::memory_order_release);
}

/// While alive, SIGINT, SIGTERM, SIGHUP and SIGQUIT wait in this thread (a process-directed one
/// may still go to another thread, as it may at any time).
class DeferredEndingSignals {
 public:
  DeferredEndingSignals() {
    sigset_t ending;
    ::sigemptyset(&ending);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) ::sigaddset(&ending, signal);
    ::pthread_sigmask(SIG_BLOCK, &ending, &previous_);
  }
  DeferredEndingSignals(const DeferredEndingSignals&) = delete;
  DeferredEndingSignals& operator=(const DeferredEndingSignals&) = delete;
  ~DeferredEndingSignals() { ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }

 private:
  sigset_t previous_{};
};

/// Takes the flock on the temporary file `fd` was just created as, which marks it as being
/// written until `fd` is closed. False (and `fd` closed) when another process's
/// RemoveAbandonedTemporaries took it first, between its creation and now, and removes it.
bool HoldWhileWriting(int fd, const std::string& path) {
  struct stat opened {};
  struct stat named {};
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &opened) == 0 &&
      ::stat(path.c_str(), &named) == 0 && opened.st_ino == named.st_ino &&
      opened.st_dev == named.st_dev) {
    return true;
  }
  ::close(fd);
  return false;
}

/// Whether `name` is `prefix` and six letters or digits, as TemporaryBeside names its files.
bool IsTemporaryName(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + 6 || name.compare(0, prefix.size(), prefix) != 0) {
    return false;
  }
  return std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; });
}

/// Removes the temporary files beside `target` that no process is writing: left by one that
/// was killed (SIGKILL, a power cut) before it could remove them. A file being written holds a
/// flock (HoldWhileWriting), so taking it here means its writer is gone.
void RemoveAbandonedTemporaries(const std::string& target) {
  const std::filesystem::path target_path(target);
  const std::string prefix = target_path.filename().string() + ".tmp-";
  const std::filesystem::path directory =
      target_path.has_parent_path() ? target_path.parent_path() : std::filesystem::path(".");
  std::error_code error;
  for (std::filesystem::directory_iterator it(directory, error), end; !error && it != end;
       it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (!IsTemporaryName(name, prefix)) continue;
    const std::string path = (directory / name).string();
    // Not waiting on what is not a plain file: opening a FIFO of that name blocked for good,
    // with the ending signals held back (DeferredEndingSignals).
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0) continue;
    struct stat status {};
    if (::fstat(fd, &status) != 0 || !S_ISREG(status.st_mode)) {
      ::close(fd);
      continue;
    }
    // Unlinked while the flock is held, so that a writer that creates the file just now and
    // takes the flock after this sees it gone (HoldWhileWriting) instead of writing into it.
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      for (const char* suffix : kSideSuffixes) ::unlink((path + suffix).c_str());
    }
    ::close(fd);
  }
}

/// A fresh empty file beside `target`, removed (with any SQLite side files) unless kept, and
/// removed by RemoveSnapshotTemporariesOnSignal while it exists. It holds a flock until then, and
/// makes way for it by removing the temporary files of `target` whose writers are gone.
class TemporaryBeside {
 public:
  explicit TemporaryBeside(const std::string& target) {
    // A signal between creating the file and registering it would leave it behind: the signals
    // that end a process wait until it is registered.
    const DeferredEndingSignals deferred;
    static constexpr char kLetters[] =
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    std::random_device random;
    for (int attempt = 0; attempt < 100; ++attempt) {
      std::string name = target + ".tmp-";
      for (int i = 0; i < 6; ++i) name += kLetters[random() % (sizeof kLetters - 1)];
      // Created as SQLite creates a database, 0644 less the umask (mkstemp's 0600 kept a
      // --read-only replica running as another user from serving the snapshot), and exclusively.
      const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd < 0 && errno == EEXIST) continue;
      if (fd < 0) {
        throw std::runtime_error(SystemError("cannot create a temporary file beside " + target));
      }
      if (!HoldWhileWriting(fd, name)) continue;
      lock_fd_ = fd;
      path_ = std::move(name);
      pending_ = Register(path_);
      RemoveAbandonedTemporaries(target);
      return;
    }
    throw std::runtime_error("cannot create a temporary file beside " + target +
                             ": 100 names were taken");
  }
  TemporaryBeside(const TemporaryBeside&) = delete;
  TemporaryBeside& operator=(const TemporaryBeside&) = delete;
  ~TemporaryBeside() {
    for (const char* suffix : {"-journal", "-wal", "-shm"}) ::unlink((path_ + suffix).c_str());
    if (!kept_) ::unlink(path_.c_str());
    Unregister(pending_);
    ::close(lock_fd_);
  }
  const std::string& path() const { return path_; }
  /// Renamed into place: nothing to remove any more.
  void keep() {
    kept_ = true;
    Unregister(pending_);
    pending_ = nullptr;
  }

 private:
  std::string path_;
  bool kept_ = false;
  PendingTemporary* pending_ = nullptr;
  int lock_fd_ = -1;  ///< holds the flock that tells RemoveAbandonedTemporaries it is in use
};

std::string Directory(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? "." : parent.string();
}

/// Whether the SQLite file at `path` says it keeps a write-ahead log (file format bytes 18 and 19
/// are 2): every database `pintag serve` writes, never a snapshot.
bool InWalMode(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return false;
  std::array<unsigned char, 20> header{};
  const bool read = std::fread(header.data(), 1, header.size(), file) == header.size();
  std::fclose(file);
  static constexpr char kMagic[] = "SQLite format 3";  // and its NUL
  return read && std::memcmp(header.data(), kMagic, sizeof kMagic) == 0 && header[18] == 2 &&
         header[19] == 2;
}

/// What SQLite's quick_check finds wrong with the database open on `connection`, or empty when
/// it finds nothing: the first two findings and how many more (a damaged page alone can list a
/// hundred, one per cell, and the whole list once filled a terminal).
std::string QuickCheckFindings(Connection& connection,
                               const std::string& pragma = "PRAGMA quick_check") {
  Statement check = connection.prepare(pragma);
  std::vector<std::string> findings;
  while (check.step()) {
    const std::string row = check.getText(0);
    std::size_t start = 0;
    while (start <= row.size()) {
      const std::size_t end = std::min(row.find('\n', start), row.size());
      const std::string line = row.substr(start, end - start);
      // SQLite heads the findings of each attached database with its name.
      if (!line.empty() && !line.starts_with("*** in database")) findings.push_back(line);
      start = end + 1;
    }
  }
  if (findings.size() == 1 && findings.front() == "ok") return {};
  if (findings.empty()) return "quick_check gave no answer";
  constexpr std::size_t kShown = 2;
  constexpr std::size_t kQuickCheckLimit = 100;  // SQLite stops counting there
  std::string text = findings.front();
  for (std::size_t i = 1; i < std::min(findings.size(), kShown); ++i) {
    text += "; ";
    text += findings[i];
  }
  if (findings.size() > kShown) {
    text += " (and ";
    text += findings.size() >= kQuickCheckLimit ? "at least " : "";
    text += std::to_string(findings.size() - kShown) + " more)";
  }
  return text;
}

/// The table a snapshot holds empty: each server keeps its own scan log.
constexpr std::string_view kScanLogTable = "scan_log";

/// `name` as an SQL identifier.
std::string QuotedIdentifier(std::string_view name) {
  std::string quoted = "\"";
  for (const char c : name) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

/// Fills the empty database open on `copy` with the schema of the database at `source_path` and
/// the rows of each of its tables but the scan log, all read in one transaction: one instant's
/// state, while writers go on. The rows go in before the indexes and triggers are made, so no
/// trigger fires on the copy (each would move the registry version). Returns what SQLite's
/// quick_check finds wrong with the source's copied tables and their indexes, or empty (nothing
/// is copied then). Throws SqliteError.
///
/// The backup API copied every page, the scan log's too, which was then deleted and the copy
/// vacuumed: a primary's snapshot took time and room in proportion to its scan log (6.1 s at a
/// million scans against 0.4 s, measured 2026-12-08), and it grows by every scan.
std::string CopyRegistryInto(Connection& copy, const std::string& source_path) {
  // The copy's own journal mode (`main.`, so that no attached database is ever in question).
  copy.execute("PRAGMA main.journal_mode=DELETE; PRAGMA foreign_keys=OFF");
  // Closing, this connection may be the last on the source; its log stays the source's to write.
  copy.leaveWriteAheadLogsOnClose();
  copy.prepare("ATTACH DATABASE ?1 AS source").bind(1, source_path).run();
  copy.execute("BEGIN");
  struct SchemaObject {
    std::string type, name, sql;
  };
  std::vector<SchemaObject> objects;
  {
    Statement schema = copy.prepare(
        "SELECT type, name, sql FROM source.sqlite_master WHERE sql IS NOT NULL AND name NOT "
        "LIKE 'sqlite\\_%' ESCAPE '\\' ORDER BY rowid");
    while (schema.step())
      objects.push_back({schema.getText(0), schema.getText(1), schema.getText(2)});
  }
  for (const SchemaObject& object : objects) {
    if (object.type != "table" || object.name == kScanLogTable) continue;
    std::string findings = QuickCheckFindings(
        copy, "PRAGMA source.quick_check(" + QuotedIdentifier(object.name) + ")");
    if (!findings.empty()) {
      copy.execute("ROLLBACK");
      return findings;
    }
  }
  for (const SchemaObject& object : objects) {
    if (object.type == "table") copy.execute(object.sql);
  }
  for (const SchemaObject& object : objects) {
    if (object.type != "table" || object.name == kScanLogTable) continue;
    const std::string table = QuotedIdentifier(object.name);
    std::string insert = "INSERT INTO main.";
    insert += table;
    insert += " SELECT * FROM source.";
    insert += table;
    copy.execute(insert);
  }
  if (copy.queryInt64("SELECT count(*) FROM source.sqlite_master WHERE name = 'sqlite_sequence'") >
      0) {
    // The rows copied set each AUTOINCREMENT table's sequence to its largest id; the source's
    // may be larger (ids deleted), and a second row per table would not be read.
    copy.execute("DELETE FROM main.sqlite_sequence");
    copy.prepare(
            "INSERT INTO main.sqlite_sequence SELECT * FROM source.sqlite_sequence WHERE "
            "name != ?1")
        .bind(1, kScanLogTable)
        .run();
  }
  for (const SchemaObject& object : objects) {
    if (object.type != "table") copy.execute(object.sql);
  }
  copy.execute("PRAGMA main.user_version = " +
               std::to_string(copy.queryInt64("PRAGMA source.user_version")));
  copy.execute("COMMIT");
  copy.execute("DETACH DATABASE source");
  return {};
}

/// VerifySnapshot's checks but the schema version's: a regular file, not in WAL mode (opened
/// read-only it would miss what its log holds), of a PinTag schema version, whole (quick_check).
/// Its schema version, with `connection` open on it; throws SqliteError when SQLite cannot open it.
Result<int> OpenWholeRegistry(const std::string& path, std::optional<Connection>& connection) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    // A directory or a device there is not "does not exist".
    return Error{ErrorCode::kNotFound,
                 "snapshot " + path +
                     (std::filesystem::exists(path, error) ? " is not a file" : " does not exist")};
  }
  if (InWalMode(path)) {
    return Error{ErrorCode::kConflict,
                 "snapshot " + path +
                     " is in WAL mode, as a live registry database is; a replica serves a "
                     "snapshot (`pintag snapshot --db LIVE --out FILE` writes one)"};
  }
  connection.emplace(path, ConnectionOptions{.create = false, .read_only = true});
  const int version = SchemaVersion(*connection);
  if (version == 0) {
    return Error{ErrorCode::kConflict, "snapshot " + path +
                                           " holds no PinTag registry (it is empty, or another "
                                           "application's SQLite database)"};
  }
  if (const std::string findings = QuickCheckFindings(*connection); !findings.empty()) {
    return Error{ErrorCode::kStorage, "snapshot " + path + " is damaged: " + findings};
  }
  return version;
}

/// Whether `path` holds keys a replica serves: a whole PinTag file with its key table, of any
/// schema version. A replica just upgraded to a newer pintag still holds its last snapshot of the
/// older schema, which VerifySnapshot refuses; the next snapshot must keep its keys all the same
/// (it was installed without the comparison before 2026-12-07).
bool HoldsServedKeys(const std::string& path) {
  try {
    std::optional<Connection> connection;
    if (!OpenWholeRegistry(path, connection)) return false;
    return connection->queryInt64(
               "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND "
               "name = 'tag_keys'") == 1;
  } catch (const std::exception&) {
    return false;  // not SQLite: replaced, as a damaged file is
  }
}

}  // namespace

std::string LiveDatabaseAt(const std::string& path) {
  // Renaming a copy over a live database swaps the file under its open connections, whose
  // write-ahead log then belongs to another file: the next checkpoint corrupts it.
  std::error_code error;
  if (std::filesystem::exists(path + "-wal", error)) {
    return path + " is a live database (" + path + "-wal is beside it)";
  }
  if (InWalMode(path)) {
    return path +
           " is a registry database (in WAL mode, as `pintag serve` keeps its --db), not "
           "a snapshot";
  }
  return {};
}

std::string DatabaseOwningFile(const std::string& path, const std::string& source) {
  std::error_code error;
  for (const std::string_view suffix : {"-wal", "-shm", "-journal"}) {
    // The source's own files, however they are named (a link, a relative path), and by name
    // alone while they are not there yet (a server's first start).
    if (!source.empty() &&
        (path == source + std::string(suffix) ||
         std::filesystem::equivalent(path, source + std::string(suffix), error))) {
      return source;
    }
    // Any other database's: SQLite names them after it. Only a file that is an SQLite database
    // counts (its header), so `notes-wal` beside a text file `notes` is a path like any other.
    if (path.size() > suffix.size() && path.ends_with(suffix)) {
      std::string base = path.substr(0, path.size() - suffix.size());
      std::array<char, 16> header{};
      std::ifstream file(base, std::ios::binary);
      if (file.read(header.data(), header.size()) &&
          std::string_view(header.data(), header.size()) ==
              std::string_view("SQLite format 3\0", 16)) {
        return base;
      }
    }
  }
  return {};
}

Result<std::int64_t> RegistryVersion(Connection& connection) {
  return detail::Guard([&]() -> Result<std::int64_t> {
    Statement s = connection.prepare("SELECT version FROM registry_version WHERE id = 1");
    if (!s.step()) return Error{ErrorCode::kStorage, "the registry version row is missing"};
    return s.getInt64(0);
  });
}

Result<SnapshotInfo> WriteSnapshot(Connection& source, const std::string& out_path) {
  const FileToReplace target = FileReplacedBy(out_path);
  if (!target.problem.empty()) return Error{ErrorCode::kStorage, target.problem};
  const std::string& written_path = target.path;
  std::error_code error;
  if (std::filesystem::equivalent(written_path, source.path(), error)) {
    return Error{ErrorCode::kConflict, "the snapshot " + written_path +
                                           " would replace the database it is taken from; write "
                                           "it to another path"};
  }
  if (const std::string live = LiveDatabaseAt(written_path); !live.empty()) {
    return Error{ErrorCode::kConflict,
                 live + ": a snapshot must not replace it; write it to another path"};
  }
  if (const std::string owner = DatabaseOwningFile(written_path, source.path()); !owner.empty()) {
    return Error{ErrorCode::kConflict,
                 "the snapshot " + written_path + " would replace a file of the database " + owner +
                     " (its write-ahead log, shared memory or journal), corrupting it; write it "
                     "to another path"};
  }
  try {
    TemporaryBeside temporary(written_path);
    SnapshotInfo info;
    info.path = out_path;
    {
      // A rollback journal keeps the snapshot one file, which read-only servers open without
      // needing to create -wal and -shm files beside it.
      Connection copy(temporary.path(), {.create = false, .wal = false});
      // The copy reads the file at the source's path, on a connection of its own: another file
      // put there (a restore copied in while a primary serves) would be read with the source's
      // write-ahead log, and the snapshot would be of neither. Looked at before and after.
      const auto moved = [&] {
        return Error{ErrorCode::kConflict,
                     source.path() +
                         " is no longer the database open here (moved, removed or replaced); no "
                         "snapshot is taken of another file (restart the server to use it)"};
      };
      if (!source.fileIsAtPath()) return moved();
      // A damaged source would give a snapshot that replicas refuse, or one that lacks rows,
      // and a restore from it would bring the damage back.
      const std::string findings = CopyRegistryInto(copy, source.path());
      if (!source.fileIsAtPath()) return moved();
      if (!findings.empty()) {
        return Error{ErrorCode::kStorage,
                     "the database " + source.path() +
                         " is damaged, so no snapshot of it was written (SQLite's quick_check "
                         "found: " +
                         findings +
                         "); restore it from the newest snapshot a replica holds "
                         "(docs/SCALING.md, Snapshots)"};
      }
      Result<std::int64_t> version = RegistryVersion(copy);
      if (!version) return version.error();
      info.registry_version = *version;
    }
    Sync(temporary.path(), false);
    info.bytes = std::filesystem::file_size(temporary.path());
    if (::rename(temporary.path().c_str(), written_path.c_str()) != 0) {
      const std::string renaming = SystemError("cannot rename the snapshot to " + written_path);
      // A directory made there since the check above fails the rename: said in the check's
      // words, so that a publisher's error reads the same at every try (replicas log it once).
      const std::string problem = FileReplacedBy(out_path).problem;
      return Error{ErrorCode::kStorage, problem.empty() ? renaming : problem};
    }
    temporary.keep();
    Sync(Directory(written_path), true);
    return info;
  } catch (const SqliteError& e) {
    return detail::ToError(e);
  } catch (const std::exception& e) {
    return Error{ErrorCode::kStorage, e.what()};
  }
}

Result<SnapshotInfo> InstallSnapshot(std::string_view bytes, const std::string& path) {
  if (const std::string live = LiveDatabaseAt(path); !live.empty()) {
    return Error{ErrorCode::kConflict,
                 live + ": a replica must not replace it; give the replica a --db of its own"};
  }
  if (const std::string owner = DatabaseOwningFile(path); !owner.empty()) {
    return Error{ErrorCode::kConflict, path + " is a file of the database " + owner +
                                           " (its write-ahead log, shared memory or journal): "
                                           "give the replica a --db of its own"};
  }
  try {
    TemporaryBeside temporary(path);
    {
      const int fd = ::open(temporary.path().c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
      // Errors name `path`, not the temporary file's random name: a follower logs an error that
      // repeats once (a full disk failed every poll under another name, each logged).
      const std::string received = "the snapshot received for " + path + " (a file beside it)";
      if (fd < 0) throw std::runtime_error(SystemError("cannot open " + received));
      std::size_t written = 0;
      while (written < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
          const std::string error = SystemError("cannot write " + received);
          ::close(fd);
          throw std::runtime_error(error);
        }
        written += static_cast<std::size_t>(n);
      }
      const bool synced = ::fsync(fd) == 0;
      ::close(fd);
      if (!synced) throw std::runtime_error(SystemError("cannot fsync " + received));
    }
    const auto named_by_target = [&](std::string message) {
      const std::string named = path + " (as received)";
      for (std::size_t at = 0; (at = message.find(temporary.path(), at)) != std::string::npos;
           at += named.size()) {
        message.replace(at, temporary.path().size(), named);
      }
      return message;
    };
    Result<SnapshotInfo> verified = VerifySnapshot(temporary.path());
    if (!verified) return Error{verified.error().code, named_by_target(verified.error().message)};
    // A registry served now (a replica's last snapshot) is replaced only by one that keeps its
    // keys. A file there that is not a snapshot is replaced, as a damaged one must be.
    if (HoldsServedKeys(path)) {
      std::string lost;
      try {
        lost = KeysNotKept(path, temporary.path());
      } catch (const std::exception& e) {
        return Error{ErrorCode::kStorage, "cannot compare the keys: " + named_by_target(e.what())};
      }
      if (!lost.empty()) {
        return Error{ErrorCode::kConflict,
                     "the snapshot received does not keep the keys of " + path + ": " + lost +
                         ". Labels printed with them would be misrouted, so " + path +
                         " stays as it was. A primary restored from an older backup does this; "
                         "restore it from this file instead (docs/SCALING.md)"};
      }
    }
    if (::rename(temporary.path().c_str(), path.c_str()) != 0) {
      return Error{ErrorCode::kStorage, SystemError("cannot rename the snapshot to " + path)};
    }
    temporary.keep();
    Sync(Directory(path), true);
    SnapshotInfo info = *verified;
    info.path = path;
    return info;
  } catch (const std::exception& e) {
    return Error{ErrorCode::kStorage, e.what()};
  }
}

std::optional<Error> KeysNotKeptBy(const std::string& received, const std::string& current) {
  try {
    const std::string lost = KeysNotKept(current, received);
    if (lost.empty()) return std::nullopt;
    return Error{ErrorCode::kConflict, "it does not keep the keys of the registry served now: " +
                                           lost + ". Labels printed with them would be misrouted"};
  } catch (const std::exception& e) {
    return Error{ErrorCode::kStorage, std::string("cannot compare the keys: ") + e.what()};
  }
}

void RemoveSnapshotTemporariesOnSignal() noexcept {
  for (PendingTemporary& slot : g_pending) {
    if (!slot.in_use.load(std::memory_order_acquire)) continue;
    for (const auto& file : slot.files) ::unlink(file.data());
  }
}

Result<SnapshotInfo> VerifySnapshot(const std::string& path) {
  try {
    std::optional<Connection> connection;
    const Result<int> version = OpenWholeRegistry(path, connection);
    if (!version) return version.error();
    if (*version != kSchemaVersion) {
      return Error{ErrorCode::kConflict, "snapshot " + path + " has schema version " +
                                             std::to_string(*version) + "; this pintag reads " +
                                             std::to_string(kSchemaVersion)};
    }
    Result<std::int64_t> registry_version = RegistryVersion(*connection);
    if (!registry_version) return registry_version.error();
    return SnapshotInfo{path, *registry_version, std::filesystem::file_size(path)};
  } catch (const SqliteError& e) {
    return Error{ErrorCode::kStorage, "snapshot " + path + ": " + e.what()};
  } catch (const std::exception& e) {
    return Error{ErrorCode::kStorage, e.what()};
  }
}

}  // namespace pintag::db
