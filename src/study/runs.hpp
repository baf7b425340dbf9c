// `divcoll study`: one run file per (variant, seed) of a study file (study/study_file.hpp), each made by one
// `divcoll run` in a session the command keeps open for all of them, reusing the earlier stages of an already
// finished run of the same seed whose keys for those stages agree (study/plan.hpp), in a study folder that
// holds the base config as the study started, the manifest and the runs (study/folder.hpp).
//
// Every variant's config is built and validated (unknown keys, bad values, impossible combinations) before any
// work. `--resume` continues a killed study and gives the same run files; without it an existing manifest is
// refused. The study file may have grown (seeds, variants: their runs are added), but every run the folder holds
// (run file, summary, or complete in the manifest) must keep its config, else the run and its first differing
// key are named. `--plan` validates the study file and prints the runs, writing nothing.
//
// Several jobs at once (a cluster, jobs/README.md): `--resume --run K` computes only run K (its number in --plan,
// or its path) and exits kBaseNotComplete, computing nothing, while the run it reuses has not ended; --submit
// (study/submit.hpp) hands the runs to a scheduler, --status (study/status.hpp) says what each is doing, --adopt
// (study/adopt.hpp) takes in a run file made elsewhere.
//
// Nothing in src/study calls MPI: the runs are run by the session the command opens (Session), and adopt, status
// and submit need none.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace divcoll::study {

// --run's exit status when the run's base (the run whose stages it copies) has not ended yet
inline constexpr int kBaseNotComplete = 3;

// what one run of a study asks of `divcoll run`
struct RunRequest {
  std::string config;                  // the folder's copy of the base config
  std::vector<std::string> overrides;  // the run's
  std::string out;                     // its run file
  bool resume = false;                 // continue the run file (or start it)
  std::string from, base;              // or: compute stage `from` on, on a copy of run file `base`'s earlier stages
};

// the processes that run a study's runs (the ranks of an MPI session), each running the same loop: what the loop
// asks of them
class Session {
 public:
  virtual ~Session() = default;
  // the process that reads the folder, writes the manifest and prints (rank 0)
  virtual bool leader() const = 0;
  // the leader's value on every process
  virtual int share(int value) = 0;
  // every process waits here for the others
  virtual void wait_all() = 0;
  // `f` on the leader; an exception it throws is an InputError on every process
  virtual void on_leader(const std::function<void()>& f) = 0;
  // one run, as `divcoll run` makes it (every process); its exit status
  virtual int run(const RunRequest& r) = 0;
};

struct StudyRequest {
  std::string study, out;  // the study file, the study folder
  bool resume = false;
  bool plan = false;       // validate and print the runs (what each computes and reuses), run nothing
  std::string run;         // compute only this run (its number in the plan, or its path)
};
// runs the study's runs that are not complete (or the one of `run`): 0 when they are, 2 on bad input (said by the
// leader on standard error), kBaseNotComplete, or the exit status of the run that failed
int run_study(const StudyRequest& req, Session& session);

}  // namespace divcoll::study
