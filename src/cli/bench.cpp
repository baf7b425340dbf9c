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

#include "analysis/pacmap.hpp"
#include "common/rng.hpp"
#include "common/version.hpp"
#include "cli/commands.hpp"
#include "collective/builders.hpp"
#include "collective/deploy_variants.hpp"
#include "config/pipeline.hpp"
#include "morph/body.hpp"
#include "nn/kernel_path.hpp"
#include "nn/mlp.hpp"
#include "sim/engine.hpp"

namespace divcoll::cli {
namespace {

// CPU seconds of the calling thread
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// the benchmark times the spec's step: Coulomb contact (its scenes and the anchors' runs), the networks in double
// unless a row says float
constexpr sim::RunPhysics kSpecPhysics{};

struct Fixture {
  std::vector<morph::Agent> agents;
  std::vector<double> conn;
  collective::Tether tether;  // of the weak connector, from the config
};

Fixture make_fixture(int n_agents, uint64_t seed) {
  Fixture f;
  Rng rng(seed_for(seed, 99, 0));
  for (int q = 0; q < n_agents; ++q) {
    f.agents.push_back(collective::random_agent(rng));
    f.agents.back().anchors = collective::compute_anchors(f.agents.back(), kSpecPhysics, {}, 300);
  }
  f.conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
  return f;
}

// scene b of a batch of the given kind: agents drawn round-robin from the fixture
sim::Scene make_scene(const Fixture& f, const std::string& kind, int b, const sim::Constants& c = {}) {
  const int n = static_cast<int>(f.agents.size());
  if (kind == "agent") return collective::agent_scene(f.agents[b % n], "flat", kSpecPhysics.contact, c);
  if (kind == "pair")
    return collective::pair_scene(f.agents[b % n], f.agents[(b + 1) % n], f.conn, f.tether, "flat", kSpecPhysics.contact, c);
  std::vector<const morph::Agent*> chain;
  for (int q = 0; q < 20; ++q) chain.push_back(&f.agents[(b + q) % n]);
  return collective::chain_scene(chain, f.conn, f.tether, "flat", kSpecPhysics.contact, c);
}

// runs batches until `seconds` of the thread's CPU time have passed; returns scene-steps per CPU-second
// agent_param_grad: with grad, also the gradient of the agents' weights (agent training wants it, connector
// training does not: its agents are frozen)
// float_networks: the networks in float (RunOptions::float_networks)
double time_batch(sim::Simulator& sim, const std::vector<sim::Scene>& batch, int steps, bool grad, double seconds,
                  bool agent_param_grad = true, bool float_networks = false) {
  sim::RunOptions opt;
  opt.steps = steps;
  opt.grad = grad;
  opt.agent_param_grad = agent_param_grad;
  opt.float_networks = float_networks;
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

// the controllers' networks of one pair-step, alone (SPEC §4.3, §6.3): two agents' networks (54 → 32 → 32 → 21,
// one column each) and the connector's (11 → 32 → 32 → 1, 5 columns); backward as connector training asks:
// input gradients of the agents' networks, input and weight gradients of the connector's. In T = double (the
// engine) or float (the kernels' second instantiation), on the same weights and inputs.
template <class T>
struct PairNets {
  nn::Layout La = nn::agent_layout(54), Lc = nn::connector_layout();
  int npa = nn::packed_count<T>(La), na = La.activation_count(), nc = Lc.activation_count();
  std::vector<T> pa, pc, acts_a, acts_c, yb_a, yb_c, g_conn, gin_a, gin_c, scratch;
  PairNets(const std::vector<double>& agent_params, const std::vector<double>& conn_params, uint64_t seed) {
    pa.resize(2 * static_cast<size_t>(npa));
    for (int g = 0; g < 2; ++g) nn::pack(La, agent_params.data() + static_cast<size_t>(g) * La.param_count(), pa.data() + g * npa);
    pc.resize(nn::packed_count<T>(Lc));
    nn::pack(Lc, conn_params.data(), pc.data());
    Rng rng(seed_for(seed, 98, 0));
    acts_a.assign(2 * static_cast<size_t>(na), T(0));
    acts_c.assign(5 * static_cast<size_t>(nc), T(0));
    for (int g = 0; g < 2; ++g)
      for (int i = 0; i < 54; ++i) acts_a[static_cast<size_t>(g) * na + i] = static_cast<T>(2 * uniform01(rng) - 1);
    for (int i = 0; i < 5 * 11; ++i) acts_c[i] = static_cast<T>(2 * uniform01(rng) - 1);
    yb_a.assign(21, T(0.1));
    yb_c.assign(5, T(0.1));
    g_conn.assign(Lc.param_count(), T(0));
    gin_a.resize(54);
    gin_c.resize(5 * 11);
    scratch.resize(std::max(La.scratch_count(), 5 * Lc.scratch_count()));
  }
  void forward() {
    nn::forward_packed_nets(La, pa.data(), npa, 2, acts_a.data());
    nn::forward_packed(Lc, pc.data(), 5, acts_c.data());
  }
  void backward() {
    for (int g = 0; g < 2; ++g)
      nn::backward_packed(La, pa.data() + g * npa, 1, acts_a.data() + static_cast<size_t>(g) * na, yb_a.data(), static_cast<T*>(nullptr),
                          gin_a.data(), scratch.data());
    nn::backward_packed(Lc, pc.data(), 5, acts_c.data(), yb_c.data(), g_conn.data(), gin_c.data(), scratch.data());
  }
  // pair-steps of network work per CPU-second
  double rate(bool with_backward, double seconds) {
    long done = 0;
    const double t0 = thread_cpu_seconds();
    double el = 0;
    do {
      for (int q = 0; q < 1000; ++q) {
        forward();
        if (with_backward) backward();
      }
      done += 1000;
      el = thread_cpu_seconds() - t0;
    } while (el < seconds);
    return done / el;
  }
};

}  // namespace

// the CPU cost of one PaCMAP fit (the analysis stage's familiarity, ANALYSIS.md §1) by its number of states: 32-D
// states (a connector's hidden layer) uniform in [-1, 1], the analysis stage's options
int bench_pacmap(const std::vector<int>& sizes) {
  std::printf("# divcoll bench --pacmap (one core, version %s %s)\n\n", DIVCOLL_VERSION, divcoll::git_commit());
  std::printf("| states in the fit | CPU seconds | µs per state | CPU s / n² × 1e9 |\n|---|---|---|---|\n");
  for (int n : sizes) {
    Rng rng(static_cast<uint64_t>(n));
    std::vector<double> X(static_cast<size_t>(n) * 32);
    for (double& x : X) x = 2.0 * uniform01(rng) - 1.0;
    const double t0 = thread_cpu_seconds();
    const std::vector<double> Y = analysis::pacmap_fit(X.data(), n, 32);
    const double s = thread_cpu_seconds() - t0;
    std::printf("| %d | %.2f | %.1f | %.2f |\n", n, s, 1e6 * s / n, 1e9 * s / (static_cast<double>(n) * n));
    std::fflush(stdout);
    if (Y.empty()) return 1;
  }
  return 0;
}

int bench(const BenchArgs& a) {
  if (!a.pacmap.empty()) return bench_pacmap(a.pacmap);
  std::printf("# divcoll bench (one core, double precision, version %s %s; kernels %s on %s, built for %s)\n\n",
              DIVCOLL_VERSION, divcoll::git_commit(), nn::kernel_path_name(nn::kernel_path()),
              nn::cpu_description().c_str(), divcoll::build_target());
  Fixture f = make_fixture(24, 7);
  f.tether = collective::strength_tether((a.config.empty() ? config::default_config() : config::load_config(a.config)).connectors, "weak");

  // ---- throughput --------------------------------------------------------------------------------
  std::printf("## Throughput: scene-steps per CPU-second of one core (the thread's CPU time, not wall time)\n\n");
  std::printf("forward+backward computes the gradient blocks its training asks for: an agent's every block, a pair's\n"
              "or chain's all but the frozen agents' weights (as connector training does); the last column asks for\n"
              "every block of every scene.\n\n");
  std::printf("The float columns run the same scenes with the controllers' networks in float and the physics in\n"
              "double (RunOptions::float_networks; not the spec's double precision: see the table further down).\n\n");
  std::printf("| scene | masses | batch | steps/episode | forward | forward+backward | fwd+bwd µs/step | fwd+bwd, every block | forward, float networks | fwd+bwd, float networks |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  struct Row {
    const char* kind;
    int steps;
  };
  const Row rows[] = {{"agent", 1000}, {"pair", 1000}, {"chain20", 200}};
  double pair_fwd = 0, pair_bwd = 0;  // the pair at batch 100, for the networks' table below
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
      const double fwd_f = time_batch(sim, scenes, r.steps, false, a.seconds, true, true);
      const double bwd_f = time_batch(sim, scenes, r.steps, true, a.seconds, agent, true);
      std::printf("| %s | %d | %d | %d | %.0f | %.0f | %.1f | %.0f | %.0f (x%.2f) | %.0f (x%.2f) |\n", r.kind,
                  scenes[0].n_masses(), batch, r.steps, fwd, bwd, 1e6 / bwd, all, fwd_f, fwd_f / fwd, bwd_f, bwd_f / bwd);
      if (std::string(r.kind) == "pair" && batch == 100) pair_fwd = fwd, pair_bwd = bwd;
      std::fflush(stdout);
    }
  }

