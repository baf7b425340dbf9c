#include "cli/run.hpp"

#include <fcntl.h>
#include <mpi.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <set>

#include "cli/commands.hpp"
#include "common/check.hpp"
#include "common/version.hpp"
#include "config/config.hpp"
#include "io/file_lock.hpp"
#include "io/h5.hpp"
#include "io/memory.hpp"
#include "io/run_file.hpp"
#include "mpi/agree.hpp"
#include "mpi/checkpoint.hpp"
#include "mpi/driver.hpp"
#include "mpi/pipeline.hpp"
#include "mpi/protocol.hpp"
#include "mpi/stop.hpp"
#include "mpi/wait.hpp"
#include "nn/kernel_path.hpp"
#include "stages/needs.hpp"

namespace divcoll::cli {
namespace {

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return b;
}

// MPI for the lifetime of a command (work happens in an inner scope, so files close before Finalize)
struct MpiSession {
  // FUNNELED: the task farm computes items in a thread of its own; only the calling thread uses MPI
  MpiSession(int argc, char** argv) {
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  }
  ~MpiSession() { MPI_Finalize(); }
};

// rank 0: copies `base` to `path` without the groups of `from` and the later stages, with the new config
void derive_run_file(const std::string& base, const std::string& path, const std::string& from,
                     const std::string& toml) {
  namespace fs = std::filesystem;
  const std::string tmp = path + ".new";
  fs::copy_file(base, tmp, fs::copy_options::overwrite_existing);
  {
    io::h5::File f = io::h5::File::open(tmp, true);
    io::run_file::derive(f, from, toml, now_iso(), fs::absolute(base).string() + " (stages before " + from + ")");
    f.close();
  }
  fs::remove(mpi::checkpoint_path(path));
  fs::rename(tmp, path);
}

// the tape of the longest episode with gradients of the stages that run: every rank's simulator holds
// one, so the ranks on a node share run.memory_limit_gb (default 80% of rank 0's MemAvailable)
void check_memory(MPI_Comm comm, const config::RunConfig& cfg, const RunArgs& args) {
  MPI_Comm node;
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  int per_node = 1;
  MPI_Comm_size(node, &per_node);
  MPI_Comm_free(&node);
  mpi::agree_rank0(comm, [&] {
    const stages::Tape need = stages::largest_tape(cfg, args.agents_only);
    const uint64_t limit = memory_limit_bytes(cfg.run.memory_limit_gb) / static_cast<uint64_t>(per_node);
    if (need.bytes > limit)
      throw InputError(msg() << "each rank's episodes with gradients need about " << gb_text(need.bytes) << " of memory ("
                             << need.what << "), more than its share of the limit: " << gb_text(limit) << " = "
                             << (cfg.run.memory_limit_gb > 0 ? "run.memory_limit_gb" : "80% of MemAvailable")
                             << " / " << per_node << " rank(s) on this node. Shorten the episodes, run fewer ranks "
                             << "per node, or raise run.memory_limit_gb");
  });
}

// refuses outputs that are not (or would not be) regular files, and an output that is one of the inputs
void check_run_output(const std::string& path, const RunArgs& args) {
  if (!cli::check_existing_output(path, "run file")) return;
  std::error_code ec;
  DIVCOLL_THROW_UNLESS(!std::filesystem::equivalent(path, args.config, ec), "--out " << path << " is the config file");
  if (args.resume || args.force) {
    const int fd = ::open(path.c_str(), O_RDWR);
    if (fd < 0) {
      const int err = errno;
      throw InputError(msg() << path << ": cannot open it for writing: " << std::strerror(err)
                             << (err == EPERM ? " (is it immutable? see lsattr)" : ""));
    }
    ::close(fd);
  }
}


// the command line, the config, the output and --from's base (every rank checks; prepare agrees the verdict)
void check_request(const RunArgs& args, config::RunConfig& cfg, std::string& path) {
  namespace fs = std::filesystem;
  cfg = config::load_config(args.config, args.overrides);
  path = args.out.empty() ? (fs::path(cfg.output.dir) / (cfg.run.name + ".h5")).string() : args.out;
  DIVCOLL_THROW_UNLESS(!(args.resume && args.force), "--resume and --force contradict each other");
  DIVCOLL_THROW_UNLESS(args.from.empty() == args.base.empty(), "--from STAGE and --base RUN.h5 go together");
  DIVCOLL_THROW_UNLESS(args.from.empty() || !args.resume,
                       "--from starts a new run file; to continue one that was interrupted, use --resume alone");
  check_run_output(path, args);
  if (!args.from.empty()) {
    DIVCOLL_THROW_UNLESS(fs::absolute(args.base) != fs::absolute(path),
                         "--from writes a new run file: give an --out other than --base " << args.base);
    std::string why;
    DIVCOLL_THROW_UNLESS(mpi::valid_run_file(args.base, &why), "--base " << args.base << " is not a usable run file: " << why);
    io::h5::File f = io::h5::File::open(args.base);
    const config::RunConfig before = config::parse_config(f.read_string("config"), args.base + " (stored config)");
    const std::string diff = config::incompatible_keys(before, cfg, args.from);
    if (!diff.empty())
      throw InputError(msg() << "--from " << args.from << " reuses the earlier stages of " << args.base
                             << ", so their keys must be the same:" << diff);
    for (const std::string& s : config::sections_before(args.from))
      if (config::stage_enabled(cfg, s))
        DIVCOLL_THROW_UNLESS(mpi::complete(f, s),
                             "--from " << args.from << ": stage " << s << " is not complete in " << args.base);
  }
  if (fs::exists(path) && !args.resume && !args.force)
    throw InputError(msg() << path << " exists; pass --resume to continue it or --force to start over");
}

// the run file's folder: rank 0 makes it, then every rank must find it and be able to write there
void make_output_folder(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path parent = fs::absolute(path).parent_path();
  mpi::agree_rank0(MPI_COMM_WORLD, [&] {
    std::error_code mkdir_error;
    fs::create_directories(parent, mkdir_error);
  });
  mpi::agree_all(MPI_COMM_WORLD, [&] {
    DIVCOLL_THROW_UNLESS(fs::is_directory(parent), "cannot create the output folder " << parent.string());
    DIVCOLL_THROW_UNLESS(access(parent.c_str(), W_OK) == 0, "the output folder " << parent.string() << " is not writable");
  });
}

// one writer per run file: rank 0 takes the lock, the other ranks join it
io::WriterLock lock_run_file(const std::string& path, int rank, int size) {
  io::WriterLock lock;
  std::string note;
  mpi::agree_rank0(MPI_COMM_WORLD, [&] { lock = io::WriterLock::acquire(path, size, &note); });
  mpi::agree_all(MPI_COMM_WORLD, [&] {
    if (rank != 0) lock = io::WriterLock::join(path, rank);
  });
  if (rank == 0 && !note.empty()) std::printf("divcoll: %s\n", note.c_str());
  return lock;
}

// rank 0: a run resumes only with the config it started with, but for the keys that choose what runs now or how it
// reports (checked read-only, before anything is opened for writing)
void check_resume_config(const std::string& path, const config::RunConfig& cfg) {
  std::string diff;
  io::h5::File f = io::h5::File::open(path);
  if (!f.has_attribute("format") || f.read_string("format") != "divcoll-run" || !f.has_attribute("config")) {
    diff = " (not a divcoll run file)";
  } else {
    const config::RunConfig before = config::parse_config(f.read_string("config"), path + " (stored config)");
    const auto a = config::flat(before), b = config::flat(cfg);
    // keys that choose what runs now or how it reports, not what it computes, may change
    const std::set<std::string> free = {"run.stages", "run.progress_every_s", "run.stop_grace_s", "run.memory_limit_gb", "output.dir",
                                        "output.checkpoint_every", "output.checkpoint_interval_s"};
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].second != b[i].second && !free.count(a[i].first))
        diff += " " + a[i].first + " (" + a[i].second + " -> " + b[i].second + ")";
  }
  if (!diff.empty()) throw InputError(msg() << "cannot resume " << path << " with a different config:" << diff);
}

