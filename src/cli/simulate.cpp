// divcoll simulate, scene, demo, envs
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "cli/commands.hpp"
#include "collective/builders.hpp"
#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "io/memory.hpp"
#include "config/config.hpp"
#include "config/environments.hpp"
#include "io/h5.hpp"
#include "config/pipeline.hpp"
#include "io/run_read.hpp"
#include "io/scene_file.hpp"
#include "io/trajectory_file.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"

namespace divcoll::cli {

bool check_existing_output(const std::string& path, const char* noun) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return false;
  DIVCOLL_THROW_UNLESS(!fs::is_directory(st), "--out " << path << " is a directory; give the " << noun << "'s path");
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(st), "--out " << path << " exists and is not a regular file (a device, "
                                                          "pipe or socket); divcoll never writes over one, even with --force");
  return true;
}

void check_output_path(const std::string& path, bool force, const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  DIVCOLL_THROW_UNLESS(!path.empty(), "no output path given");
  if (check_existing_output(path, "output file")) {
    std::error_code ec;
    for (const std::string& in : inputs)
      DIVCOLL_THROW_UNLESS(!fs::equivalent(path, in, ec), "--out " << path << " is the input file " << in
                                                                    << "; write the output elsewhere");
  }
  if (fs::exists(path) && !force)
    throw InputError(msg() << path << " exists; pass --force to overwrite it");
  const fs::path parent = fs::absolute(path).parent_path();
  DIVCOLL_THROW_UNLESS(fs::is_directory(parent), "output folder " << parent.string() << " does not exist");
}

// the trajectory file's content for a simulated scene (without gradients)
io::Trajectory trajectory_of(const sim::Scene& scene, const sim::RunResult& r, int steps) {
  io::Trajectory t;
  t.steps = steps;
  t.n_masses = scene.n_masses();
  t.n_agents = scene.n_agents();
  t.x = r.x;
  t.v = r.v;
  t.touch = r.touch;
  t.travel = r.travel;
  t.status = sim::status_name(r.status);
  return t;
}

int simulate(const SimulateArgs& a) {
  check_output_path(a.out, a.force, {a.scene});
  const sim::Scene scene = io::read_scene(a.scene);
  sim::RunOptions opt;
  opt.steps = a.steps;
  opt.grad = a.grad;
  opt.record = true;
  // the tape (--grad) and the recorded trajectory, known before they are allocated
  const uint64_t need = episode_bytes(scene, opt), limit = memory_limit_bytes(a.memory_limit_gb);
  DIVCOLL_THROW_UNLESS(need <= limit, a.scene << " for " << a.steps << " steps" << (a.grad ? " with --grad" : "")
                                              << " needs about " << gb_text(need) << " of memory ("
                                              << sim::substeps_needed(scene) << " substep(s) per step), more than the limit of "
                                              << gb_text(limit)
                                              << (a.memory_limit_gb > 0 ? " (--memory-limit-gb)" : " (80% of MemAvailable; raise it with --memory-limit-gb)")
                                              << ": simulate fewer steps");
  sim::RunResult r = sim::simulate(scene, opt);

  io::Trajectory t = trajectory_of(scene, r, a.steps);
  t.has_grad = a.grad;
  if (a.grad) {
    t.grad_agent_params = std::move(r.grad_agent_params);
    t.grad_connector_params = std::move(r.grad_connector_params);
    t.grad_x0 = std::move(r.grad_x0);
    t.grad_rest_length = std::move(r.grad_rest_length);
  }
  io::write_trajectory(a.out, t, a.force);
  std::printf("%s: %d steps (%d substeps each), status %s, travel %.6f u = %.4f BL%s\n", a.out.c_str(), a.steps,
              r.substeps, t.status.c_str(), r.travel, r.travel / sim::mean_body_length(scene),
              a.grad ? ", with gradients" : "");
  if (r.status != sim::Status::ok) std::fprintf(stderr, "divcoll simulate: %s\n", r.message.c_str());
  return r.status == sim::Status::ok ? 0 : 3;
}

