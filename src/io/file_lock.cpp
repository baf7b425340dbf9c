#include "io/file_lock.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <sstream>
#include <utility>

#include "common/check.hpp"

namespace divcoll::io {
namespace {

std::string hostname() {
  char h[256] = {0};
  gethostname(h, sizeof h - 1);
  return h;
}

// the holder's line: "host pid start ranks"
struct Holder {
  std::string host, start;
  long pid = 0;
  int ranks = 0;
  bool parsed = false;
  std::string text() const {
    if (!parsed) return "an unknown holder (the lock file names none)";
    return "host " + host + ", pid " + std::to_string(pid) + ", started " + start + ", " + std::to_string(ranks) +
           " rank(s)";
  }
};

Holder read_holder(int fd) {
  std::string s(512, '\0');
  const ssize_t n = pread(fd, s.data(), s.size(), 0);
  s.resize(n > 0 ? static_cast<size_t>(n) : 0);
  Holder h;
  std::istringstream in(s);
  h.parsed = static_cast<bool>(in >> h.host >> h.pid >> h.start >> h.ranks);
  return h;
}

void write_holder(int fd, int ranks) {
  const std::time_t t = std::time(nullptr);
  char when[64];
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  const std::string line = hostname() + " " + std::to_string(getpid()) + " " + when + " " + std::to_string(ranks) + "\n";
  if (ftruncate(fd, 0) != 0 || pwrite(fd, line.data(), line.size(), 0) != static_cast<ssize_t>(line.size()))
    throw InputError(msg() << "cannot write the lock file: " << std::strerror(errno));
}

// a write lock on the bytes [start, start + len) (len 0: to the end)
struct flock write_lock(off_t start, off_t len) {
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = start;
  fl.l_len = len;
  return fl;
}

bool set_lock(int fd, off_t start, off_t len) {
  struct flock fl = write_lock(start, len);
  return fcntl(fd, F_SETLK, &fl) == 0;
}

// the pid of a process holding a lock on [start, start + len) (len 0: to the end), or 0 if none
long lock_holder(int fd, off_t start, off_t len) {
  struct flock fl = write_lock(start, len);
  if (fcntl(fd, F_GETLK, &fl) != 0 || fl.l_type == F_UNLCK) return 0;
  return fl.l_pid > 0 ? fl.l_pid : -1;
}

bool same_file(int fd, const std::string& path) {
  struct stat a {}, b {};
  return fstat(fd, &a) == 0 && stat(path.c_str(), &b) == 0 && a.st_ino == b.st_ino && a.st_dev == b.st_dev;
}

bool no_record_locks(int err) { return err == ENOLCK || err == EOPNOTSUPP || err == EINVAL; }

}  // namespace

WriterLock::WriterLock(WriterLock&& o) noexcept : fd_(o.fd_), owner_(o.owner_), path_(std::move(o.path_)) {
  o.fd_ = -1;
}

WriterLock& WriterLock::operator=(WriterLock&& o) noexcept {
  if (this != &o) {
    release();
    fd_ = o.fd_;
    owner_ = o.owner_;
    path_ = std::move(o.path_);
    o.fd_ = -1;
  }
  return *this;
}

bool WriterLock::held_by_someone(const std::string& target, std::string* holder) {
  const std::string lp = lock_path(target);
  const int fd = ::open(lp.c_str(), O_RDONLY);
  if (fd < 0) return false;
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = 0;
  fl.l_len = 1;
  const bool held = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
  char b[256] = {0};
  const ssize_t n = ::read(fd, b, sizeof b - 1);
  ::close(fd);
  if (holder) *holder = n > 0 ? std::string(b, static_cast<size_t>(n)) : std::string();
  if (holder && !holder->empty() && holder->back() == '\n') holder->pop_back();
  return held;
}

WriterLock WriterLock::acquire(const std::string& target, int ranks, std::string* note) {
  const std::string lp = lock_path(target);
  for (int attempt = 0; attempt < 8; ++attempt) {
    const int fd = ::open(lp.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    DIVCOLL_THROW_UNLESS(fd >= 0, "cannot make the lock file " << lp << ": " << std::strerror(errno));
    WriterLock l;
    l.fd_ = fd;
    l.path_ = lp;
    // bytes 0 (the job) and 1 (its rank 0) in one lock: closing any descriptor of a file drops all of a
    // process's record locks on it, so rank 0 never opens the lock file twice
    if (set_lock(fd, 0, 2)) {
      // the lock file may have been removed by a holder that was just ending: then lock the new one
      if (!same_file(fd, lp)) continue;
      const Holder old = read_holder(fd);
      const long orphan = lock_holder(fd, 2, 0);
      if (orphan != 0)
        throw InputError(msg() << target << " is still being written by rank(s) of an earlier job whose first rank "
                               << "has ended (a rank holds its lock, pid " << orphan << " on "
                               << (old.parsed ? old.host : std::string("its host")) << "; that job: " << old.text()
                               << "); wait a few seconds for them to end, or kill them, then retry. Nothing was "
                                  "written.");
      if (old.parsed && note)
        *note = "stale lock " + lp + " (" + old.text() + ", no longer running) taken over";
      write_holder(fd, ranks);
      l.owner_ = true;
      return l;
    }
    const int err = errno;
    if (err == EACCES || err == EAGAIN) {
      const Holder h = read_holder(fd);
      const long pid = lock_holder(fd, 0, 2);
      throw InputError(msg() << target << " is being written by another run (" << h.text()
                             << (pid > 0 && (!h.parsed || pid != h.pid) ? "; lock held by pid " + std::to_string(pid) : "")
                             << "): one run file has one writer. Wait for that run to end or stop it; this run "
                                "wrote nothing.");
    }
    DIVCOLL_THROW_UNLESS(no_record_locks(err), "cannot lock " << lp << ": " << std::strerror(err));
    // no record locks on this file system: the lock file's text decides (see the header)
    const Holder h = read_holder(fd);
    if (h.parsed) {
      const bool here = h.host == hostname();
      const bool alive = here && (::kill(static_cast<pid_t>(h.pid), 0) == 0 || errno == EPERM);
      if (!here || alive)
        throw InputError(msg() << target << " is being written by another run (" << h.text() << "; this file system "
                               << "has no record locks, so " << (here ? "that pid is running" : "a holder on another host cannot be checked")
                               << "). If that job has ended, delete " << lp << " and retry; this run wrote nothing.");
      if (note) *note = "stale lock " + lp + " (" + h.text() + ", pid gone) taken over";
    }
    write_holder(fd, ranks);
    l.owner_ = true;
    return l;
  }
  throw InputError(msg() << "cannot lock " << lp << ": it keeps being replaced by other runs");
}

WriterLock WriterLock::join(const std::string& target, int rank) {
  WriterLock l;
  l.path_ = lock_path(target);
  l.fd_ = ::open(l.path_.c_str(), O_RDWR | O_CLOEXEC);
  DIVCOLL_THROW_UNLESS(l.fd_ >= 0, "rank " << rank << " cannot open the lock file " << l.path_ << ": "
                                            << std::strerror(errno));
  if (!set_lock(l.fd_, 1 + rank, 1) && !no_record_locks(errno))
    throw InputError(msg() << "rank " << rank << " cannot lock " << l.path_ << ": " << std::strerror(errno));
  return l;
}

void WriterLock::release() {
  if (fd_ < 0) return;
  // removed while still locked, so that a run waiting for it never locks a file that is then removed
  if (owner_) ::unlink(path_.c_str());
  ::close(fd_);
  fd_ = -1;
}

}  // namespace divcoll::io
