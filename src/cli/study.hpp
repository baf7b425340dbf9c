// `divcoll study STUDY.toml --out DIR [--resume [--run K] | --submit slurm|pbs | --adopt RUN.h5]`, `divcoll study DIR
// --status`: one run file per (variant, seed) of a study, each made
// by `divcoll run` (run_session), reusing the earlier stages of an already finished run of the same seed
// whose keys for those stages agree (as --from does), so variants that differ only in deploy keys do not
// retrain agents or connectors.
//
// The study file (TOML):
//   [study]
//   name  = "claims"               run-file folder names and the report title
//   base  = "../paper.toml"        the run config every run starts from (relative to the study file)
//   seeds = [1, 2, 3]              run.seed of each replicate run
//   scale = ["deploy.pairs=100"]   section.key=value overrides applied to every run (before the variant's)
//   doc   = "..."                  optional: what the study asks
//   [[variant]]                    one table per variant, in the order they run and are reported
//   name = "baseline"              [A-Za-z0-9_-]+, unique; its runs are DIR/<name>/seed<k>.h5
//   set  = []                      section.key=value overrides of this variant
//   doc  = "..."                   optional: the reading of the paper it stands for
//   seeds = [1, 2]                 optional: run this variant at these study seeds only (default: every one)
// Every variant's config is built and validated (unknown keys, bad values, impossible combinations) before
// any work. Runs go seed by seed, each seed's variants in file order; the base of a run is the earlier
// variant of the same seed that shares the most leading stages (the earliest on a tie).
//
// DIR/base.toml is the run config as the study started: every run reads it, resumed runs too, so an edit of
// the config file (or a newer checkout) does not change a study half way.
// DIR/study.toml is the manifest: the study file's text, and per run its variant, seed, path, the stage it
// was computed from and the run it reused (empty: computed from scratch), its status, and for an adopted
// run the file it came from and that file's commit. `--resume` continues a killed study and gives the same
// run files; without it an existing manifest is refused. The study file may have grown (seeds, variants:
// their runs are added), but every run the folder holds (run file, summary, or complete in the manifest)
// must keep its config, else the run and its first differing key are named. `--plan` validates the study
// file and prints the runs, writing nothing. Every rank runs the same loop (any rank count, like `divcoll
// run`).
//
// Several jobs at once (a cluster, jobs/README.md):
//   --resume --run K     computes only run K (its number in --plan, or its path); exit 3, computing nothing,
//                        while the run it reuses has not ended. Every job that rewrites the manifest holds
//                        the folder's lock (io::WriterLock on DIR/study.toml) and merges: a run either side
//                        knows complete stays complete.
//   --submit slurm|pbs   (no MPI) writes the folder and DIR/jobs/runs.tsv (the runs still to compute and the
//                        run each waits for), then execs jobs/study-submit.sh: one job per run with
//                        --ranks-per-run ranks, at most --max-parallel at once, a derived run after its base,
//                        then `divcoll report DIR`; --dry-run prints the jobs and writes nothing; options after
//                        `--` go to every sbatch/qsub.
//   --adopt RUN.h5       (no MPI) copies a complete run file into the folder if its stored config is, key by
//                        key, the study's run of its (variant, seed) (--variant, else its folder's name);
//                        else exit 2 naming the first differing key, nothing written.
//   DIR --status         (no MPI) every run: done / running (job, stage, ETA) / waiting on its base / failed
//                        (its log's last lines) / not started, and an overall ETA; the job scripts record
//                        each run's job in DIR/<variant>/seed<k>.job. Exit 1 when a run failed.
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

// --run's exit status when the run's base (the run whose stages it copies) has not ended yet
inline constexpr int kBaseNotComplete = 3;

// initialises MPI, runs the study, finalises; returns the exit code (2 bad input, 1 failure, 75 stopped by a
// signal after a checkpoint, kBaseNotComplete); --status, --adopt and --submit run without MPI
int study_main(int argc, char** argv, const StudyArgs& args);

}  // namespace divcoll::cli
