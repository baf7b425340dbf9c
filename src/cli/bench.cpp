// divcoll bench: throughput of the engine (steps per CPU-second of one core) and speed against error.
// Prints markdown tables; it is a benchmark, not a test: nothing here passes or fails.
//
// Time is the calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID), not the wall clock: on a machine shared with
// other work the wall clock counts the time the thread waited for a core, its CPU time does not, so the figures
// hold on a loaded machine. (They still move a little with load: a busy sibling hyperthread or cache slows the
// thread itself. Compare two builds by ratios of runs made in turn.)
#include <cmath>
#include <cstdio>
#include <ctime>
#include <vector>

#include "common/version.hpp"
#include "cli/commands.hpp"
#include "collective/builders.hpp"
#include "collective/deploy_variants.hpp"
#include "io/pipeline.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"

namespace divcoll::cli {
namespace {

// CPU seconds of the calling thread
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Fixture {
  std::vector<collective::Agent> agents;
  std::vector<double> conn;
  collective::Tether tether;  // of the weak connector, from the config
};

Fixture make_fixture(int n_agents, uint64_t seed) {
  Fixture f;
  Rng rng(seed_for(seed, 99, 0));
  for (int q = 0; q < n_agents; ++q) {
    f.agents.push_back(collective::random_agent(rng));
    f.agents.back().anchors = collective::compute_anchors(f.agents.back(), {}, 300);
  }
  f.conn = morph::init_connector_params(rng);
  return f;
}

// scene b of a batch of the given kind: agents drawn round-robin from the fixture
sim::Scene make_scene(const Fixture& f, const std::string& kind, int b, const sim::Constants& c = {}) {
  const int n = static_cast<int>(f.agents.size());
  if (kind == "agent") return collective::agent_scene(f.agents[b % n], "flat", c);
  if (kind == "pair")
    return collective::pair_scene(f.agents[b % n], f.agents[(b + 1) % n], f.conn, f.tether, "flat", c);
  std::vector<const collective::Agent*> chain;
  for (int q = 0; q < 20; ++q) chain.push_back(&f.agents[(b + q) % n]);
  return collective::chain_scene(chain, f.conn, f.tether, "flat", c);
}

// runs batches until `seconds` of the thread's CPU time have passed; returns scene-steps per CPU-second
// agent_param_grad: with grad, also the gradient of the agents' weights (agent training wants it, connector
// training does not: its agents are frozen)
double time_batch(sim::Simulator& sim, const std::vector<sim::Scene>& batch, int steps, bool grad, double seconds,
                  bool agent_param_grad = true) {
  sim::RunOptions opt;
  opt.steps = steps;
  opt.grad = grad;
  opt.agent_param_grad = agent_param_grad;
  sim.run_batch({batch.front()}, opt);  // warm up: size the workspace
  long done = 0;
  const double t0 = thread_cpu_seconds();
  double el = 0;
  do {
    sim.run_batch(batch, opt);
    done += static_cast<long>(batch.size()) * steps;
    el = thread_cpu_seconds() - t0;
  } while (el < seconds);
  return done / el;
}

}  // namespace

int bench(const BenchArgs& a) {
  std::printf("# divcoll bench (one core, double precision, version %s %s)\n\n", DIVCOLL_VERSION,
              divcoll::git_commit());
  Fixture f = make_fixture(24, 7);
  f.tether = collective::strength_tether(a.config.empty() ? io::default_config() : io::load_config(a.config), "weak");

  // ---- throughput --------------------------------------------------------------------------------
  std::printf("## Throughput: scene-steps per CPU-second of one core (the thread's CPU time, not wall time)\n\n");
  std::printf("forward+backward computes the gradient blocks its training asks for: an agent's every block, a pair's\n"
              "or chain's all but the frozen agents' weights (as connector training does); the last column asks for\n"
              "every block of every scene.\n\n");
  std::printf("| scene | masses | batch | steps/episode | forward | forward+backward | fwd+bwd µs/step | fwd+bwd, every block |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  struct Row {
    const char* kind;
    int steps;
  };
  const Row rows[] = {{"agent", 1000}, {"pair", 1000}, {"chain20", 200}};
  for (const Row& r : rows) {
    for (int batch : {1, 100}) {
      if (a.quick && batch == 100 && std::string(r.kind) == "chain20") continue;
      std::vector<sim::Scene> scenes;
      for (int b = 0; b < batch; ++b) scenes.push_back(make_scene(f, r.kind, b));
      sim::Simulator sim;
      const double fwd = time_batch(sim, scenes, r.steps, false, a.seconds);
      const bool agent = std::string(r.kind) == "agent";
      const double bwd = time_batch(sim, scenes, r.steps, true, a.seconds, agent);
      const double all = agent ? bwd : time_batch(sim, scenes, r.steps, true, a.seconds, true);
      std::printf("| %s | %d | %d | %d | %.0f | %.0f | %.1f | %.0f |\n", r.kind, scenes[0].n_masses(), batch, r.steps,
                  fwd, bwd, 1e6 / bwd, all);
      std::fflush(stdout);
    }
  }

  // ---- speed against error -----------------------------------------------------------------------
  // the same pair for 1 s of simulated time at several Δt; α is rescaled to keep the actuation filter's
  // time constant (α(Δt) = 1 − (1 − α)^(Δt/0.004)); error = largest position deviation at t = 1 s
  // against a reference at Δt = 0.000125 s (the smallest Δt / 8)
  std::printf("\n## Speed against error: one pair, 1 s of simulated time, flat ground\n\n");
  std::printf("| Δt (s) | substeps | steps | pair-steps per CPU-s (fwd) | simulated s per CPU-s | max position error (u) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  auto constants_for = [](double dt) {
    sim::Constants c;
    c.dt = dt;
    c.agent_alpha = 1.0 - std::pow(1.0 - 0.15, dt / 0.004);
    c.conn_alpha = 1.0 - std::pow(1.0 - 0.1, dt / 0.004);
    return c;
  };
  auto final_x = [&](double dt) {
    const sim::Scene s = make_scene(f, "pair", 0, constants_for(dt));
    sim::RunOptions opt;
    opt.steps = static_cast<int>(std::lround(1.0 / dt));
    opt.record = true;
    const sim::RunResult r = sim::simulate(s, opt);
    return std::vector<double>(r.x.end() - 2 * s.n_masses(), r.x.end());
  };
  const std::vector<double> ref = final_x(0.000125);
  for (double dt : {0.001, 0.002, 0.004, 0.008}) {
    const sim::Scene s = make_scene(f, "pair", 0, constants_for(dt));
    const std::vector<double> x = final_x(dt);
    double err = 0;
    for (size_t q = 0; q < x.size(); ++q) err = std::max(err, std::abs(x[q] - ref[q]));
    sim::Simulator sim;
    const int steps = static_cast<int>(std::lround(1.0 / dt));
    const double sps = time_batch(sim, {s}, steps, false, a.seconds);
    std::printf("| %.3f | %d | %d | %.0f | %.1f | %.2e |\n", dt, sim::substeps_needed(s), steps, sps, sps * dt, err);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace divcoll::cli
