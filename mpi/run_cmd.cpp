#include "mpi/run_cmd.hpp"

#include <mpi.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <algorithm>
#include <set>

#include "common/check.hpp"
#include "common/version.hpp"
#include "io/config.hpp"
#include "io/h5.hpp"
#include "mpi/agents_stage.hpp"
#include "mpi/analysis_stage.hpp"
#include "mpi/checkpoint.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/deploy_stage.hpp"
#include "mpi/later_stages.hpp"
#include "mpi/scheduler.hpp"

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
  // FUNNELED: the task farm computes items in a thread of its own; only the calling thread uses MPI
  MpiSession(int argc, char** argv) {
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  }
  ~MpiSession() { MPI_Finalize(); }
};

}  // namespace

// the sections whose keys decide what a stage computes (beside run.seed, which every stage uses)
std::vector<std::string> sections_before(const std::string& stage) {
  std::vector<std::string> out;
  for (const std::string& s : io::stage_names()) {
    if (s == stage) break;
    out.push_back(s);
  }
  return out;
}

// --from: the keys of the stages before `from` (and run.seed) must be the base's; returns the differences
std::string incompatible_keys(const io::RunConfig& base, const io::RunConfig& now, const std::string& from) {
  const auto a = io::flat(base), b = io::flat(now);
  const auto secs = sections_before(from);
  std::string diff;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string sec = a[i].first.substr(0, a[i].first.find('.'));
    const bool bound = a[i].first == "run.seed" || std::find(secs.begin(), secs.end(), sec) != secs.end();
    if (bound && a[i].second != b[i].second) diff += " " + a[i].first + " (" + a[i].second + " -> " + b[i].second + ")";
  }
  return diff;
}

