// crash-safe run files. HDF5 has no journal: a job killed while it writes can leave the file's metadata
// half-updated, older generations included. So the run file is created under a temporary name and
// renamed into place, and at a checkpoint it is flushed and copied to RUN.h5.ckpt (copy, fsync, read
// back, atomic rename). --resume continues from the checkpoint (the run file only when there is none).
//
// A stage commits its state every output.checkpoint_every rounds; the copy to the checkpoint, which costs
// the run file's size twice (copy and read-back) while every rank waits, is made at a commit only when
// output.checkpoint_interval_s of wall time have passed since the last one (rank 0's clock decides for
// all), at the end of every stage, and when a stop was asked for. A commit's rows and state are written to
// the run file just before the copy (DeferredWrites below), since nothing between copies is resumed from. Rounds committed
// after the last copy are redone on --resume with the same results, so where the copies fall never
// changes the run file.
#pragma once

#include <mpi.h>

#include <chrono>
#include <functional>
#include <string>

#include "io/h5.hpp"

namespace divcoll::mpi {

std::string checkpoint_path(const std::string& run_path);

// A stage's driver keeps the rows and state of its rounds in memory until a commit that copies, since only
// a copy is ever resumed from (mpi/driver.cpp): while a DeferredWrites is alive, a Checkpointer that copies
// calls its `flush` first (on every rank), and copies at a commit when `urgent` says so on rank 0 (what it
// holds has grown large). One at a time; every rank holds one at the same points.
class DeferredWrites {
 public:
  DeferredWrites(std::function<void()> flush, std::function<bool()> urgent);
  ~DeferredWrites();
  DeferredWrites(const DeferredWrites&) = delete;
  DeferredWrites& operator=(const DeferredWrites&) = delete;

 private:
  friend class Checkpointer;
  std::function<void()> flush_;
  std::function<bool()> urgent_;
};

// every rank calls it: flush, then rank 0 copies the file to its checkpoint
void checkpoint(MPI_Comm comm, io::h5::File& file, const std::string& run_path);

// when to copy: every rank holds one and calls it at the same points
class Checkpointer {
 public:
  // interval_s: least wall time between copies (0: a copy at every commit)
  Checkpointer(MPI_Comm comm, io::h5::File& file, std::string run_path, double interval_s);
  // at a commit: copies if the interval has passed on rank 0 (or rank 0's DeferredWrites is urgent) or a stop
  // was asked for on any rank, a DeferredWrites' flush first; then
  // stops (StopRequested on every rank, right after the copy) if one was asked for
  void commit() { at(false); }
  // copies now (a stage's end, a new run file; a DeferredWrites' flush first), then stops if asked
  void force() { at(true); }
  int copies() const { return copies_; }
  double copy_s() const { return copy_s_; }  // wall time spent in copies (every rank waits for them)

 private:
  void at(bool force);
  MPI_Comm comm_;
  io::h5::File& file_;
  std::string path_;
  double interval_s_;
  std::chrono::steady_clock::time_point last_{};
  int copies_ = 0;
  double copy_s_ = 0;
};

// rank-local: a divcoll run file whose every dataset reads back; `why` says what is wrong otherwise
bool valid_run_file(const std::string& path, std::string* why);

// rank 0 decides what to resume from: the checkpoint when there is one that reads back (it replaces the run
// file), else the run file as it is (a finished run's, whose checkpoint is removed); returns
// (on every rank) true if there is a run to continue, false if the run must start from nothing.
// Throws InputError if `run_path` exists, is damaged and has no checkpoint.
bool prepare_resume(MPI_Comm comm, const std::string& run_path);

// removes the checkpoint (rank 0) once the run is complete
void remove_checkpoint(MPI_Comm comm, const std::string& run_path);

}  // namespace divcoll::mpi
