// divcoll grad-diag: is the backpropagated gradient of a connector's batch objective (mean pair travel over a
// fixed batch, on a run file's trained agents) the slope of that objective, and at what scale? For each
// horizon: the batch travel, the gradient's norm, how consistent it is across pairs, and, along the gradient and
// along random directions, central finite differences of the batch objective at several perturbation sizes
// against the gradient's directional derivative.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "cli/commands.hpp"
#include "evo/connector_opt.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/references.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"
#include "config/config.hpp"
#include "io/h5.hpp"
#include "morph/body.hpp"
#include "config/pipeline.hpp"
#include "io/run_read.hpp"

namespace divcoll::cli {
namespace {

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t q = 0; q < a.size(); ++q) s += a[q] * b[q];
  return s;
}
double norm(const std::vector<double>& a) { return std::sqrt(dot(a, a)); }
double cosine(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = norm(a) * norm(b);
  return n > 0 ? dot(a, b) / n : NAN;
}
std::vector<double> axpy(const std::vector<double>& x, double h, const std::vector<double>& d) {
  std::vector<double> y = x;
  for (size_t q = 0; q < y.size(); ++q) y[q] += h * d[q];
  return y;
}

template <class T>
std::vector<T> parse_list(const std::string& text, const char* flag) {
  std::vector<T> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::stringstream is(item);
    T v{};
    DIVCOLL_THROW_UNLESS(is >> v && is.eof(), flag << ": '" << item << "' is not a number");
    out.push_back(v);
  }
  DIVCOLL_THROW_UNLESS(!out.empty(), flag << " is empty");
  return out;
}

}  // namespace

RunAgents load_run_agents(const std::string& run, const std::vector<std::string>& overrides) {
  io::h5::quiet_errors();
  const io::h5::File f = io::h5::File::open(run);
  DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run",
                       run << " is not a divcoll run file");
  DIVCOLL_THROW_UNLESS(f.has("agents/final"), run << " has no final agent population (run the agents stage)");
  RunAgents ra{config::apply_overrides(config::parse_config(f.read_string("config"), run + " (stored config)"), overrides), {}, {}};
  ra.physics.contact = config::run_physics(ra.cfg).contact;  // the run's scenes under the run's contact law
  for (const auto& x : io::read_final_population(f)) ra.agents.push_back(x.agent);
  for (auto& ag : ra.agents) ag.anchors = collective::compute_anchors(ag, ra.physics);
  return ra;
}