// what the checks leave for the work: the config, the run file's path, whether the file is continued, its lock
struct Prepared {
  config::RunConfig cfg;
  std::string path;
  bool existing = false;
  io::WriterLock lock;
};

// everything that can be refused is refused here, identically on every rank, before any work: each check's verdict
// is agreed by all ranks (mpi/agree.hpp), so a refusal (InputError) on one rank is every rank's. On the way it arms
// the stop signals, takes the run file's lock and, with --from, makes the run file from the base's earlier stages
void prepare(const RunArgs& args, int rank, int size, Prepared& p) {
  mpi::agree_all(MPI_COMM_WORLD, [&] { check_request(args, p.cfg, p.path); });
  make_output_folder(p.path);
  // a stop asked for by a signal takes effect right after a checkpoint, on every rank at once. Armed before
  // the lock is taken, so a job script that sees the lock file knows the ranks will act on SIGUSR1
  mpi::arm_stop_signals(rank, p.cfg.run.stop_grace_s);
  mpi::barrier_sleeping(MPI_COMM_WORLD);
  // taken before anything is written (the lock also covers the checkpoint)
  p.lock = lock_run_file(p.path, rank, size);
  p.existing = args.resume && mpi::prepare_resume(MPI_COMM_WORLD, p.path);
  if (p.existing) mpi::agree_rank0(MPI_COMM_WORLD, [&] { check_resume_config(p.path, p.cfg); });
  // memory: the tapes of the episodes with gradients, before any is allocated
  check_memory(MPI_COMM_WORLD, p.cfg, args);
  // every stage that will run finds its inputs: in a stage that runs before it, or complete in the file
  mpi::agree_rank0(MPI_COMM_WORLD, [&] {
    stages::check_inputs(p.cfg, args.agents_only, p.existing ? p.path : std::string(), args.from, args.base);
  });
  if (!args.from.empty()) {
    // a copy of the base's earlier stages is made now and continued like a resumed run
    mpi::agree_rank0(MPI_COMM_WORLD, [&] {
      try {
        derive_run_file(args.base, p.path, args.from, config::to_toml(p.cfg));
      } catch (const std::exception& e) {
        throw InputError(msg() << "cannot make " << p.path << " from " << args.base << ": " << e.what());
      }
    });
    if (rank == 0) std::printf("divcoll: %s holds the stages of %s before %s\n", p.path.c_str(), args.base.c_str(), args.from.c_str());
    p.existing = true;
  }
}

