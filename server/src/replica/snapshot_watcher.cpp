#include "replica/snapshot_watcher.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "pintag/server/log.hpp"

namespace pintag::replica {

namespace {

constexpr std::string_view kLockSuffix = ".lock";
constexpr std::string_view kNewLockSuffix = ".lock.new";  // before it is renamed into place

std::string RandomTag() {
  std::random_device device;
  std::ostringstream tag;
  tag << std::hex << std::setfill('0') << std::setw(8) << device() << std::setw(8) << device();
  return tag.str();
}

// Locks `path` exclusively without waiting; the descriptor holding the lock, or −1 when the file
// is missing or someone holds it.
int TryLock(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);  // enough for flock
  if (fd < 0) return -1;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

/// `message` with every `link` (the server's own hard link, "F.serving-…") said as `name`: the
/// operator knows the file by its path.
std::string NamedAs(std::string message, const std::string& link, const std::string& name) {
  for (std::size_t at = message.find(link); at != std::string::npos;
       at = message.find(link, at + name.size())) {
    message.replace(at, link.size(), name);
  }
  return message;
}

}  // namespace

SnapshotWatcher::SnapshotWatcher(std::string path, OnLoaded on_loaded)
    : path_(std::move(path)), on_loaded_(std::move(on_loaded)) {
  takeTag();
  try {
    removeEndedRuns();
    const std::lock_guard lock(mutex_);
    std::optional<FileIdentity> linked;
    std::string link;
    const db::Result<db::SnapshotInfo> loaded = linkAndVerify(&linked, &link);
    seen_ = linked;
    if (!loaded) {
      if (!link.empty()) ::unlink(link.c_str());
      throw std::runtime_error("cannot serve " + path_ + ": " + loaded.error().message);
    }
    loaded_ = *loaded;
  } catch (...) {
    releaseTag();  // no destructor runs for a constructor that throws
    throw;
  }
}

std::string SnapshotWatcher::servingName(const std::string& tag, std::string_view suffix) const {
  return path_ + ".serving-" + tag + std::string(suffix);
}

SnapshotWatcher::~SnapshotWatcher() {
  thread_.stop();
  // The server has stopped serving: nothing leases a connection on the link any more, and a
  // connection still open keeps reading the unlinked file.
  if (loaded_) ::unlink(loaded_->path.c_str());
  releaseTag();
}

void SnapshotWatcher::releaseTag() {
  ::unlink(servingName(tag_, kLockSuffix).c_str());
  if (lock_fd_ >= 0) ::close(lock_fd_);
  lock_fd_ = -1;
}

void SnapshotWatcher::takeTag() {
  // The lock file is locked under a temporary name and then renamed, so a lock file another
  // replica sees under its own name is always held by its maker while that lives.
  std::string error;
  for (int attempt = 0; attempt < 8; ++attempt) {
    const std::string tag = RandomTag();
    const std::string fresh = servingName(tag, kNewLockSuffix);
    const int fd = ::open(fresh.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
      error = "cannot create " + fresh + ": " + std::strerror(errno);
      if (errno == EEXIST) continue;
      break;
    }
    // Another replica starting at this moment may take the fresh file for a crashed run's and
    // remove it: then the lock or the rename fails, and another tag is tried.
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0 &&
        ::rename(fresh.c_str(), servingName(tag, kLockSuffix).c_str()) == 0) {
      tag_ = tag;
      lock_fd_ = fd;
      return;
    }
    error = "cannot lock " + fresh + ": " + std::strerror(errno);
    ::close(fd);
    ::unlink(fresh.c_str());
  }
  throw std::runtime_error(error);
}