  // ---- the networks alone, double against float ----------------------------------------------------
  // what a float path could gain where most of a pair's time goes: the same networks in the kernels' two
  // instantiations, and how far float's outputs and gradients are from double's
  {
    std::printf("\n## The controllers' networks of one pair-step alone: double against float (kernels only; the engine is double)\n\n");
    Rng rng(seed_for(7, 97, 0));
    std::vector<double> agent_params(2 * static_cast<size_t>(nn::agent_layout(54).param_count()));
    for (double& w : agent_params) w = 0.3 * normal(rng);
    PairNets<double> d(agent_params, f.conn, 7);
    PairNets<float> s(agent_params, f.conn, 7);
    d.forward(), s.forward(), d.backward(), s.backward();
    auto max_dev = [](const auto& x, const auto& y) {
      double m = 0, scale = 0;
      for (size_t q = 0; q < x.size(); ++q) m = std::max(m, std::abs(static_cast<double>(x[q]) - static_cast<double>(y[q]))), scale = std::max(scale, std::abs(static_cast<double>(x[q])));
      return scale > 0 ? m / scale : m;
    };
    const double dev_out = std::max(max_dev(d.acts_a, s.acts_a), max_dev(d.acts_c, s.acts_c));
    const double dev_grad = std::max(max_dev(d.g_conn, s.g_conn), std::max(max_dev(d.gin_a, s.gin_a), max_dev(d.gin_c, s.gin_c)));
    const double fd = d.rate(false, a.seconds), ff = s.rate(false, a.seconds);
    const double bd = d.rate(true, a.seconds), bf = s.rate(true, a.seconds);
    std::printf("| networks of a pair-step | double: pair-steps per CPU-s | float | float / double | largest deviation of float, relative to the largest value |\n");
    std::printf("|---|---|---|---|---|\n");
    std::printf("| forward | %.0f | %.0f | %.2f | activations %.1e |\n", fd, ff, ff / fd, dev_out);
    std::printf("| forward+backward (connector training's blocks) | %.0f | %.0f | %.2f | gradients %.1e |\n", bd, bf, bf / bd, dev_grad);
    // a model, not a measurement: the step's time less the networks' double time plus their float time
    auto projected = [](double pair, double dbl, double flt) { return 1.0 / (1.0 / pair - 1.0 / dbl + 1.0 / flt); };
    std::printf("\nThe networks are %.0f%% of a pair's forward step and %.0f%% of its forward+backward (the throughput\n"
                "table's pair at batch 100). A model, not a measurement: with the networks in float and the rest of the\n"
                "step unchanged, a pair would run %.0f forward (x%.2f) and %.0f forward+backward (x%.2f) pair-steps per\n"
                "CPU-second.\n",
                100 * pair_fwd / fd, 100 * pair_bwd / bd, projected(pair_fwd, fd, ff), projected(pair_fwd, fd, ff) / pair_fwd,
                projected(pair_bwd, bd, bf), projected(pair_bwd, bd, bf) / pair_bwd);
    std::fflush(stdout);
  }

