// divcoll: the command-line entry point. commands() is the list of subcommands, one row each (its name, its line in
// `divcoll --help`, the options it registers, what it runs); main builds the CLI11 app from it and runs the one
// named. Adding a command is adding its row.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "cli/bench_farm.hpp"
#include "cli/commands.hpp"
#include "cli/run.hpp"
#include "cli/study.hpp"
#include "common/check.hpp"
#include "common/version.hpp"
#include "nn/kernel_path.hpp"
#include "config/config.hpp"

namespace divcoll::cli {
namespace {

// the stages --from may name: every stage of DIVCOLL_STAGES but the first (agents is never recomputed on a copy)
std::vector<std::string> from_stages() {
  const std::vector<std::string>& all = config::stage_names();
  return std::vector<std::string>(all.begin() + 1, all.end());
}

// one subcommand of `divcoll`
struct Command {
  const char* name;
  const char* about;                           // its line in `divcoll --help`
  std::function<void(CLI::App&)> add_options;  // registers its options, which fill arguments the row holds
  std::function<int(int, char**)> run;         // runs it on those arguments (argc, argv: for MPI_Init); its exit code
};

// a row whose options fill an Args that its run reads: a single-process command ...
template <class Args>
Command command(const char* name, const char* about, std::type_identity_t<void (*)(CLI::App&, Args&)> options,
                std::type_identity_t<int (*)(const Args&)> run) {
  auto args = std::make_shared<Args>();
  return {name, about, [=](CLI::App& app) { options(app, *args); }, [=](int, char**) { return run(*args); }};
}
// ... or one that initialises MPI with the command line
template <class Args>
Command command(const char* name, const char* about, std::type_identity_t<void (*)(CLI::App&, Args&)> options,
                std::type_identity_t<int (*)(int, char**, const Args&)> run) {
  auto args = std::make_shared<Args>();
  return {name, about, [=](CLI::App& app) { options(app, *args); },
          [=](int argc, char** argv) { return run(argc, argv, *args); }};
}

struct NoArgs {};
struct SchemaArgs {
  std::string check;
};
struct CompareArgs {
  std::string a, b;
  bool digest = false;
};

// the options `divcoll evolve` and `divcoll run` share
void run_options(CLI::App& cmd, RunArgs& a) {
  cmd.add_option("config", a.config, "config file (TOML), e.g. configs/quick.toml")->required()->check(CLI::ExistingFile);
  cmd.add_option("overrides", a.overrides, "section.key=value overrides");
  cmd.add_option("--out", a.out, "run file (default: <output.dir>/<run.name>.h5)");
  cmd.add_flag("--resume", a.resume, "continue the run file if it exists (else start it)");
  cmd.add_flag("--force", a.force, "overwrite an existing run file");
}

// every subcommand, in the order `divcoll --help` lists them
std::vector<Command> commands() {
  return {
      command<SimulateArgs>(
          "simulate", "simulate a scene file and write its trajectory file (SPEC §9)",
          [](CLI::App& s, SimulateArgs& a) {
            s.add_option("--scene", a.scene, "scene file (HDF5)")->required()->check(CLI::ExistingFile);
            s.add_option("--steps", a.steps, "control steps T")->required()->check(CLI::Range(1, 10000000));
            s.add_option("--out", a.out, "trajectory file to write")->required();
            s.add_flag("--grad", a.grad, "also write the gradient of travel (grad/*)");
            s.add_flag("--force", a.force, "overwrite an existing output file");
            s.add_option("--memory-limit-gb", a.memory_limit_gb,
                         "refuse an episode whose tape and trajectory need more (default: 80% of MemAvailable)")
                ->check(CLI::Range(0.0, 1e6));
          },
          simulate),

      command<SceneArgs>(
          "scene", "write the scene file of an agent, a pair or a chain in an environment",
          [](CLI::App& c, SceneArgs& a) {
            c.add_option("--kind", a.kind, "agent, pair or chain")->check(CLI::IsMember({"agent", "pair", "chain"}));
            c.add_option("--env", a.env, "environment name (see `divcoll envs`)");
            c.add_option("--out", a.out, "scene file to write")->required();
            c.add_option("--agents", a.agents, "agents in a chain")->check(CLI::Range(2, 1000));
            c.add_option("--seed", a.seed, "random seed for agents and connector");
            c.add_option("--connector", a.connector, "weak or strong")->check(CLI::IsMember({"weak", "strong"}));
            c.add_flag("--uniform", a.uniform, "clones of one agent instead of different agents");
            c.add_option("--config", a.config,
                         "run config whose connector stiffness and contact law (run.contact) to use (default: the paper's)")
                ->check(CLI::ExistingFile);
            c.add_flag("--force", a.force, "overwrite an existing output file");
          },
          scene),

      command<ExportArgs>(
          "export", "write the scene file of one episode of a run file (then `simulate` it)",
          [](CLI::App& x, ExportArgs& a) {
            x.add_option("run", a.run, "run file")->required()->check(CLI::ExistingFile);
            x.add_option("--what", a.what, "alone (deploy), pair (deploy), specialist or chain (scaling)")
                ->check(CLI::IsMember({"alone", "pair", "specialist", "chain"}));
            x.add_option("--env", a.env, "environment of the episode");
            x.add_option("--agent", a.agent, "agent index (alone)");
            x.add_option("--type", a.type, "collective type KIND@DEPLOYMENT, e.g. weak_uniform@diverse (pair)");
            x.add_option("--replicate", a.replicate, "connector replicate (pair, specialist, chain)");
            x.add_option("--pair", a.pair, "pair index (pair, specialist)");
            x.add_option("--size", a.size, "chain size N (chain)");
            x.add_option("--variant", a.variant, "uniform or diverse (chain)")->check(CLI::IsMember({"uniform", "diverse"}));
            x.add_option("--draw", a.draw, "chain index within its replicate (chain)");
            x.add_option("--out", a.out, "scene file to write")->required();
            x.add_flag("--force", a.force, "overwrite an existing output file");
          },
          export_scene),

      command<DemoArgs>(
          "demo", "a pair on flat ground and in a novel environment, travel in body lengths",
          [](CLI::App& d, DemoArgs& a) {
            d.add_option("--out", a.out, "output folder");
            d.add_option("--env", a.env, "the novel environment");
            d.add_option("--seed", a.seed, "random seed");
            d.add_option("--steps", a.steps, "steps per episode (without --run)")->check(CLI::Range(1, 10000000));
            d.add_option("--run", a.run, "run file whose trained agents and connector to use")->check(CLI::ExistingFile);
            d.add_flag("--movie", a.movie, "also render the episodes as MP4 (ffmpeg)");
          },
          demo),

      command<TetherArgs>(
          "tether", "what a run's tethers do to each agent of a deployed pair: impulse, work, travel against alone",
          [](CLI::App& t, TetherArgs& a) {
            t.add_option("run", a.run, "run file with a deployment")->required()->check(CLI::ExistingFile);
            t.add_option("--out", a.out, "output folder (tether.csv; tether.md, .png by divcoll_post.tether)");
            t.add_option("--pairs", a.pairs, "the first N deployed pairs of each deployment")->check(CLI::Range(1, 100000));
            t.add_option("--replicate", a.replicate, "trained connector replicate")->check(CLI::NonNegativeNumber);
            t.add_option("--steps", a.steps, "steps per episode (default: the run's deploy.episode_steps)")
                ->check(CLI::Range(1, 10000000));
            t.add_flag("--force", a.force, "overwrite existing output files");
          },
          tether),

      command<ReportArgs>(
          "report", "one page with the paper's claims beside a run file's numbers, and every figure",
          [](CLI::App& r, ReportArgs& a) {
            r.add_option("run", a.run, "run file, or a study folder (the robustness page)")->required()->check(CLI::ExistingPath);
            r.add_option("--out", a.out, "output folder (report.md, report.html, table_s1.md, figures/)");
            r.add_flag("--movie", a.movie, "also render the supplementary movie (MP4, ffmpeg) into the page");
            r.add_option("--keep", a.keep,
                         "study folder only: also copy the study (manifest, base config, run summaries; no run files) to "
                         "this folder, e.g. postprocess/gallery/studies/NAME, from which `divcoll report` redraws the page");
          },
          report),

      command<MovieArgs>(
          "movie", "the paper's Supplementary Movie from a run file, as MP4 (ffmpeg)",
          [](CLI::App& m, MovieArgs& a) {
            m.add_option("run", a.run, "run file")->required()->check(CLI::ExistingFile);
            m.add_option("--out", a.out, "output folder");
            m.add_flag("--quick", a.quick, "fewer frames and environments (tests)");
          },
          movie),

      command<BenchArgs>(
          "bench", "steps per CPU-second of one core, and speed against error",
          [](CLI::App& b, BenchArgs& a) {
            b.add_option("--seconds", a.seconds, "minimum CPU seconds timed per row")->check(CLI::Range(0.01, 600.0));
            b.add_flag("--quick", a.quick, "fewer rows");
            b.add_option("--pacmap", a.pacmap, "only the CPU cost of one PaCMAP fit of each of these numbers of states")
                ->delimiter(',')
                ->check(CLI::Range(4, 1000000));
            b.add_option("--config", a.config, "run config whose weak connector stiffness to use (default: the paper's)")
                ->check(CLI::ExistingFile);
          },
          bench),

      command<BenchFarmArgs>(
          "bench-farm", "the task farm's master alone: cost per item at any rank count (MPI)",
          [](CLI::App& b, BenchFarmArgs& a) {
            b.add_option("--item-ms", a.item_ms, "cost of one synthetic item, ms (a sleep)")->check(CLI::Range(0.0, 60000.0));
            b.add_option("--result-bytes", a.result_bytes, "bytes of one result")->check(CLI::Range(0, 1 << 28));
            b.add_option("--task-bytes", a.task_bytes, "bytes of one task")->check(CLI::Range(0, 1 << 28));
            b.add_option("--items", a.items, "items per round")->check(CLI::Range(0, 100000000));
            b.add_option("--rounds", a.rounds, "rounds measured (after one warm-up round)")->check(CLI::Range(1, 100000));
            b.add_option("--block", a.block, "items per task message (0: guided)")->check(CLI::Range(0, 1000000));
            b.add_option("--max-block", a.max_block, "largest guided block")->check(CLI::Range(1, 1000000));
            b.add_option("--depth", a.depth, "blocks a worker holds at once")->check(CLI::Range(1, 64));
            b.add_option("--fold", a.fold, "master folds results: none, after the round, during it")
                ->check(CLI::IsMember({"none", "after", "during"}));
            b.add_flag("--master-works", a.master_works, "the master computes items too");
          },
          bench_farm_main),

      command<NoArgs>(
          "envs", "list the built-in environments", [](CLI::App&, NoArgs&) {},
          [](const NoArgs&) { return envs(); }),

      command<NoArgs>(
          "keys", "every config key with its type, default, allowed range, unit and meaning (markdown)",
          [](CLI::App&, NoArgs&) {},
          [](const NoArgs&) { return std::printf("%s", config::schema_markdown().c_str()) < 0 ? 1 : 0; }),

      command<SchemaArgs>(
          "schema", "every group and dataset of a run file: type, axes, unit, meaning (markdown)",
          [](CLI::App& s, SchemaArgs& a) {
            s.add_option("--check", a.check, "instead, list where this run file differs from the schema (exit 1 if it does)")
                ->check(CLI::ExistingFile);
          },
          [](const SchemaArgs& a) { return schema(a.check); }),

      command<CompareArgs>(
          "compare", "are two HDF5 files' datasets bit-identical? (exit 0 yes, 1 no)",
          [](CLI::App& c, CompareArgs& a) {
            c.add_option("a", a.a, "first file")->required()->check(CLI::ExistingFile);
            c.add_option("b", a.b, "second file (not with --digest)")->check(CLI::ExistingFile);
            c.add_flag("--digest", a.digest,
                       "instead, print the digest of the first file's datasets (paths, shapes and bytes; what "
                       "tests/mpi/tiny_golden.txt holds for the tiny preset)");
          },
          [](const CompareArgs& a) {
            if (a.digest) {
              if (!a.b.empty()) throw InputError("compare --digest takes one file");
              std::printf("%s\n", datasets_digest(a.a).c_str());
              return 0;
            }
            if (a.b.empty()) throw InputError("compare needs two files (or --digest and one)");
            return compare(a.a, a.b);
          }),

      command<GdCompareArgs>(
          "gd-compare", "measure the gradient rules of SPEC §4.4 on the same random agents",
          [](CLI::App& g, GdCompareArgs& a) {
            g.add_option("--agents", a.agents, "random agents")->check(CLI::Range(2, 100000));
            g.add_option("--epochs", a.epochs, "epochs per agent")->check(CLI::Range(1, 100000));
            g.add_option("--steps", a.steps, "steps per episode")->check(CLI::Range(1, 10000000));
            g.add_option("--seed", a.seed, "seed");
          },
          gd_compare),

      command<GradDiagArgs>(
          "grad-diag", "a connector batch objective's BPTT gradient against finite differences",
          [](CLI::App& g, GradDiagArgs& a) {
            g.add_option("run", a.run, "run file with the agents stage")->required()->check(CLI::ExistingFile);
            g.add_option("overrides", a.overrides, "section.key=value overrides of the run file's config");
            g.add_option("--kind", a.kind, "connector kind (stiffness, uniform or diverse batch)");
            g.add_option("--pairs", a.pairs, "pairs in the batch")->check(CLI::Range(1, 100000));
            g.add_option("--horizons", a.horizons, "episode lengths, comma-separated");
            g.add_option("--scales", a.scales, "perturbation sizes relative to |weights|, comma-separated");
            g.add_option("--directions", a.directions, "random directions besides the gradient")->check(CLI::Range(0, 1000));
            g.add_option("--window", a.window, "also the truncated-backpropagation gradient with this window")
                ->check(CLI::Range(0, 10000000));
            g.add_option("--train", a.train_iterations, "first train this many iterations with the [connectors] keys")
                ->check(CLI::Range(0, 1000000));
          },
          grad_diag),

      command<ConnectorOptArgs>(
          "connector-opt", "connector training with the [connectors] keys in one process, then flat travel",
          [](CLI::App& c, ConnectorOptArgs& a) {
            c.add_option("run", a.run, "run file with the agents stage")->required()->check(CLI::ExistingFile);
            c.add_option("overrides", a.overrides, "section.key=value overrides of the run file's config");
            c.add_option("--out", a.out, "prefix of the CSV files PREFIX_curves.csv and PREFIX_summary.csv")->required();
            c.add_option("--label", a.label, "label of this run in the CSV files");
            c.add_option("--eval-pairs", a.eval_pairs, "pairs per evaluation on flat")->check(CLI::Range(1, 100000));
            c.add_option("--eval-steps", a.eval_steps, "evaluation episode lengths, comma-separated");
            c.add_flag("--force", a.force, "overwrite existing CSV files");
          },
          connector_opt),

      command<RunArgs>(
          "evolve", "the agents stage: evolution and gradient descent (MPI)",
          [](CLI::App& v, RunArgs& a) {
            run_options(v, a);
            a.agents_only = true;
          },
          run_main),

      command<RunArgs>(
          "run", "the whole pipeline, stage by stage (MPI)",
          [](CLI::App& r, RunArgs& a) {
            run_options(r, a);
            r.add_option("--from", a.from,
                         "rerun this stage and the later ones on a copy of --base's earlier stages (written to --out)")
                ->check(CLI::IsMember(from_stages()));
            r.add_option("--base", a.base, "the run file whose earlier stages --from reuses")->check(CLI::ExistingFile);
          },
          run_main),

      command<StudyArgs>(
          "study", "one run file per (variant, seed) of a study file, reusing shared stages (MPI)",
          [](CLI::App& s, StudyArgs& a) {
            s.add_option("study", a.study,
                         "study file (TOML), e.g. configs/studies/tiny.toml; with --status the study folder")
                ->required()
                ->check(CLI::ExistingPath);
            s.add_option("--out", a.out, "study folder (manifest study.toml, <variant>/seed<k>.h5)");
            s.add_flag("--resume", a.resume, "continue a study that was interrupted, or grown by new seeds or variants");
            s.add_flag("--plan", a.plan,
                       "validate the study file and print its runs (what each computes and reuses); run nothing");
            s.add_option("--run", a.run, "with --resume: compute only this run (its number in --plan, or its path), "
                                         "exit 3 if the run it reuses has not ended");
            s.add_flag("--status", a.status, "list every run of the study folder: done, running, waiting, failed; ETA");
            s.add_option("--adopt", a.adopt, "copy a complete run file made elsewhere into the study folder, if its "
                                             "config is the study's run of its (variant, seed)")
                ->check(CLI::ExistingFile);
            s.add_option("--variant", a.variant,
                         "with --adopt: the variant the file stands for (default: its folder's name, "
                         "else the variant whose config it has)");
            s.add_option("--submit", a.submit, "submit one job per run still to compute (with its own ranks and "
                                               "resubmission), then the report job: slurm or pbs")
                ->check(CLI::IsMember({"slurm", "pbs"}));
            s.add_option("--ranks-per-run", a.ranks_per_run, "with --submit: MPI ranks of each run's job (default 1)");
            s.add_option("--max-parallel", a.max_parallel,
                         "with --submit: at most this many run jobs at once (default: no limit)");
            s.add_flag("--dry-run", a.dry_run, "with --submit: print the jobs and their dependencies, submit nothing");
            s.add_option("scheduler_options", a.scheduler_args,
                         "with --submit, after --: options for every sbatch / qsub");
          },
          study_main),
  };
}

}  // namespace
}  // namespace divcoll::cli