// how this session computes (kernel path, CPU, build), as the run file's root attributes, rank 0's on every rank (the
// nodes of one run may have different CPUs, and an attribute is written by all): rewritten by every session of the
// run, so a resumed run names its last machine (every path gives the same bits; this is provenance). Returns
// "KERNELS on CPU" for the run's first line
std::string write_machine(io::h5::File& file, MPI_Comm comm) {
  const std::string kernels = mpi::broadcast(comm, std::string(nn::kernel_path_name(nn::kernel_path())));
  const std::string cpu = mpi::broadcast(comm, nn::cpu_description());
  file.write_string("kernels", kernels);
  file.write_string("cpu", cpu);
  file.write_string("build_target", mpi::broadcast(comm, std::string(build_target())));
  return kernels + " on " + cpu;
}

// a new run file is made under a temporary name and renamed into place when its provenance is written, so a file
// at `path` is always a complete run file (and gets a checkpoint at once)
void create_run_file(const std::string& path, const config::RunConfig& cfg, const std::string& toml, hid_t fapl, int rank) {
  namespace fs = std::filesystem;
  const std::string tmp = path + ".new";
  {
    io::h5::File fresh = io::h5::File::create(tmp, true, fapl);
    fresh.write_string("format", "divcoll-run");
    fresh.write_int("version", 1);
    fresh.write_string("divcoll_version", DIVCOLL_VERSION);
    fresh.write_string("git_commit", git_commit());
    fresh.write_int("seed", static_cast<int64_t>(cfg.run.seed));
    fresh.write_string("config", toml);
    fresh.write_string("start_time", now_iso());
    char host[256] = {0};
    gethostname(host, sizeof host - 1);
    fresh.write_string("hostname", host);
    fresh.close();
  }
  mpi::barrier_sleeping(MPI_COMM_WORLD);
  if (rank == 0) {
    fs::remove(mpi::checkpoint_path(path));
    fs::rename(tmp, path);
  }
  mpi::barrier_sleeping(MPI_COMM_WORLD);
}

}  // namespace