  // ---- speed against error -----------------------------------------------------------------------
  // the same pair for 1 s of simulated time at several Δt; α is rescaled to keep the actuation filter's
  // time constant (α(Δt) = 1 − (1 − α)^(Δt/0.004)); error = largest position deviation at t = 1 s
  // against a reference at Δt = 0.000125 s (the smallest Δt / 8)
  std::printf("\n## Speed against error: one pair, 1 s of simulated time, flat ground\n\n");
  std::printf("The last row runs Δt = 0.004 s with the networks in float (run.precision = float_networks); its error is\n"
              "against the same reference, beside the double row above it.\n\n");
  std::printf("| Δt (s) | substeps | steps | pair-steps per CPU-s (fwd) | simulated s per CPU-s | max position error (u) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  auto constants_for = [](double dt) {
    sim::Constants c;
    c.dt = dt;
    c.agent_alpha = 1.0 - std::pow(1.0 - 0.15, dt / 0.004);
    c.conn_alpha = 1.0 - std::pow(1.0 - 0.1, dt / 0.004);
    return c;
  };
  auto final_x = [&](double dt, bool float_networks = false) {
    const sim::Scene s = make_scene(f, "pair", 0, constants_for(dt));
    sim::RunOptions opt;
    opt.steps = static_cast<int>(std::lround(1.0 / dt));
    opt.record = true;
    opt.float_networks = float_networks;
    const sim::RunResult r = sim::simulate(s, opt);
    return std::vector<double>(r.x.end() - 2 * s.n_masses(), r.x.end());
  };
  const std::vector<double> ref = final_x(0.000125);
  for (const auto& [dt, fl] : {std::pair{0.001, false}, {0.002, false}, {0.004, false}, {0.008, false}, {0.004, true}}) {
    const sim::Scene s = make_scene(f, "pair", 0, constants_for(dt));
    const std::vector<double> x = final_x(dt, fl);
    double err = 0;
    for (size_t q = 0; q < x.size(); ++q) err = std::max(err, std::abs(x[q] - ref[q]));
    sim::Simulator sim;
    const int steps = static_cast<int>(std::lround(1.0 / dt));
    const double sps = time_batch(sim, {s}, steps, false, a.seconds, true, fl);
    std::printf("| %.3f%s | %d | %d | %.0f | %.1f | %.2e |\n", dt, fl ? ", float networks" : "", sim::substeps_needed(s),
                steps, sps, sps * dt, err);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace divcoll::cli
