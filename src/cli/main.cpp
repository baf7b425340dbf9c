// divcoll: command-line entry point. Every subcommand lives in src/cli; this file only parses.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "common/version.hpp"
#include "cli/commands.hpp"
#include "common/check.hpp"
#include "config/config.hpp"
#include "cli/bench_farm.hpp"
#include "cli/run.hpp"
#include "cli/study.hpp"

int main(int argc, char** argv) {
  using namespace divcoll;
  CLI::App app{"divcoll: morphological diversity within machines (Hein & Bongard), reproduced"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(DIVCOLL_VERSION) + " (" + git_commit() + ")");

  cli::SimulateArgs sim;
  auto* s = app.add_subcommand("simulate", "simulate a scene file and write its trajectory file (SPEC §9)");
  s->add_option("--scene", sim.scene, "scene file (HDF5)")->required()->check(CLI::ExistingFile);
  s->add_option("--steps", sim.steps, "control steps T")->required()->check(CLI::Range(1, 10000000));
  s->add_option("--out", sim.out, "trajectory file to write")->required();
  s->add_flag("--grad", sim.grad, "also write the gradient of travel (grad/*)");
  s->add_flag("--force", sim.force, "overwrite an existing output file");
  s->add_option("--memory-limit-gb", sim.memory_limit_gb,
                "refuse an episode whose tape and trajectory need more (default: 80% of MemAvailable)")
      ->check(CLI::Range(0.0, 1e6));

  cli::SceneArgs sc;
  auto* c = app.add_subcommand("scene", "write the scene file of an agent, a pair or a chain in an environment");
  c->add_option("--kind", sc.kind, "agent, pair or chain")->check(CLI::IsMember({"agent", "pair", "chain"}));
  c->add_option("--env", sc.env, "environment name (see `divcoll envs`)");
  c->add_option("--out", sc.out, "scene file to write")->required();
  c->add_option("--agents", sc.agents, "agents in a chain")->check(CLI::Range(2, 1000));
  c->add_option("--seed", sc.seed, "random seed for agents and connector");
  c->add_option("--connector", sc.connector, "weak or strong")->check(CLI::IsMember({"weak", "strong"}));
  c->add_flag("--uniform", sc.uniform, "clones of one agent instead of different agents");
  c->add_option("--config", sc.config, "run config whose connector stiffness and contact law (run.contact) to use (default: the paper's)")
      ->check(CLI::ExistingFile);
  c->add_flag("--force", sc.force, "overwrite an existing output file");

  cli::ExportArgs ex;
  auto* x = app.add_subcommand("export", "write the scene file of one episode of a run file (then `simulate` it)");
  x->add_option("run", ex.run, "run file")->required()->check(CLI::ExistingFile);
  x->add_option("--what", ex.what, "alone (deploy), pair (deploy), specialist or chain (scaling)")
      ->check(CLI::IsMember({"alone", "pair", "specialist", "chain"}));
  x->add_option("--env", ex.env, "environment of the episode");
  x->add_option("--agent", ex.agent, "agent index (alone)");
  x->add_option("--type", ex.type, "collective type KIND@DEPLOYMENT, e.g. weak_uniform@diverse (pair)");
  x->add_option("--replicate", ex.replicate, "connector replicate (pair, specialist, chain)");
  x->add_option("--pair", ex.pair, "pair index (pair, specialist)");
  x->add_option("--size", ex.size, "chain size N (chain)");
  x->add_option("--variant", ex.variant, "uniform or diverse (chain)")->check(CLI::IsMember({"uniform", "diverse"}));
  x->add_option("--draw", ex.draw, "chain index within its replicate (chain)");
  x->add_option("--out", ex.out, "scene file to write")->required();
  x->add_flag("--force", ex.force, "overwrite an existing output file");

  cli::DemoArgs demo;
  auto* d = app.add_subcommand("demo", "a pair on flat ground and in a novel environment, travel in body lengths");
  d->add_option("--out", demo.out, "output folder");
  d->add_option("--env", demo.env, "the novel environment");
  d->add_option("--seed", demo.seed, "random seed");
  d->add_option("--steps", demo.steps, "steps per episode (without --run)")->check(CLI::Range(1, 10000000));
  d->add_option("--run", demo.run, "run file whose trained agents and connector to use")->check(CLI::ExistingFile);
  d->add_flag("--movie", demo.movie, "also render the episodes as MP4 (ffmpeg)");

  cli::ReportArgs rep;
  auto* rp = app.add_subcommand("report", "one page with the paper's claims beside a run file's numbers, and every figure");
  rp->add_option("run", rep.run, "run file, or a study folder (the robustness page)")->required()->check(CLI::ExistingPath);
  rp->add_option("--out", rep.out, "output folder (report.md, report.html, table_s1.md, figures/)");
  rp->add_flag("--movie", rep.movie, "also render the supplementary movie (MP4, ffmpeg) into the page");
  rp->add_option("--keep", rep.keep,
                 "study folder only: also copy the study (manifest, base config, run summaries; no run files) to "
                 "this folder, e.g. postprocess/gallery/studies/NAME, from which `divcoll report` redraws the page");

  cli::MovieArgs mov;
  auto* mv = app.add_subcommand("movie", "the paper's Supplementary Movie from a run file, as MP4 (ffmpeg)");
  mv->add_option("run", mov.run, "run file")->required()->check(CLI::ExistingFile);
  mv->add_option("--out", mov.out, "output folder");
  mv->add_flag("--quick", mov.quick, "fewer frames and environments (tests)");

  cli::BenchArgs bench;
  auto* b = app.add_subcommand("bench", "steps per CPU-second of one core, and speed against error");
  b->add_option("--seconds", bench.seconds, "minimum CPU seconds timed per row")->check(CLI::Range(0.01, 600.0));
  b->add_flag("--quick", bench.quick, "fewer rows");
  b->add_option("--pacmap", bench.pacmap, "only the CPU cost of one PaCMAP fit of each of these numbers of states")
      ->delimiter(',')->check(CLI::Range(4, 1000000));
  b->add_option("--config", bench.config, "run config whose weak connector stiffness to use (default: the paper's)")
      ->check(CLI::ExistingFile);

  cli::BenchFarmArgs bf;
  auto* bfc = app.add_subcommand("bench-farm", "the task farm's master alone: cost per item at any rank count (MPI)");
  bfc->add_option("--item-ms", bf.item_ms, "cost of one synthetic item, ms (a sleep)")->check(CLI::Range(0.0, 60000.0));
  bfc->add_option("--result-bytes", bf.result_bytes, "bytes of one result")->check(CLI::Range(0, 1 << 28));
  bfc->add_option("--task-bytes", bf.task_bytes, "bytes of one task")->check(CLI::Range(0, 1 << 28));
  bfc->add_option("--items", bf.items, "items per round")->check(CLI::Range(0, 100000000));
  bfc->add_option("--rounds", bf.rounds, "rounds measured (after one warm-up round)")->check(CLI::Range(1, 100000));
  bfc->add_option("--block", bf.block, "items per task message (0: guided)")->check(CLI::Range(0, 1000000));
  bfc->add_option("--max-block", bf.max_block, "largest guided block")->check(CLI::Range(1, 1000000));
  bfc->add_option("--depth", bf.depth, "blocks a worker holds at once")->check(CLI::Range(1, 64));
  bfc->add_option("--fold", bf.fold, "master folds results: none, after the round, during it")
      ->check(CLI::IsMember({"none", "after", "during"}));
  bfc->add_flag("--master-works", bf.master_works, "the master computes items too");

  auto* e = app.add_subcommand("envs", "list the built-in environments");
  auto* keys = app.add_subcommand("keys", "every config key with its type, default, allowed range, unit and meaning (markdown)");

  std::string schema_check;
  auto* sch = app.add_subcommand("schema", "every group and dataset of a run file: type, axes, unit, meaning (markdown)");
  sch->add_option("--check", schema_check, "instead, list where this run file differs from the schema (exit 1 if it does)")
      ->check(CLI::ExistingFile);

  std::string cmp_a, cmp_b;
  auto* cmpc = app.add_subcommand("compare", "are two HDF5 files' datasets bit-identical? (exit 0 yes, 1 no)");
  cmpc->add_option("a", cmp_a, "first file")->required()->check(CLI::ExistingFile);
  cmpc->add_option("b", cmp_b, "second file")->required()->check(CLI::ExistingFile);

  cli::GdCompareArgs gdc;
  auto* g = app.add_subcommand("gd-compare", "measure the gradient rules of SPEC §4.4 on the same random agents");
  g->add_option("--agents", gdc.agents, "random agents")->check(CLI::Range(2, 100000));
  g->add_option("--epochs", gdc.epochs, "epochs per agent")->check(CLI::Range(1, 100000));
  g->add_option("--steps", gdc.steps, "steps per episode")->check(CLI::Range(1, 10000000));
  g->add_option("--seed", gdc.seed, "seed");

  cli::GradDiagArgs gdg;
  auto* gd = app.add_subcommand("grad-diag", "a connector batch objective's BPTT gradient against finite differences");
  gd->add_option("run", gdg.run, "run file with the agents stage")->required()->check(CLI::ExistingFile);
  gd->add_option("overrides", gdg.overrides, "section.key=value overrides of the run file's config");
  gd->add_option("--kind", gdg.kind, "connector kind (stiffness, uniform or diverse batch)");
  gd->add_option("--pairs", gdg.pairs, "pairs in the batch")->check(CLI::Range(1, 100000));
  gd->add_option("--horizons", gdg.horizons, "episode lengths, comma-separated");
  gd->add_option("--scales", gdg.scales, "perturbation sizes relative to |weights|, comma-separated");
  gd->add_option("--directions", gdg.directions, "random directions besides the gradient")->check(CLI::Range(0, 1000));
  gd->add_option("--window", gdg.window, "also the truncated-backpropagation gradient with this window")
      ->check(CLI::Range(0, 10000000));
  gd->add_option("--train", gdg.train_iterations, "first train this many iterations with the [connectors] keys")
      ->check(CLI::Range(0, 1000000));

  cli::ConnectorOptArgs cop;
  auto* co = app.add_subcommand("connector-opt",
                                "connector training with the [connectors] keys in one process, then flat travel");
  co->add_option("run", cop.run, "run file with the agents stage")->required()->check(CLI::ExistingFile);
  co->add_option("overrides", cop.overrides, "section.key=value overrides of the run file's config");
  co->add_option("--out", cop.out, "prefix of the CSV files PREFIX_curves.csv and PREFIX_summary.csv")->required();
  co->add_option("--label", cop.label, "label of this run in the CSV files");
  co->add_option("--eval-pairs", cop.eval_pairs, "pairs per evaluation on flat")->check(CLI::Range(1, 100000));
  co->add_option("--eval-steps", cop.eval_steps, "evaluation episode lengths, comma-separated");
  co->add_flag("--force", cop.force, "overwrite existing CSV files");

  cli::RunArgs evo;
  auto* v = app.add_subcommand("evolve", "the agents stage: evolution and gradient descent (MPI)");
  cli::RunArgs run;
  auto* r = app.add_subcommand("run", "the whole pipeline, stage by stage (MPI)");
  for (auto [cmd, a] : {std::pair{v, &evo}, std::pair{r, &run}}) {
    cmd->add_option("config", a->config, "config file (TOML), e.g. configs/quick.toml")->required()->check(CLI::ExistingFile);
    cmd->add_option("overrides", a->overrides, "section.key=value overrides");
    cmd->add_option("--out", a->out, "run file (default: <output.dir>/<run.name>.h5)");
    cmd->add_flag("--resume", a->resume, "continue the run file if it exists (else start it)");
    cmd->add_flag("--force", a->force, "overwrite an existing run file");
  }
  r->add_option("--from", run.from,
                "rerun this stage and the later ones on a copy of --base's earlier stages (written to --out)")
      ->check(CLI::IsMember({"connectors", "deploy", "specialists", "scaling", "graded", "analysis"}));
  r->add_option("--base", run.base, "the run file whose earlier stages --from reuses")->check(CLI::ExistingFile);
  evo.agents_only = true;

  cli::StudyArgs study;
  auto* st = app.add_subcommand("study", "one run file per (variant, seed) of a study file, reusing shared stages (MPI)");
  st->add_option("study", study.study, "study file (TOML), e.g. configs/studies/tiny.toml; with --status the study folder")
      ->required()->check(CLI::ExistingPath);
  st->add_option("--out", study.out, "study folder (manifest study.toml, <variant>/seed<k>.h5)");
  st->add_flag("--resume", study.resume, "continue a study that was interrupted, or grown by new seeds or variants");
  st->add_flag("--plan", study.plan, "validate the study file and print its runs (what each computes and reuses); run nothing");
  st->add_option("--run", study.run, "with --resume: compute only this run (its number in --plan, or its path), "
                                     "exit 3 if the run it reuses has not ended");
  st->add_flag("--status", study.status, "list every run of the study folder: done, running, waiting, failed; ETA");
  st->add_option("--adopt", study.adopt, "copy a complete run file made elsewhere into the study folder, if its "
                                         "config is the study's run of its (variant, seed)")->check(CLI::ExistingFile);
  st->add_option("--variant", study.variant, "with --adopt: the variant the file stands for (default: its folder's name, "
                                             "else the variant whose config it has)");
  st->add_option("--submit", study.submit, "submit one job per run still to compute (with its own ranks and "
                                           "resubmission), then the report job: slurm or pbs")
      ->check(CLI::IsMember({"slurm", "pbs"}));
  st->add_option("--ranks-per-run", study.ranks_per_run, "with --submit: MPI ranks of each run's job (default 1)");
  st->add_option("--max-parallel", study.max_parallel, "with --submit: at most this many run jobs at once (default: no limit)");
  st->add_flag("--dry-run", study.dry_run, "with --submit: print the jobs and their dependencies, submit nothing");
  st->add_option("scheduler_options", study.scheduler_args, "with --submit, after --: options for every sbatch / qsub");

  // a mistyped command is named, with the list of commands
  std::string known;
  bool found = false;
  for (const auto* sub : app.get_subcommands({})) {
    known += (known.empty() ? "" : ", ") + sub->get_name();
    found = found || (argc > 1 && sub->get_name() == argv[1]);
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
    if (*s) return cli::simulate(sim);
    if (*c) return cli::scene(sc);
    if (*d) return cli::demo(demo);
    if (*rp) return cli::report(rep);
    if (*mv) return cli::movie(mov);
    if (*x) return cli::export_scene(ex);
    if (*b) return cli::bench(bench);
    if (*e) return cli::envs();
    if (*keys) return std::printf("%s", io::schema_markdown().c_str()) < 0;
    if (*sch) return cli::schema(schema_check);
    if (*g) return cli::gd_compare(gdc);
    if (*cmpc) return cli::compare(cmp_a, cmp_b);
    if (*gd) return cli::grad_diag(gdg);
    if (*co) return cli::connector_opt(cop);
    if (*v) return cli::run_main(argc, argv, evo);
    if (*r) return cli::run_main(argc, argv, run);
    if (*bfc) return cli::bench_farm_main(argc, argv, bf);
    if (*st) return cli::study_main(argc, argv, study);
  } catch (const InputError& err) {
    std::fprintf(stderr, "divcoll: error: %s\n", err.what());
    return 2;
  } catch (const std::exception& err) {
    std::fprintf(stderr, "divcoll: failed: %s\n", err.what());
    return 1;
  }
  return 0;
}
