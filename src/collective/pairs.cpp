#include "collective/pairs.hpp"

#include <cmath>
#include <limits>

#include "common/check.hpp"

namespace divcoll::collective {

std::vector<std::pair<int, int>> uniform_pairs(int n) {
  std::vector<std::pair<int, int>> p;
  for (int i = 0; i < n; ++i) p.emplace_back(i, i);
  return p;
}

std::vector<std::pair<int, int>> random_pairs(Rng& rng, int population, int n) {
  DIVCOLL_THROW_UNLESS(population >= 2, "diverse pairs need at least 2 agents");
  std::vector<std::pair<int, int>> p;
  for (int q = 0; q < n; ++q) {
    const int a = static_cast<int>(uniform_int(rng, population));
    int b = static_cast<int>(uniform_int(rng, population - 1));
    if (b >= a) ++b;  // a different agent
    p.emplace_back(a, b);
  }
  return p;
}

PairOutcome run_pair(sim::Simulator& sim, const Agent& P, const Agent& A, const std::vector<double>& params,
                     const Tether& tether, const std::string& env, const sim::RunPhysics& physics, int steps,
                     bool grad) {
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  opt.grad = grad;
  opt.agent_param_grad = false;  // only the connector gradient is returned: the agents stay frozen
  return run_pair(sim, P, A, params, tether, env, physics.contact, opt, nullptr);
}

PairOutcome run_pair(sim::Simulator& sim, const Agent& P, const Agent& A, const std::vector<double>& params,
                     const Tether& tether, const std::string& env, sim::ContactLaw law, const sim::RunOptions& opt,
                     sim::RunResult* full) {
  const sim::Scene s = pair_scene(P, A, params, tether, env, law);
  sim::RunResult r = sim.run(s, opt);
  PairOutcome o;
  o.status = r.status;
  o.travel_u = r.travel;
  o.travel_bl = r.travel / (0.5 * (body_length(P) + body_length(A)));
  if (opt.grad) o.grad = std::move(r.grad_connector_params);
  o.redone_in_double = r.redone_in_double;
  if (full) *full = std::move(r);
  return o;
}

PairOutcome run_chain(sim::Simulator& sim, const std::vector<const Agent*>& agents, const std::vector<double>& params,
                      const Tether& tether, const std::string& env, const sim::RunPhysics& physics, int steps) {
  const sim::Scene s = chain_scene(agents, params, tether, env, physics.contact);
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  const sim::RunResult r = sim.run(s, opt);
  double bl = 0;
  for (const Agent* a : agents) bl += body_length(*a);
  PairOutcome o;
  o.status = r.status;
  o.travel_u = r.travel;
  o.travel_bl = r.travel / (bl / static_cast<double>(agents.size()));
  return o;
}

PairOutcome run_alone(sim::Simulator& sim, const Agent& a, const std::string& env, const sim::RunPhysics& physics,
                      int steps) {
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  return run_alone(sim, a, env, physics.contact, opt, nullptr);
}

PairOutcome run_alone(sim::Simulator& sim, const Agent& a, const std::string& env, sim::ContactLaw law,
                      const sim::RunOptions& opt, sim::RunResult* full, double feature_offset) {
  const sim::Scene s = agent_scene(a, env, law, {}, feature_offset);
  sim::RunResult r = sim.run(s, opt);
  PairOutcome o;
  o.status = r.status;
  o.travel_u = r.travel;
  o.travel_bl = r.travel / body_length(a);
  if (full) *full = std::move(r);
  return o;
}

}  // namespace divcoll::collective