namespace {

// rank 0: copies `base` to `path` without the groups of `from` and the later stages, with the new config
void derive_run_file(const std::string& base, const std::string& path, const std::string& from,
                     const std::string& toml) {
  namespace fs = std::filesystem;
  const std::string tmp = path + ".new";
  fs::copy_file(base, tmp, fs::copy_options::overwrite_existing);
  {
    io::h5::File f = io::h5::File::open(tmp, true);
    bool later = false;
    for (const std::string& s : io::stage_names()) {
      later = later || s == from;
      if (later && f.has(s)) DIVCOLL_THROW_UNLESS(H5Ldelete(f.id(), s.c_str(), H5P_DEFAULT) >= 0, "cannot drop " << s);
    }
    // the earlier stages' provenance is kept under base_*; the new stages' is this binary's
    if (f.has_attribute("git_commit")) f.write_string("base_git_commit", f.read_string("git_commit"));
    if (f.has_attribute("start_time")) f.write_string("base_start_time", f.read_string("start_time"));
    for (const char* a : {"end_time", "resumed", "config", "git_commit", "start_time", "divcoll_version"})
      if (f.has_attribute(a)) H5Adelete(f.id(), a);
    f.write_string("config", toml);
    f.write_string("git_commit", git_commit());
    f.write_string("divcoll_version", DIVCOLL_VERSION);
    f.write_string("start_time", now_iso());
    f.write_string("derived_from", fs::absolute(base).string() + " (stages before " + from + ")");
    f.close();
  }
  fs::remove(checkpoint_path(path));
  fs::rename(tmp, path);
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
  namespace fs = std::filesystem;

  // everything that can be refused is refused here, identically on every rank, before any work
  io::RunConfig cfg;
  std::string path;
  bool existing = false;
  try {
    cfg = io::load_config(args.config, args.overrides);
    path = args.out.empty() ? (fs::path(cfg.output.dir) / (cfg.run.name + ".h5")).string() : args.out;
    DIVCOLL_THROW_UNLESS(!(args.resume && args.force), "--resume and --force contradict each other");
    DIVCOLL_THROW_UNLESS(args.from.empty() == args.base.empty(), "--from STAGE and --base RUN.h5 go together");
    DIVCOLL_THROW_UNLESS(args.from.empty() || !args.resume,
                         "--from starts a new run file; to continue one that was interrupted, use --resume alone");
    if (!args.from.empty()) {
      DIVCOLL_THROW_UNLESS(fs::absolute(args.base) != fs::absolute(path),
                           "--from writes a new run file: give an --out other than --base " << args.base);
      std::string why;
      DIVCOLL_THROW_UNLESS(valid_run_file(args.base, &why), "--base " << args.base << " is not a usable run file: " << why);
      io::h5::File f = io::h5::File::open(args.base);
      const io::RunConfig before = io::parse_config(f.read_string("config"), args.base + " (stored config)");
      const std::string diff = incompatible_keys(before, cfg, args.from);
      if (!diff.empty())
        throw InputError(msg() << "--from " << args.from << " reuses the earlier stages of " << args.base
                               << ", so their keys must be the same:" << diff);
      for (const std::string& s : sections_before(args.from))
        if (io::stage_enabled(cfg, s))
          DIVCOLL_THROW_UNLESS(f.has(s) && f.group(s).has_attribute("status") && f.group(s).read_string("status") == "complete",
                               "--from " << args.from << ": stage " << s << " is not complete in " << args.base);
    }
    if (fs::exists(path) && !args.resume && !args.force)
      throw InputError(msg() << path << " exists; pass --resume to continue it or --force to start over");
    const fs::path parent = fs::absolute(path).parent_path();
    std::error_code mkdir_error;  // a failure is reported below, on every rank alike
    if (rank == 0) fs::create_directories(parent, mkdir_error);
    MPI_Barrier(MPI_COMM_WORLD);
    DIVCOLL_THROW_UNLESS(fs::is_directory(parent), "cannot create the output folder " << parent.string());
    DIVCOLL_THROW_UNLESS(access(parent.c_str(), W_OK) == 0, "the output folder " << parent.string() << " is not writable");
    // a run resumes only with the config it started with (checked read-only, before anything is opened
    // for writing; rank 0 reads, every rank gets the verdict)
    existing = args.resume && prepare_resume(MPI_COMM_WORLD, path);
    if (!args.from.empty()) {
      // a copy of the base's earlier stages is made now and continued like a resumed run
      int ok = 1;
      std::string err;
      if (rank == 0) try {
          derive_run_file(args.base, path, args.from, io::to_toml(cfg));
        } catch (const std::exception& e) {
          ok = 0;
          err = e.what();
        }
      MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
      if (!ok) throw InputError(msg() << "cannot make " << path << " from " << args.base << ": " << err);
      if (rank == 0) std::printf("divcoll: %s holds the stages of %s before %s\n", path.c_str(), args.base.c_str(), args.from.c_str());
      existing = true;
    }
    if (existing && args.from.empty()) {
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
        fresh.write_string("git_commit", git_commit());
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
      std::printf("divcoll %s (%s): %s on %d rank(s), seed %llu -> %s\n", DIVCOLL_VERSION, git_commit(),
                  args.agents_only ? "evolve" : "run", size, static_cast<unsigned long long>(cfg.run.seed),
                  path.c_str());
    if (rank == 0 && existing)
      std::printf("resuming %s from its last checkpoint (resumed %lld time(s))\n", path.c_str(),
                  static_cast<long long>(file.read_int("resumed")));

    using StageFn = void (*)(MPI_Comm, const io::RunConfig&, io::h5::File&, const std::function<void()>&);
    const std::vector<std::pair<std::string, StageFn>> stages = {
        {"agents", run_agents_stage},           {"connectors", run_connectors_stage},
        {"deploy", run_deploy_stage},           {"specialists", run_specialists_stage},
        {"scaling", run_scaling_stage},         {"graded", run_graded_stage},
        {"analysis", run_analysis_stage}};
    for (const auto& [name, fn] : stages) {
      if (args.agents_only ? name != "agents" : !io::stage_enabled(cfg, name)) continue;
      if (file.has(name) && file.group(name).has_attribute("status") &&
          file.group(name).read_string("status") == "complete") {
        if (rank == 0) std::printf("stage %s: complete in the run file\n", name.c_str());
        continue;
      }
      const auto t1 = std::chrono::steady_clock::now();
      const FarmClock before = farm_clock();
      fn(MPI_COMM_WORLD, cfg, file, ckpt);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      // how busy each rank was (seconds computing items), gathered on every rank
      double busy = farm_clock().compute_s - before.compute_s;
      std::vector<double> busy_all(size);
      MPI_Allgather(&busy, 1, MPI_DOUBLE, busy_all.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
      std::string busy_text;
      double busy_sum = 0, busy_max = 0;
      for (double b : busy_all) {
        char tmp[32];
        std::snprintf(tmp, sizeof tmp, "%s%.3f", busy_text.empty() ? "" : ",", b);
        busy_text += tmp;
        busy_sum += b, busy_max = std::max(busy_max, b);
      }
      io::h5::Node g = file.group(name);
      g.write_double("wall_s_last_session", wall);
      g.write_double("wall_s", (g.has_attribute("wall_s") ? g.read_double("wall_s") : 0.0) + wall);
      // timings are attributes: `divcoll compare` (and the determinism tests) compare datasets only
      g.write_string("busy_s_per_rank_last_session", busy_text);
      if (rank == 0 && g.has_attribute("status") && g.read_string("status") == "complete")
        std::printf("stage %s: done in %.1f s; ranks busy %.0f%% of it (master %.0f%%), load imbalance max/mean %.2f\n",
                    name.c_str(), wall, 100 * busy_sum / (size * wall), 100 * busy_all[0] / wall,
                    busy_sum > 0 ? busy_max / (busy_sum / size) : 1.0);
    }
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
