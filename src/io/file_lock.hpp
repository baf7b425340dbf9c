// one writer per run file: `RUN.h5.lock` beside the run file, held for the whole run by the
// job that writes RUN.h5 and its checkpoint RUN.h5.ckpt.
//
// The lock is a POSIX record lock (fcntl) on the lock file, so the kernel (or the shared file system's
// lock manager) drops it the moment its holder dies, however it dies: a lock file left by a killed job is
// recognised as stale because nobody holds its lock. Byte 0 is the job's (rank 0); byte 1 + r is held by
// rank r, so the ranks of a job whose launcher was killed keep the file locked until the last of them
// has ended. The file's text names the holder: host, pid, start time, ranks.
//
// Policy where the file system has no record locks (fcntl fails with ENOLCK or EOPNOTSUPP): the text
// decides. A holder on this host whose pid is gone is stale and is replaced; one whose pid runs is
// refused; a holder on another host cannot be checked from here and is refused, with the advice to
// delete RUN.h5.lock once that job is known to have ended. A lock is never broken automatically.
#pragma once

#include <string>

namespace divcoll::io {

class WriterLock {
 public:
  WriterLock() = default;
  ~WriterLock() { release(); }
  WriterLock(WriterLock&& o) noexcept;
  WriterLock& operator=(WriterLock&& o) noexcept;
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;

  // the job's lock (rank 0): refuses (InputError naming the holder) if another live process holds it
  // or still holds a rank's byte. `note` gets a line to print when a stale lock was taken over.
  static WriterLock acquire(const std::string& target, int ranks, std::string* note = nullptr);
  // a rank's share (ranks != 0, after rank 0 has acquired): byte 1 + rank
  static WriterLock join(const std::string& target, int rank);

  // drops the lock; the job's lock (rank 0) also removes the lock file
  void release();
  bool held() const { return fd_ >= 0; }

  static std::string lock_path(const std::string& target) { return target + ".lock"; }
  // whether a live process holds the job's lock of `target` (byte 0 of its lock file), read only; `holder`, if
  // given, gets the lock file's text (who took it)
  static bool held_by_someone(const std::string& target, std::string* holder = nullptr);

 private:
  int fd_ = -1;
  bool owner_ = false;
  std::string path_;
};

}  // namespace divcoll::io