void SnapshotWatcher::removeEndedRuns() const {
  const std::filesystem::path target(path_);
  const std::string prefix = target.filename().string() + ".serving-";
  const std::filesystem::path directory =
      target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  // Each tag's files: links `<tag>-N`, its lock file; names of an older scheme (`serving-N`)
  // fall under the tag "" and have no lock.
  std::map<std::string, std::vector<std::filesystem::path>> files_of_tag;
  std::error_code ignored;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ignored)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());
    const std::size_t end = rest.find_first_of("-.");
    const bool tagged = end != std::string::npos && rest.find('-') != 0;
    files_of_tag[tagged ? rest.substr(0, end) : std::string()].push_back(entry.path());
  }
  for (auto& [tag, files] : files_of_tag) {
    if (tag == tag_) continue;
    std::vector<int> held;  // the ended run's locks, held while its files go
    bool running = false;
    for (const std::string_view suffix : {kLockSuffix, kNewLockSuffix}) {
      const std::string lock = servingName(tag, suffix);
      if (const int fd = TryLock(lock); fd >= 0) {
        held.push_back(fd);
      } else if (!tag.empty() && std::filesystem::exists(lock, ignored)) {
        running = true;
      }
    }
    if (!running) {
      // Links first, lock files last: a lock file still marks its links as another run's.
      std::stable_partition(files.begin(), files.end(), [](const std::filesystem::path& file) {
        const std::string name = file.filename().string();
        return !name.ends_with(kLockSuffix) && !name.ends_with(kNewLockSuffix);
      });
      for (const auto& file : files) std::filesystem::remove(file, ignored);
    }
    for (const int fd : held) ::close(fd);
  }
}

db::Result<db::SnapshotInfo> SnapshotWatcher::linkAndVerify(std::optional<FileIdentity>* linked,
                                                            std::string* link_made) {
  std::string number = "-";
  number += std::to_string(++links_made_);
  const std::string link = servingName(tag_, number);
  ::unlink(link.c_str());
  if (::link(path_.c_str(), link.c_str()) != 0) {
    *linked = IdentifyFile(path_);
    return db::Error{db::ErrorCode::kStorage,
                     "cannot link " + path_ + " to " + link + ": " + std::strerror(errno)};
  }
  *link_made = link;
  // What was linked, not what was at the path a moment before: a file renamed into place in
  // between is looked at once, now, and not taken for a change again.
  *linked = IdentifyFile(link);
  db::Result<db::SnapshotInfo> verified = db::VerifySnapshot(link);
  if (!verified) {
    return db::Error{verified.error().code, NamedAs(verified.error().message, link, path_)};
  }
  return verified;
}

bool SnapshotWatcher::check() {
  const std::lock_guard lock(mutex_);
  const std::optional<FileIdentity> now = IdentifyFile(path_);
  if (!now || now == seen_) return false;  // gone (keep serving) or unchanged
  std::optional<FileIdentity> linked;
  std::string link;
  const db::Result<db::SnapshotInfo> verified = linkAndVerify(&linked, &link);
  seen_ = linked ? linked : now;
  // A --follow replica's install refuses a registry that gives a served key to another pincode
  // (a primary restored from an older backup); a file renamed into place is held to the same.
  std::optional<db::Error> refusal;
  const std::optional<FileIdentity> served_file = IdentifyFile(loaded_->path);
  const bool written_in_place = linked && served_file && linked->device == served_file->device &&
                                linked->inode == served_file->inode;
  if (!verified && written_in_place) {
    // Nothing to refuse or put back: the served registry is this file, changed under it.
    if (!link.empty()) ::unlink(link.c_str());
    served_damaged_ = true;
    {
      const std::lock_guard damage_lock(damage_mutex_);
      damage_ = path_ + " was written over in place: " + verified.error().message;
    }
    server::LogEvent(path_ +
                         " was written over in place, and the registry served (the same file) "
                         "changed with it: " +
                         verified.error().message + ". Not ready until a good snapshot is at " +
                         path_ + " (a --follow replica fetches one; else rename one into place)",
                     /*warning=*/true);
    return false;
  }
  if (!verified) {
    refusal = verified.error();
  } else if (served_damaged_) {
    // The served file shares FILE's inode, so a copy written over FILE in place (cp, scp, a
    // truncation) changed it: there are no keys left to compare, and refusing every later file
    // for that ("cannot compare the keys") left the replica unready for good. db::InstallSnapshot
    // replaces a file that is not a snapshot likewise.
    server::LogEvent("the registry served was written over in place; taking the new file at " +
                         path_ + " without comparing keys",
                     /*warning=*/true);
  } else {
    refusal = db::KeysNotKeptBy(verified->path, loaded_->path);
    if (refusal) {
      refusal->message = NamedAs(NamedAs(refusal->message, verified->path, path_ + " (new)"),
                                 loaded_->path, "the registry served");
    }
  }
  if (refusal) {
    const std::string kept = putBackServed(link);
    server::LogEvent("ignoring the new file at " + path_ + ": " + refusal->message +
                         "; still serving registry version " +
                         std::to_string(loaded_->registry_version) + kept,
                     /*warning=*/true);
    return false;
  }
  const std::string previous = loaded_->path;
  loaded_ = *verified;
  served_damaged_ = false;
  {
    const std::lock_guard damage_lock(damage_mutex_);
    damage_.reset();
  }
  on_loaded_(*loaded_);
  ::unlink(previous.c_str());  // connections still reading it keep it until they close
  server::LogEvent("loaded snapshot " + path_ + " (registry version " +
                   std::to_string(loaded_->registry_version) + ")");
  return true;
}