int main(int argc, char** argv) {
  using namespace divcoll;
  CLI::App app{"divcoll: morphological diversity within machines (Hein & Bongard), reproduced"};
  app.require_subcommand(1);
  // the kernel path is chosen before anything runs, so that a DIVCOLL_KERNELS this CPU cannot run stops here
  nn::KernelPath kernels;
  try {
    kernels = nn::kernel_path();
  } catch (const std::exception& err) {
    std::fprintf(stderr, "divcoll: error: %s\n", err.what());
    return 2;
  }
  app.set_version_flag("--version", std::string(DIVCOLL_VERSION) + " (" + git_commit() + ")\nkernels: " +
                                        nn::kernel_path_name(kernels) + " on " + nn::cpu_description() +
                                        "\nbuilt for: " + build_target());
  const std::vector<cli::Command> commands = cli::commands();
  std::vector<const CLI::App*> apps;
  for (const cli::Command& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.about);
    c.add_options(*sub);
    apps.push_back(sub);
  }

  // a mistyped command is named, with the list of commands
  std::string known;
  bool found = false;
  for (const cli::Command& c : commands) {
    known += (known.empty() ? "" : ", ") + std::string(c.name);
    found = found || (argc > 1 && c.name == std::string(argv[1]));
  }
  if (argc > 1 && argv[1][0] != '-' && !found) {
    std::fprintf(stderr, "divcoll: error: unknown command '%s' (commands: %s)\n", argv[1], known.c_str());
    return 2;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& err) {
    // --help and --version exit 0; every misuse exits 2, like every other bad input
    return app.exit(err) == 0 ? 0 : 2;
  }
  try {
    for (size_t i = 0; i < commands.size(); ++i)
      if (*apps[i]) return commands[i].run(argc, argv);
  } catch (const InputError& err) {
    std::fprintf(stderr, "divcoll: error: %s\n", err.what());
    return 2;
  } catch (const std::exception& err) {
    std::fprintf(stderr, "divcoll: failed: %s\n", err.what());
    return 1;
  }
  return 0;
}