int grad_diag(const GradDiagArgs& a) {
  const RunAgents ra = load_run_agents(a.run, a.overrides);
  const config::RunConfig& cfg = ra.cfg;
  const std::vector<morph::Agent>& agents = ra.agents;
  const auto kinds = config::connector_kind_names();
  int kind = -1;
  for (size_t k = 0; k < kinds.size(); ++k)
    if (kinds[k] == a.kind) kind = static_cast<int>(k);
  DIVCOLL_THROW_UNLESS(kind >= 0, "--kind must be one of weak_uniform, weak_diverse, strong_uniform, strong_diverse");
  const std::vector<int> horizons = parse_list<int>(a.horizons, "--horizons");
  const std::vector<double> scales = parse_list<double>(a.scales, "--scales");
  for (int h : horizons) DIVCOLL_THROW_UNLESS(h >= 1, "--horizons: every horizon must be at least 1 step");
  for (double s : scales) DIVCOLL_THROW_UNLESS(s > 0, "--scales: every scale must be positive");

  const int pop = static_cast<int>(agents.size());
  const auto& C = cfg.connectors;
  const bool diverse = config::connector_kind(a.kind).diverse;
  const collective::Tether k = collective::tether(C, a.kind);
  DIVCOLL_THROW_UNLESS(diverse || a.pairs <= pop, "--pairs " << a.pairs << " is more than the population (" << pop << ")");
  // the stage's replicate 0 of this kind: its initial weights and its first batch
  const uint64_t stream = config::stage_stream("connectors") + static_cast<uint64_t>(kind) * C.replicates;
  Rng wr = make_rng(cfg.run.seed, stream, config::kItemInitialWeights);
  std::vector<double> theta = collective::initial_connector_params(C, k.amplitude, wr);
  std::vector<std::pair<int, int>> batch;
  if (diverse) {
    Rng br = make_rng(cfg.run.seed, stream, 0);
    batch = collective::random_pairs(br, pop, a.pairs);
  } else {
    batch = collective::uniform_pairs(a.pairs);
  }
  sim::Simulator sim;
  if (a.train_iterations > 0) {
    // first train with the run's (or the overridden) connector settings, as the stage would
    evo::PlainTrainSpec ts{k, ra.physics, diverse, a.train_iterations, a.pairs, C.episode_steps, 0, cfg.run.seed,
                                  stream};
    const auto tr = evo::train_plain(sim, agents, evo::opt_settings(C), theta, ts);
    theta = tr.params;
    std::printf("trained %d iterations (%s, lr %g): batch travel %.3f -> %.3f BL\n\n", a.train_iterations,
                C.optimizer.c_str(), C.lr, tr.curve_bl.front(), tr.curve_bl.back());
  }
  const double theta_norm = norm(theta);
  std::printf("# gradient diagnosis: %s, %d pairs, stiffness %g, amplitude %g, |theta| = %.4g, seed %llu\n\n", a.kind.c_str(),
              a.pairs, k.stiffness, k.amplitude, theta_norm, static_cast<unsigned long long>(cfg.run.seed));
  std::printf("J = mean pair travel over the batch (u; BL in brackets); g = its backpropagated gradient. Central\n"
              "finite differences (J(θ+hd) − J(θ−hd))/2h at h = scale·|θ| against g·d, as the ratio FD / BPTT\n"
              "(1 = the gradient is the slope at that scale). Along ĝ the last column block is the change\n"
              "J(θ+hĝ) − J(θ) of a step of length h along the gradient (u; > 0 = uphill).\n\n");

  auto J = [&](const std::vector<double>& w, int steps) {
    return evo::run_probe(sim, agents, batch, w, false, k, ra.physics, steps, 0).travel_u;
  };
  for (int T : horizons) {
    // per-pair gradients: their norms and the agreement of the batch's two halves
    sim::RunOptions opt = ra.physics.options();
    opt.steps = T;
    opt.grad = true;
    opt.agent_param_grad = false;
    evo::ProbeSum all, h1, h2;
    std::vector<double> pair_norms;
    for (size_t p = 0; p < batch.size(); ++p) {
      const collective::PairOutcome o =
          collective::run_pair(sim, agents[batch[p].first], agents[batch[p].second], theta, k, "flat", ra.physics.contact, opt, nullptr);
      all.add(o);
      (2 * p < batch.size() ? h1 : h2).add(o);
      if (o.status == sim::Status::ok) pair_norms.push_back(norm(o.grad));
    }
    const evo::ProbeResult r = all.mean();
    DIVCOLL_THROW_UNLESS(r.ok > 0, "every pair of the batch failed at horizon " << T);
    std::sort(pair_norms.begin(), pair_norms.end());
    const std::vector<double>& g = r.grad;
    const double gn = norm(g);
    std::printf("## horizon %d steps: J = %.5g u (%.3f BL), %d/%d pairs ok\n\n", T, r.travel_u, r.travel_bl, r.ok,
                r.ok + r.not_ok);
    std::printf("|g| = %.4g; per-pair |g|: median %.4g, max %.4g; cos(g of first half, g of second half) = %.3f\n",
                gn, pair_norms[pair_norms.size() / 2], pair_norms.back(), cosine(h1.mean().grad, h2.mean().grad));
    if (a.window > 0 && a.window < T) {
      const auto tr = evo::run_probe(sim, agents, batch, theta, true, k, ra.physics, T, a.window);
      std::printf("truncated backpropagation, window %d: |g_W| = %.4g, cos(g_W, g) = %.3f\n", a.window, norm(tr.grad),
                  cosine(tr.grad, g));
    }
    std::printf("\n| direction | g·d |");
    for (double s : scales) std::printf(" FD/BPTT @%g |", s);
    std::printf(" ΔJ along ĝ @ each scale |\n|---|---|");
    for (size_t i = 0; i <= scales.size(); ++i) std::printf("---|");
    std::printf("\n");
    const double J0 = r.travel_u;
    for (int d = 0; d <= a.directions; ++d) {
      std::vector<double> dir(theta.size());
      if (d == 0) {
        for (size_t q = 0; q < dir.size(); ++q) dir[q] = g[q] / gn;
      } else {
        Rng rr = make_rng(cfg.run.seed, 9000 + static_cast<uint64_t>(T), static_cast<uint64_t>(d));
        for (double& x : dir) x = normal(rr);
        const double n = norm(dir);
        for (double& x : dir) x /= n;
      }
      const double slope = dot(g, dir);
      std::printf("| %s | %.4g |", d == 0 ? "ĝ" : ("random " + std::to_string(d)).c_str(), slope);
      std::string steps_up;
      for (double s : scales) {
        const double h = s * theta_norm;
        const double jp = J(axpy(theta, h, dir), T), jm = J(axpy(theta, -h, dir), T);
        std::printf(" %.3g |", (jp - jm) / (2 * h) / slope);
        if (d == 0) {
          char buf[64];
          std::snprintf(buf, sizeof buf, "%s%+.2e", steps_up.empty() ? "" : " ", jp - J0);
          steps_up += buf;
        }
      }
      std::printf(" %s |\n", d == 0 ? steps_up.c_str() : "");
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace divcoll::cli