int scene(const SceneArgs& a) {
  check_output_path(a.out, a.force);
  config::environment_table(a.env);  // refuses an unknown name before any work
  DIVCOLL_THROW_UNLESS(a.kind == "agent" || a.kind == "pair" || a.kind == "chain",
                       "--kind must be agent, pair or chain (got '" << a.kind << "')");
  const config::RunConfig cfg = a.config.empty() ? config::default_config() : config::load_config(a.config);
  const collective::Tether k = collective::strength_tether(cfg.connectors, a.connector);
  // the config's contact law (run.contact) for the scene and the anchors' runs; the networks in double
  const sim::RunPhysics physics{config::run_physics(cfg).contact, false};
  const int n = a.kind == "agent" ? 1 : a.kind == "pair" ? 2 : a.agents;
  DIVCOLL_THROW_UNLESS(a.kind != "chain" || (a.agents >= 2 && a.agents <= 1000),
                       "--agents for a chain must lie in [2, 1000] (got " << a.agents << ")");
  // agents are random until the agents stage provides trained ones
  Rng rng(seed_for(a.seed, 0, 0));
  std::vector<morph::Agent> agents;
  for (int q = 0; q < (a.uniform ? 1 : n); ++q) {
    agents.push_back(collective::random_agent(rng));
    if (n > 1) agents.back().anchors = collective::compute_anchors(agents.back(), physics);
  }
  const std::vector<double> conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
  sim::Scene s;
  if (a.kind == "agent") {
    s = collective::agent_scene(agents[0], a.env, physics.contact);
  } else {
    std::vector<const morph::Agent*> ptr;
    for (int q = 0; q < n; ++q) ptr.push_back(&agents[a.uniform ? 0 : q]);
    s = a.kind == "pair" ? collective::pair_scene(*ptr[0], *ptr[1], conn, k, a.env, physics.contact)
                         : collective::chain_scene(ptr, conn, k, a.env, physics.contact);
  }
  io::write_scene(a.out, s, a.force);
  std::printf("%s: %s of %d agent(s) in %s, %d masses, %d springs, %d connector(s), %d substep(s)\n",
              a.out.c_str(), a.kind.c_str(), s.n_agents(), a.env.c_str(), s.n_masses(), s.n_springs(),
              s.n_connectors(), sim::substeps_needed(s));
  return 0;
}

namespace {
// the pair of the run's weak diverse-trained connector (replicate 0) whose travel on flat is the median of
// the ok pairs: a typical pair, not the best one
int median_pair(const std::string& run, int* n_ok, double* median_bl) {
  io::h5::quiet_errors();
  const io::h5::File f = io::h5::File::open(run);
  DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run",
                       run << " is not a divcoll run file");
  DIVCOLL_THROW_UNLESS(f.has("deploy/collectives/travel_bl") && f.group("deploy").read_string("status") == "complete",
                       run << " has no complete deploy stage (the demo needs trained agents and connectors)");
  const auto envs = io::split(f.group("deploy").read_string("environments"));
  const auto types = io::split(f.group("deploy").read_string("types"));
  int e = -1, t = -1;
  for (size_t i = 0; i < envs.size(); ++i)
    if (envs[i] == "flat") e = static_cast<int>(i);
  for (size_t i = 0; i < types.size(); ++i)
    if (types[i] == "weak_diverse@diverse") t = static_cast<int>(i);
  DIVCOLL_THROW_UNLESS(e >= 0 && t >= 0, run << " has no weak_diverse@diverse deployment on flat");
  io::h5::Dims d;
  const std::vector<double> bl = f.read<double>("deploy/collectives/travel_bl", &d);
  const std::vector<uint8_t> st = f.read<uint8_t>("deploy/collectives/status");
  const size_t base = ((static_cast<size_t>(e) * d[1] + t) * d[2] + 0) * d[3];
  std::vector<std::pair<double, int>> ok;
  for (size_t q = 0; q < d[3]; ++q)
    if (st[base + q] == 0) ok.emplace_back(bl[base + q], static_cast<int>(q));
  DIVCOLL_THROW_UNLESS(!ok.empty(), run << ": no weak_diverse@diverse pair of replicate 0 ended ok on flat");
  std::sort(ok.begin(), ok.end());
  *n_ok = static_cast<int>(ok.size());
  *median_bl = ok[(ok.size() - 1) / 2].first;
  return ok[(ok.size() - 1) / 2].second;
}
}  // namespace

