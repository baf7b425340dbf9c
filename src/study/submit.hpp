// --submit slurm|pbs: writes the study folder and DIR/jobs/runs.tsv (the runs still to compute and the run each
// waits for), then execs jobs/study-submit.sh: one job per run with --ranks-per-run ranks, at most --max-parallel at
// once, a derived run after its base, then `divcoll report DIR`; --dry-run prints the jobs and writes nothing;
// options after `--` go to every sbatch/qsub
#pragma once

#include <string>
#include <vector>

namespace divcoll::study {

struct SubmitOptions {
  std::string scheduler;  // slurm | pbs
  int ranks_per_run = 1;
  int max_parallel = 0;   // at most this many run jobs at once (0: no limit)
  bool dry_run = false;   // print the jobs and their dependencies, submit nothing
  std::vector<std::string> scheduler_args;  // passed to every sbatch / qsub
};
// --submit: writes the folder and its list of runs to compute, then replaces the process with
// jobs/study-submit.sh (under $DIVCOLL_ROOT, else the source tree); returns only by throwing
int submit(const std::string& study_file, const std::string& dir, const SubmitOptions& options);

}  // namespace divcoll::study
