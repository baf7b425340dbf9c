#include "mpi/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <utility>

#include "common/check.hpp"
#include "mpi/agree.hpp"
#include "mpi/scheduler.hpp"
#include "mpi/stop.hpp"
#include "mpi/wait.hpp"

namespace divcoll::mpi {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string checkpoint_path(const std::string& run_path) { return run_path + ".ckpt"; }

namespace {

// copies src to dst through dst.tmp, fsyncs, reads the copy back, renames: dst is always either the old
// or the new copy, and the new one replaces the old only once it is complete and every dataset reads back
// (with its checksum). The rename gives dst a new inode, so a writer that still has the old file open
// (a rank of a killed job) cannot touch the new one.
void atomic_copy(const std::string& src, const std::string& dst, bool verify) {
  const std::string tmp = dst + ".tmp";
  try {
    fs::copy_file(src, tmp, fs::copy_options::overwrite_existing);
    const int fd = ::open(tmp.c_str(), O_RDONLY);
    DIVCOLL_THROW_UNLESS(fd >= 0 && ::fsync(fd) == 0, "cannot sync " << tmp);
    ::close(fd);
    std::string why;
    DIVCOLL_THROW_UNLESS(!verify || valid_run_file(tmp, &why), "the new copy " << tmp << " does not read back (" << why
                                                                                << "); the previous one is kept");
    fs::rename(tmp, dst);
  } catch (...) {
    // a half copy only takes the space a full disk lacks; the previous checkpoint stays as it was
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

// one int from rank 0 to all (the others wait sleeping, not spinning in MPI)
int bcast_int(MPI_Comm comm, int v) {
  MPI_Request req;
  MPI_Ibcast(&v, 1, MPI_INT, 0, comm, &req);
  wait_sleeping(req);
  return v;
}

DeferredWrites* g_deferred = nullptr;

}  // namespace

DeferredWrites::DeferredWrites(std::function<void()> flush, std::function<bool()> urgent)
    : flush_(std::move(flush)), urgent_(std::move(urgent)) {
  DIVCOLL_DEMAND(g_deferred == nullptr);
  g_deferred = this;
}

DeferredWrites::~DeferredWrites() { g_deferred = nullptr; }

void checkpoint(MPI_Comm comm, io::h5::File& file, const std::string& run_path) {
  H5Fflush(file.id(), H5F_SCOPE_GLOBAL);
  // every rank's writes are on disk before rank 0 copies; the other ranks wait for the copy sleeping
  MPI_Request req;
  MPI_Ibarrier(comm, &req);
  wait_sleeping(req);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  int ok = 1;
  std::string err;
  if (rank == 0) {
    try {
      atomic_copy(run_path, checkpoint_path(run_path), true);
    } catch (const std::exception& e) {
      ok = 0;
      err = e.what();
    }
  }
  if (!bcast_int(comm, ok)) {
    std::error_code ec;
    const auto space = fs::space(fs::absolute(run_path).parent_path(), ec);
    throw InputError(msg() << "cannot write the checkpoint " << checkpoint_path(run_path) << ": " << err << " ("
                           << space.available / 1024 << " KiB free on its file system; the last checkpoint is "
                           << "kept: free space and rerun with --resume)");
  }
}

Checkpointer::Checkpointer(MPI_Comm comm, io::h5::File& file, std::string run_path, double interval_s)
    : comm_(comm), file_(file), path_(std::move(run_path)), interval_s_(interval_s), last_(Clock::now()) {}

void Checkpointer::at(bool force) {
  int rank = 0;
  MPI_Comm_rank(comm_, &rank);
  check_symmetric_io(comm_, "a checkpoint");  // at every commit, whether it copies or not
  // one collective decides for every rank: any rank's stop request, and rank 0's clock
  int v[2] = {stop_signal(), 0};
  if (rank == 0)
    v[1] = force || interval_s_ <= 0 || std::chrono::duration<double>(Clock::now() - last_).count() >= interval_s_ ||
           (g_deferred && g_deferred->urgent_());
  MPI_Request req;
  MPI_Iallreduce(MPI_IN_PLACE, v, 2, MPI_INT, MPI_MAX, comm_, &req);
  wait_sleeping(req);
  if (v[0] != 0 || v[1] != 0) {
    if (g_deferred) g_deferred->flush_();
    const auto t0 = Clock::now();
    checkpoint(comm_, file_, path_);
    last_ = Clock::now();
    copy_s_ += std::chrono::duration<double>(last_ - t0).count();
    ++copies_;
  }
  if (v[0] != 0) throw StopRequested{v[0]};
}

bool valid_run_file(const std::string& path, std::string* why) {
  try {
    io::h5::File f = io::h5::File::open(path);
    if (!f.has_attribute("format") || f.read_string("format") != "divcoll-run" || !f.has_attribute("config")) {
      if (why) *why = "not a complete divcoll run file";
      return false;
    }
    // every dataset must read back (HDF5 checks each one's Fletcher-32 checksum on the way)
    struct Bad {
      int count = 0;
      std::string first, reason;
    } bad;
    auto visit = [](hid_t obj, const char* name, const H5O_info_t* info, void* data) -> herr_t {
      if (info->type != H5O_TYPE_DATASET) return 0;
      Bad& b = *static_cast<Bad*>(data);
      io::h5::Handle d(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose);
      bool ok = d.valid();
      if (ok) {
        io::h5::Handle space(H5Dget_space(d.id()), H5Sclose);
        io::h5::Handle type(H5Dget_type(d.id()), H5Tclose);
        const size_t n = static_cast<size_t>(H5Sget_simple_extent_npoints(space.id())) * H5Tget_size(type.id());
        std::string buf(n, '\0');
        ok = n == 0 || H5Dread(d.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) >= 0;
      }
      if (!ok && b.count++ == 0) {
        b.first = name;
        auto walk = [](unsigned k, const H5E_error2_t* err, void* out) -> herr_t {
          if (k == 0 && err && err->desc) *static_cast<std::string*>(out) = err->desc;
          return 0;
        };
        H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk, &b.reason);
      }
      H5Eclear2(H5E_DEFAULT);
      return 0;
    };
    if (H5Ovisit(f.id(), H5_INDEX_NAME, H5_ITER_INC, visit, &bad) < 0 || bad.count > 0) {
      if (why)
        *why = bad.count == 0 ? std::string("its datasets cannot be listed")
                              : std::to_string(bad.count) + " of its datasets do not read back or fail their checksum (the first: " + bad.first +
                                    (bad.reason.empty() ? "" : ": " + bad.reason) + ")";
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return false;
  }
}

bool prepare_resume(MPI_Comm comm, const std::string& run_path) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  // rank 0 decides: start from nothing (false), continue (true), or refuse (every rank throws)
  bool decision = false;
  agree_rank0(comm, [&] {
    std::string why;
    const std::string ck = checkpoint_path(run_path);
    const bool have_run = fs::exists(run_path), have_ck = fs::exists(ck);
    // the checkpoint first: only a checkpoint is a committed whole. What a killed job left in the run file
    // after its last checkpoint may hold a round's state without its counter (or the reverse: HDF5 writes its
    // cached metadata when it likes), and the rounds after the checkpoint are redone anyway
    if (have_ck && valid_run_file(ck, nullptr)) {
      if (have_run && !valid_run_file(run_path, &why))
        std::printf("resume: %s is damaged (%s); restoring the checkpoint %s\n", run_path.c_str(), why.c_str(), ck.c_str());
      else if (have_run)
        std::printf("resume: continuing from the checkpoint %s\n", ck.c_str());
      // a copy under a new inode: the checkpoint itself stays as it is until the next one replaces it
      atomic_copy(ck, run_path, false);
      decision = true;
    } else if (have_run && valid_run_file(run_path, &why)) {
      decision = true;
    } else if (have_run) {
      throw InputError(msg() << run_path << " cannot be resumed: " << why << ", and it has no usable checkpoint"
                             << (have_ck ? " (" + ck + " does not read back either)" : std::string())
                             << "; pass --force to start over");
    }
  });
  int d = decision ? 1 : 0;
  MPI_Bcast(&d, 1, MPI_INT, 0, comm);
  return d == 1;
}

void remove_checkpoint(MPI_Comm comm, const std::string& run_path) {
  barrier_sleeping(comm);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) fs::remove(checkpoint_path(run_path));
}

}  // namespace divcoll::mpi