int demo(const DemoArgs& a) {
  namespace fs = std::filesystem;
  config::environment_table(a.env);
  fs::create_directories(a.out);
  std::vector<std::pair<std::string, std::string>> episodes;  // scene, trajectory
  if (!a.run.empty()) {
    int n_ok = 0;
    double med = 0;
    const int q = median_pair(a.run, &n_ok, &med);
    std::printf("demo: the trained agents of %s joined by its weak diverse-trained connector (replicate 0); pair %d "
                "is the median of its %d ok pairs on flat (%.2f BL)\n",
                a.run.c_str(), q, n_ok, med);
    std::vector<std::string> rows;
    for (const std::string& env : {std::string("flat"), a.env}) {
      ExportArgs ex;
      ex.run = a.run;
      ex.env = env;
      ex.pair = q;
      ex.force = true;  // the demo folder is scratch: rerunning replaces it
      ex.out = (fs::path(a.out) / ("pair_" + env + "_scene.h5")).string();
      const int rc = export_scene(ex);  // prints what the run file records for the episode
      DIVCOLL_THROW_UNLESS(rc == 0, "divcoll export failed for " << env);
      const io::h5::File f = io::h5::File::open(a.run);
      const config::RunConfig cfg = config::parse_config(f.read_string("config"), a.run + " (stored config)");
      const auto envs = io::split(f.group("deploy").read_string("environments"));
      const auto types = io::split(f.group("deploy").read_string("types"));
      const int e = static_cast<int>(std::find(envs.begin(), envs.end(), env) - envs.begin());
      const int t = static_cast<int>(std::find(types.begin(), types.end(), "weak_diverse@diverse") - types.begin());
      DIVCOLL_THROW_UNLESS(e < static_cast<int>(envs.size()), a.run << " has no deployment in " << env);
      io::h5::Dims d;
      const std::vector<double> bl = f.read<double>("deploy/collectives/travel_bl", &d);
      const size_t at = ((static_cast<size_t>(e) * d[1] + t) * d[2] + 0) * d[3] + q;
      const double stored = bl[at];
      const double stored_u = f.read<double>("deploy/collectives/travel_u")[at];
      const sim::Scene s = io::read_scene(ex.out);
      sim::RunOptions opt;
      opt.steps = cfg.deploy.episode_steps;
      opt.record = true;
      const sim::RunResult r = sim::simulate(s, opt);
      const std::string traj = (fs::path(a.out) / ("pair_" + env + "_traj.h5")).string();
      io::write_trajectory(traj, trajectory_of(s, r, opt.steps), /*overwrite=*/true);
      const double got = r.travel / sim::mean_body_length(s);
      char row[512];
      std::snprintf(row, sizeof row, "%-12s %10.4f %10.4f %10s %16.4f  %s%s\n", env.c_str(), r.travel, got,
                    sim::status_name(r.status), stored, traj.c_str(),
                    (std::isnan(stored_u) && std::isnan(r.travel)) || stored_u == r.travel ? ""
                                                                                : "  (differs from the run file!)");
      rows.push_back(row);
      episodes.emplace_back(ex.out, traj);
    }
    std::printf("%-12s %10s %10s %10s %16s  %s\n", "environment", "travel_u", "travel_BL", "status", "run file (BL)",
                "trajectory file");
    for (const auto& row : rows) std::printf("%s", row.c_str());
  } else {
    Rng rng(seed_for(a.seed, 0, 0));
    // the spec's physics (coulomb, double): the demo has no config
    const sim::RunPhysics physics{};
    morph::Agent P = collective::random_agent(rng), A = collective::random_agent(rng);
    P.anchors = collective::compute_anchors(P, physics);
    A.anchors = collective::compute_anchors(A, physics);
    const std::vector<double> conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
    std::printf("demo: two random, untrained agents joined by an untrained weak connector (they barely move; "
                "pass --run RUN.h5 for a run's trained ones)\n");
    std::printf("%-12s %10s %10s %10s  %s\n", "environment", "travel_u", "travel_BL", "status", "scene file");
    for (const std::string& env : {std::string("flat"), a.env}) {
      const sim::Scene s = collective::pair_scene(P, A, conn, collective::strength_tether(config::default_config().connectors, "weak"), env,
                                                  physics.contact);
      const std::string path = (fs::path(a.out) / ("pair_" + env + "_scene.h5")).string();
      io::write_scene(path, s, /*overwrite=*/true);  // the demo folder is scratch: rerunning replaces it
      sim::RunOptions opt;
      opt.steps = a.steps;
      opt.record = true;
      const sim::RunResult r = sim::simulate(s, opt);
      const std::string traj = (fs::path(a.out) / ("pair_" + env + "_traj.h5")).string();
      io::write_trajectory(traj, trajectory_of(s, r, opt.steps), /*overwrite=*/true);
      std::printf("%-12s %10.4f %10.4f %10s  %s\n", env.c_str(), r.travel, r.travel / sim::mean_body_length(s),
                  sim::status_name(r.status), path.c_str());
      episodes.emplace_back(path, traj);
    }
  }
  if (a.movie) {
    std::vector<std::string> args = {"--episode"};
    for (const auto& [sc, tr] : episodes) args.insert(args.end(), {sc, tr});
    const std::string mp4 = (fs::path(a.out) / "demo.mp4").string();
    args.insert(args.end(), {"--out", mp4});
    const int rc = run_python("divcoll_post.movie", args);
    DIVCOLL_THROW_UNLESS(rc == 0, "rendering " << mp4 << " failed (divcoll_post.movie exit " << rc << ")");
  } else {
    std::printf("watch them: build/divcoll demo%s%s --out %s --movie (MP4 with ffmpeg)\n", a.run.empty() ? "" : " --run ",
                a.run.c_str(), a.out.c_str());
  }
  return 0;
}

// every built-in environment: its scalar fields (sim::kEnvironmentFields) and its terrain
int envs() {
  std::printf("%-12s", "name");
  for (const sim::EnvironmentField& f : sim::kEnvironmentFields) std::printf(" %*s", std::max<int>(7, std::strlen(f.name)), f.name);
  std::printf("  %s\n", "terrain (dx, y, slope) from x_f");
  for (const auto& t : config::builtin_environments()) {
    const auto& e = t.physics;
    std::string ter;
    for (const auto& s : t.relative) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "(%g, %g, %g) ", s.x_start, s.y_start, s.slope);
      ter += buf;
    }
    std::printf("%-12s", e.name.c_str());
    for (const sim::EnvironmentField& f : sim::kEnvironmentFields)
      std::printf(" %*.3g", std::max<int>(7, std::strlen(f.name)), e.*(f.field));
    std::printf("  %s\n", ter.empty() ? "flat" : ter.c_str());
  }
  return 0;
}

}  // namespace divcoll::cli
