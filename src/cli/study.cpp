#include "cli/study.hpp"

#include <mpi.h>

#include <cstdio>
#include <filesystem>
#include <optional>

#include "cli/run.hpp"
#include "common/check.hpp"
#include "mpi/agree.hpp"
#include "mpi/wait.hpp"
#include "study/adopt.hpp"
#include "study/runs.hpp"
#include "study/status.hpp"
#include "study/submit.hpp"

namespace divcoll::cli {
namespace {

namespace fs = std::filesystem;

// the ranks of MPI_COMM_WORLD as the study's session: rank 0 leads, each run is `divcoll run`'s session
class MpiStudySession final : public study::Session {
 public:
  MpiStudySession() { MPI_Comm_rank(MPI_COMM_WORLD, &rank_); }
  bool leader() const override { return rank_ == 0; }
  int share(int value) override {
    MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return value;
  }
  void wait_all() override { mpi::barrier_sleeping(MPI_COMM_WORLD); }
  void on_leader(const std::function<void()>& f) override { mpi::agree_rank0(MPI_COMM_WORLD, f); }
  int run(const study::RunRequest& r) override {
    RunArgs ra;
    ra.config = r.config;
    ra.overrides = r.overrides;
    ra.out = r.out;
    ra.resume = r.resume;
    ra.from = r.from;
    ra.base = r.base;
    return run_session(ra);
  }

 private:
  int rank_ = 0;
};

void check_options(const StudyArgs& args) {
  const int used = !args.adopt.empty() + args.status + !args.submit.empty() + !args.run.empty() + args.plan;
  DIVCOLL_THROW_UNLESS(used <= 1, "--plan, --status, --adopt, --submit and --run go one at a time");
  DIVCOLL_THROW_UNLESS(args.status || !args.out.empty(), "--out DIR (the study folder) is required");
  DIVCOLL_THROW_UNLESS(args.submit.empty() || !args.resume, "--submit continues a study folder by itself: drop --resume");
  DIVCOLL_THROW_UNLESS(!args.submit.empty() || (args.scheduler_args.empty() && !args.dry_run && args.max_parallel == 0 &&
                                                args.ranks_per_run == 1),
                       "--ranks-per-run, --max-parallel, --dry-run and scheduler options go with --submit");
  DIVCOLL_THROW_UNLESS(args.variant.empty() || !args.adopt.empty(), "--variant goes with --adopt");
}

// --status, --adopt and --submit (which hands over to the scheduler's script) run nothing themselves: no MPI.
// Nothing for the others
std::optional<int> without_mpi(const StudyArgs& args) {
  if (args.status) {
    DIVCOLL_THROW_UNLESS(fs::is_directory(args.study), "--status takes the study folder: divcoll study DIR --status");
    return study::status(args.study);
  }
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(args.study), "no study file " << args.study);
  if (!args.adopt.empty()) return study::adopt(args.study, args.out, args.adopt, args.variant);
  if (!args.submit.empty())
    return study::submit(args.study, args.out,
                         {args.submit, args.ranks_per_run, args.max_parallel, args.dry_run, args.scheduler_args});
  return std::nullopt;
}

}  // namespace

int study_main(int argc, char** argv, const StudyArgs& args) {
  try {
    check_options(args);
    if (const std::optional<int> code = without_mpi(args)) return *code;
  } catch (const InputError& e) {
    std::fprintf(stderr, "divcoll: error: %s\n", e.what());
    return 2;
  }
  int provided = 0;  // FUNNELED: the task farm computes in a thread of its own (mpi/scheduler.hpp)
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    MpiStudySession session;
    code = study::run_study({args.study, args.out, args.resume, args.plan, args.run}, session);
  }
  MPI_Finalize();
  return code;
}

}  // namespace divcoll::cli
