// `divcoll study STUDY.toml --out DIR [--plan | --resume [--run K] | --submit slurm|pbs | --adopt RUN.h5]`,
// `divcoll study DIR --status`: the command over the study subsystem (src/study/runs.hpp says what each does). It
// checks the options, opens the MPI session whose ranks run the study's runs (each a `divcoll run`: run_session),
// and runs --status, --adopt and --submit without MPI.
#pragma once

#include <string>
#include <vector>

namespace divcoll::cli {

struct StudyArgs {
  std::string study;  // study file (TOML); with --status the study folder
  std::string out;    // study folder
  bool resume = false;
  bool plan = false;    // validate and print the runs (what each computes and reuses), run nothing
  std::string run;      // --run K: compute only this run (its number in the plan, or its path)
  bool status = false;  // --status: list the runs of the folder `study` and what each is doing
  std::string adopt;    // --adopt RUN.h5: take a run file made elsewhere into the folder
  std::string variant;  // --variant NAME: the variant --adopt's file stands for (default: its folder's name)
  std::string submit;   // --submit slurm|pbs: one job per run to compute, then the report (jobs/study-submit.sh)
  int ranks_per_run = 1;
  int max_parallel = 0;  // at most this many run jobs at once (0: no limit)
  bool dry_run = false;  // --submit: print the jobs and their dependencies, submit nothing
  std::vector<std::string> scheduler_args;  // after `--`: passed to every sbatch / qsub
};

// returns the exit code: 2 bad input, 1 failure, 75 stopped by a signal after a checkpoint, 3 when --run's base run
// has not ended (study::kBaseNotComplete)
int study_main(int argc, char** argv, const StudyArgs& args);

}  // namespace divcoll::cli