int run_main(int argc, char** argv, const RunArgs& args) {
  MpiSession session(argc, argv);
  return run_session(args);
}

int run_session(const RunArgs& args) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  Prepared p;
  try {
    prepare(args, rank, size, p);
  } catch (const InputError& e) {
    if (rank == 0) std::fprintf(stderr, "divcoll: error: %s\n", e.what());
    return 2;
  }
  const config::RunConfig& cfg = p.cfg;
  const std::string& path = p.path;

  try {
    const std::string toml = config::to_toml(cfg);
    io::h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fapl_mpio(fapl.id(), MPI_COMM_WORLD, MPI_INFO_NULL);
    // the file's metadata is written collectively at a flush (one MPI-IO write) instead of by rank 0 in small
    // independent writes: the quick agents stage's per-round writes went from 0.17 to 0.11 s at 2 ranks
    H5Pset_coll_metadata_write(fapl.id(), true);
    if (!p.existing) create_run_file(path, cfg, toml, fapl.id(), rank);
    io::h5::File file = io::h5::File::open(path, true, fapl.id());
    if (p.existing) file.write_int("resumed", file.has_attribute("resumed") ? file.read_int("resumed") + 1 : 1);
    mpi::Checkpointer checkpoints(MPI_COMM_WORLD, file, path, cfg.output.checkpoint_interval_s);
    file.write_int("ranks", size);
    const std::string machine = write_machine(file, MPI_COMM_WORLD);
    if (rank == 0)
      std::printf("divcoll %s (%s): %s on %d rank(s), seed %llu -> %s\n(kernels %s)\n", DIVCOLL_VERSION,
                  git_commit(), args.agents_only ? "evolve" : "run", size, static_cast<unsigned long long>(cfg.run.seed),
                  path.c_str(), machine.c_str());
    const int64_t resumed = p.existing ? file.read_int("resumed") : 0;  // every rank reads (io/h5.hpp Journal)
    if (rank == 0 && p.existing)
      std::printf("resuming %s from its last checkpoint (resumed %lld time(s))\n", path.c_str(),
                  static_cast<long long>(resumed));

    try {
      // the first checkpoint of a new run: a stop asked for before it (the handlers are armed before the lock)
      // takes effect here
      if (!p.existing) checkpoints.force();
      mpi::run_stages(MPI_COMM_WORLD, cfg, file, checkpoints, args.agents_only);
    } catch (const mpi::StopRequested& stop) {
      // every rank is here, right after the same checkpoint: the file is closed normally
      mpi::disarm_stop_signals();
      file.close();
      mpi::barrier_sleeping(MPI_COMM_WORLD);
      p.lock.release();
      if (rank == 0)
        std::printf("divcoll: stopped by %s right after a checkpoint; %s holds every finished step: continue with "
                    "--resume (exit %d)\n",
                    mpi::signal_name(stop.signal), path.c_str(), mpi::kStoppedExit);
      std::fflush(stdout);
      return mpi::kStoppedExit;
    }
    mpi::disarm_stop_signals();
    file.write_string("end_time", now_iso());
    file.close();
    mpi::remove_checkpoint(MPI_COMM_WORLD, path);
    mpi::barrier_sleeping(MPI_COMM_WORLD);
    p.lock.release();
    if (rank == 0) std::printf("done: %s\n", path.c_str());
  } catch (const InputError& e) {
    // a failure after work started may be on one rank only: stop every rank, keep what was written
    std::fprintf(stderr, "divcoll: error (rank %d): %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "divcoll: failed (rank %d): %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  return 0;
}

}  // namespace divcoll::cli
