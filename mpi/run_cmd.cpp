#include "mpi/run_cmd.hpp"

#include <mpi.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <set>

#include "common/check.hpp"
#include "io/config.hpp"
#include "io/h5.hpp"
#include "mpi/agents_stage.hpp"
#include "mpi/checkpoint.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/deploy_stage.hpp"

namespace divcoll::mpi {
namespace {

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return b;
}

// MPI for the lifetime of a command (work happens in an inner scope, so files close before Finalize)
struct MpiSession {
  MpiSession(int argc, char** argv) { MPI_Init(&argc, &argv); }
  ~MpiSession() { MPI_Finalize(); }
};

}  // namespace

int run_main(int argc, char** argv, const RunArgs& args) {
  MpiSession session(argc, argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  namespace fs = std::filesystem;

  // everything that can be refused is refused here, identically on every rank, before any work
  io::RunConfig cfg;
  std::string path;
  bool existing = false;
  try {
    cfg = io::load_config(args.config, args.overrides);
    path = args.out.empty() ? (fs::path(cfg.output.dir) / (cfg.run.name + ".h5")).string() : args.out;
    DIVCOLL_THROW_UNLESS(!(args.resume && args.force), "--resume and --force contradict each other");
    if (fs::exists(path) && !args.resume && !args.force)
      throw InputError(msg() << path << " exists; pass --resume to continue it or --force to start over");
    const fs::path parent = fs::absolute(path).parent_path();
    if (rank == 0) fs::create_directories(parent);
    MPI_Barrier(MPI_COMM_WORLD);
    DIVCOLL_THROW_UNLESS(fs::is_directory(parent), "cannot create the output folder " << parent.string());
    DIVCOLL_THROW_UNLESS(access(parent.c_str(), W_OK) == 0, "the output folder " << parent.string() << " is not writable");
    // a run resumes only with the config it started with (checked read-only, before anything is opened
    // for writing; rank 0 reads, every rank gets the verdict)
    existing = args.resume && prepare_resume(MPI_COMM_WORLD, path);
    if (existing) {
      std::string diff;
      if (rank == 0) {
        io::h5::File f = io::h5::File::open(path);
        if (!f.has_attribute("format") || f.read_string("format") != "divcoll-run" || !f.has_attribute("config")) {
          diff = " (not a divcoll run file)";
        } else {
          const io::RunConfig before = io::parse_config(f.read_string("config"), path + " (stored config)");
          const auto a = io::flat(before), b = io::flat(cfg);
          // keys that choose what runs now or how it reports, not what it computes, may change
          const std::set<std::string> free = {"run.stages", "run.progress_every_s", "output.dir",
                                              "output.checkpoint_every"};
          for (size_t i = 0; i < a.size(); ++i)
            if (a[i].second != b[i].second && !free.count(a[i].first))
              diff += " " + a[i].first + " (" + a[i].second + " -> " + b[i].second + ")";
        }
      }
      int len = static_cast<int>(diff.size());
      MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
      diff.resize(len);
      MPI_Bcast(diff.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
      if (!diff.empty()) throw InputError(msg() << "cannot resume " << path << " with a different config:" << diff);
    }
  } catch (const InputError& e) {
    if (rank == 0) std::fprintf(stderr, "divcoll: error: %s\n", e.what());
    return 2;
  }

  try {
    const std::string toml = io::to_toml(cfg);
    io::h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fapl_mpio(fapl.id(), MPI_COMM_WORLD, MPI_INFO_NULL);
    if (!existing) {
      // a new run file is made under a temporary name and renamed into place when its provenance is
      // written, so a file at `path` is always a complete run file (and gets a checkpoint at once)
      const std::string tmp = path + ".new";
      {
        io::h5::File fresh = io::h5::File::create(tmp, true, fapl.id());
        fresh.write_string("format", "divcoll-run");
        fresh.write_int("version", 1);
        fresh.write_string("divcoll_version", DIVCOLL_VERSION);
        fresh.write_string("git_commit", DIVCOLL_GIT_COMMIT);
        fresh.write_int("seed", static_cast<int64_t>(cfg.run.seed));
        fresh.write_string("config", toml);
        fresh.write_string("start_time", now_iso());
        char host[256] = {0};
        gethostname(host, sizeof host - 1);
        fresh.write_string("hostname", host);
        fresh.close();
      }
      MPI_Barrier(MPI_COMM_WORLD);
      if (rank == 0) {
        fs::remove(checkpoint_path(path));
        fs::rename(tmp, path);
      }
      MPI_Barrier(MPI_COMM_WORLD);
    }
    io::h5::File file = io::h5::File::open(path, true, fapl.id());
    if (existing) file.write_int("resumed", file.has_attribute("resumed") ? file.read_int("resumed") + 1 : 1);
    auto ckpt = [&] { checkpoint(MPI_COMM_WORLD, file, path); };
    if (!existing) ckpt();
    file.write_int("ranks", size);
    if (rank == 0)
      std::printf("divcoll %s (%s): %s on %d rank(s), seed %llu -> %s\n", DIVCOLL_VERSION, DIVCOLL_GIT_COMMIT,
                  args.agents_only ? "evolve" : "run", size, static_cast<unsigned long long>(cfg.run.seed),
                  path.c_str());

    const auto t0 = std::chrono::steady_clock::now();
    if (io::stage_enabled(cfg, "agents") || args.agents_only) {
      run_agents_stage(MPI_COMM_WORLD, cfg, file, ckpt);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      file.group("agents").write_double("wall_s_last_session", wall);
    }
    if (!args.agents_only && io::stage_enabled(cfg, "connectors")) {
      const auto t1 = std::chrono::steady_clock::now();
      run_connectors_stage(MPI_COMM_WORLD, cfg, file, ckpt);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      file.group("connectors").write_double("wall_s_last_session", wall);
    }
    if (!args.agents_only && io::stage_enabled(cfg, "deploy")) {
      const auto t1 = std::chrono::steady_clock::now();
      run_deploy_stage(MPI_COMM_WORLD, cfg, file, ckpt);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      file.group("deploy").write_double("wall_s_last_session", wall);
    }
    // the later stages land with their issues; say so rather than pretend
    if (!args.agents_only)
      for (const std::string& st : cfg.run.stages)
        if (st != "agents" && st != "connectors" && st != "deploy" && rank == 0)
          std::printf("stage %s: not implemented yet in this version; skipped\n", st.c_str());
    file.write_string("end_time", now_iso());
    file.close();
    remove_checkpoint(MPI_COMM_WORLD, path);
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

}  // namespace divcoll::mpi
