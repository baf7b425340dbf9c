// divcoll simulate, scene, demo, envs
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "cli/commands.hpp"
#include "collective/builders.hpp"
#include "common/check.hpp"
#include "io/environments.hpp"
#include "io/pipeline.hpp"
#include "io/scene_file.hpp"
#include "io/trajectory_file.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"

namespace divcoll::cli {

void check_output_path(const std::string& path, bool force) {
  namespace fs = std::filesystem;
  DIVCOLL_THROW_UNLESS(!path.empty(), "no output path given");
  if (fs::exists(path) && !force)
    throw InputError(msg() << path << " exists; pass --force to overwrite it");
  const fs::path parent = fs::absolute(path).parent_path();
  DIVCOLL_THROW_UNLESS(fs::is_directory(parent), "output folder " << parent.string() << " does not exist");
}

int simulate(const SimulateArgs& a) {
  check_output_path(a.out, a.force);
  const sim::Scene scene = io::read_scene(a.scene);
  sim::RunOptions opt;
  opt.steps = a.steps;
  opt.grad = a.grad;
  opt.record = true;
  const sim::RunResult r = sim::simulate(scene, opt);

  io::Trajectory t;
  t.steps = a.steps;
  t.n_masses = scene.n_masses();
  t.n_agents = scene.n_agents();
  t.x = r.x;
  t.v = r.v;
  t.touch = r.touch;
  t.travel = r.travel;
  t.status = sim::status_name(r.status);
  t.has_grad = a.grad;
  if (a.grad) {
    t.grad_agent_params = r.grad_agent_params;
    t.grad_connector_params = r.grad_connector_params;
    t.grad_x0 = r.grad_x0;
    t.grad_rest_length = r.grad_rest_length;
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
  io::environment_table(a.env);  // refuses an unknown name before any work
  DIVCOLL_THROW_UNLESS(a.kind == "agent" || a.kind == "pair" || a.kind == "chain",
                       "--kind must be agent, pair or chain (got '" << a.kind << "')");
  const double k = io::strength_stiffness(a.config.empty() ? io::default_config() : io::load_config(a.config),
                                         a.connector);
  const int n = a.kind == "agent" ? 1 : a.kind == "pair" ? 2 : a.agents;
  DIVCOLL_THROW_UNLESS(a.kind != "chain" || (a.agents >= 2 && a.agents <= 1000),
                       "--agents for a chain must lie in [2, 1000] (got " << a.agents << ")");
  // agents are random until the agents stage provides trained ones
  Rng rng(seed_for(a.seed, 0, 0));
  std::vector<collective::Agent> agents;
  for (int q = 0; q < (a.uniform ? 1 : n); ++q) {
    agents.push_back(collective::random_agent(rng));
    if (n > 1) agents.back().anchors = collective::compute_anchors(agents.back());
  }
  const std::vector<double> conn = morph::init_connector_params(rng);
  sim::Scene s;
  if (a.kind == "agent") {
    s = collective::agent_scene(agents[0], a.env);
  } else {
    std::vector<const collective::Agent*> ptr;
    for (int q = 0; q < n; ++q) ptr.push_back(&agents[a.uniform ? 0 : q]);
    s = a.kind == "pair" ? collective::pair_scene(*ptr[0], *ptr[1], conn, k, a.env)
                         : collective::chain_scene(ptr, conn, k, a.env);
  }
  io::write_scene(a.out, s, a.force);
  std::printf("%s: %s of %d agent(s) in %s, %d masses, %d springs, %d connector(s), %d substep(s)\n",
              a.out.c_str(), a.kind.c_str(), s.n_agents(), a.env.c_str(), s.n_masses(), s.n_springs(),
              s.n_connectors(), sim::substeps_needed(s));
  return 0;
}

int demo(const DemoArgs& a) {
  namespace fs = std::filesystem;
  fs::create_directories(a.out);
  io::environment_table(a.env);
  Rng rng(seed_for(a.seed, 0, 0));
  collective::Agent P = collective::random_agent(rng), A = collective::random_agent(rng);
  P.anchors = collective::compute_anchors(P);
  A.anchors = collective::compute_anchors(A);
  const std::vector<double> conn = morph::init_connector_params(rng);
  std::printf("demo: two random agents (untrained until the agents stage lands) joined by a weak connector\n");
  std::printf("%-12s %10s %10s %10s  %s\n", "environment", "travel_u", "travel_BL", "status", "scene file");
  for (const std::string& env : {std::string("flat"), a.env}) {
    const sim::Scene s = collective::pair_scene(P, A, conn, collective::kWeakConnector, env);
    const std::string path = (fs::path(a.out) / ("pair_" + env + ".h5")).string();
    io::write_scene(path, s, /*overwrite=*/true);  // the demo folder is scratch: rerunning replaces it
    sim::RunOptions opt;
    opt.steps = a.steps;
    const sim::RunResult r = sim::simulate(s, opt);
    std::printf("%-12s %10.4f %10.4f %10s  %s\n", env.c_str(), r.travel, r.travel / sim::mean_body_length(s),
                sim::status_name(r.status), path.c_str());
  }
  std::printf("simulate a scene file yourself: build/divcoll simulate --scene %s/pair_flat.h5 --steps 1000 "
              "--out %s/traj_flat.h5 --grad --force\n",
              a.out.c_str(), a.out.c_str());
  return 0;
}

int envs() {
  std::printf("%-12s %7s %7s %7s %7s %7s %7s %7s %7s  %s\n", "name", "gravity", "damping", "mu", "kappa_t",
              "belt", "wind", "adhes.", "band", "terrain (dx, y, slope) from x_f");
  for (const auto& t : io::builtin_environments()) {
    const auto& e = t.physics;
    std::string ter;
    for (const auto& s : t.relative) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "(%g, %g, %g) ", s.x_start, s.y_start, s.slope);
      ter += buf;
    }
    std::printf("%-12s %7.3g %7.3g %7.3g %7.3g %7.3g %7.3g %7.3g %7.3g  %s\n", e.name.c_str(), e.gravity, e.damping,
                e.friction, e.tangent_keep, e.belt_speed, e.wind_amp, e.adhesion, e.adhesion_band,
                ter.empty() ? "flat" : ter.c_str());
  }
  return 0;
}

}  // namespace divcoll::cli