std::string SnapshotWatcher::putBackServed(const std::string& refused_link) {
  // A refusal must outlast this process: left at the path, the refused file was served by the
  // next replica started on it, or by this one after a restart, with no check to refuse it.
  const std::string refused = path_ + ".refused";
  const std::string staged = servingName(tag_, "-staged");
  std::string kept;
  ::unlink(staged.c_str());
  if (!refused_link.empty() && ::link(refused_link.c_str(), staged.c_str()) == 0 &&
      ::rename(staged.c_str(), refused.c_str()) == 0) {
    kept = "; the refused file is kept as " + refused;
  }
  if (!refused_link.empty()) ::unlink(refused_link.c_str());
  ::unlink(staged.c_str());
  // The served registry put back at the path by one rename: a reader of the path sees one file
  // or the other, never none.
  if (::link(loaded_->path.c_str(), staged.c_str()) == 0 &&
      ::rename(staged.c_str(), path_.c_str()) == 0) {
    seen_ = IdentifyFile(path_);
    return kept + ", and " + path_ + " is that registry again";
  }
  const std::string error = std::strerror(errno);
  ::unlink(staged.c_str());
  return kept + "; " + path_ + " could not be put back to it (" + error +
         "): a replica started on it would serve the refused file";
}

void SnapshotWatcher::start(std::chrono::milliseconds interval) {
  thread_.start(interval, [this] { check(); });
}

db::SnapshotInfo SnapshotWatcher::loaded() const {
  const std::lock_guard lock(mutex_);
  return *loaded_;
}

std::optional<std::string> SnapshotWatcher::servedDamage() const {
  const std::lock_guard lock(damage_mutex_);
  return damage_;
}

std::optional<std::int64_t> SnapshotWatcher::servedVersion() const {
  const std::lock_guard lock(mutex_);
  if (served_damaged_) return std::nullopt;
  // The file removed (a cleanup, a mistaken rm): the registry served is still open through its
  // link, but a restart would find nothing there. Asked for whole, the follower puts it back.
  if (!IdentifyFile(path_)) return std::nullopt;
  return loaded_->registry_version;
}

bool AReplicaServes(const std::string& path) {
  const std::filesystem::path target(path);
  const std::string prefix = target.filename().string() + ".serving-";
  const std::filesystem::path directory =
      target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(prefix) || !name.ends_with(kLockSuffix)) continue;
    // flock, on the lock file: the database's own POSIX locks are not touched.
    const int fd = TryLock(entry.path().string());
    if (fd >= 0) {
      ::close(fd);  // an ended run's lock, nobody's now
    } else if (std::filesystem::exists(entry.path(), error)) {
      return true;
    }
  }
  return false;
}

}  // namespace pintag::replica
