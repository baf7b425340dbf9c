#include "collective/tether_effect.hpp"

#include <limits>

namespace divcoll::collective {

TetherEffect tether_effect(sim::Simulator& sim, const Agent& posterior, const Agent& anterior,
                           const std::vector<double>& params, const Tether& tether, const std::string& env,
                           const sim::RunPhysics& physics, int steps) {
  const sim::Scene s = pair_scene(posterior, anterior, params, tether, env, physics.contact);
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  opt.record = true;
  opt.record_tether = true;
  const sim::RunResult r = sim.run(s, opt);
  TetherEffect e;
  e.status = r.status;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (r.status != sim::Status::ok) {
    e.pair_travel_bl = e.force_time = nan;
    e.travel_bl = e.impulse_x = e.work = {nan, nan};
    return e;
  }
  const double bl[2] = {body_length(posterior), body_length(anterior)};
  e.pair_travel_bl = r.travel / (0.5 * (bl[0] + bl[1]));
  // each agent's centre of mass (mean x of its masses, as travel itself: SPEC §1) at T against step 0
  const int N = s.n_masses();
  std::vector<int> owner(N, -1);
  for (int q = 0; q < 2; ++q) {
    double x0 = 0, x1 = 0;
    for (int k = 0; k < sim::kAgentMasses; ++k) {
      const int i = s.agent_mass_index[q * sim::kAgentMasses + k];
      owner[i] = q;
      x0 += r.x[2 * i];
      x1 += r.x[(static_cast<size_t>(steps) * N + i) * 2];
    }
    e.travel_bl[q] = (x1 - x0) / sim::kAgentMasses / bl[q];
  }
  for (size_t c = 0; c < s.connector_spring_index.size(); ++c) {
    const int sp = s.connector_spring_index[c];
    const double* row = &r.tether[c * sim::kTetherColumns];
    const int i = owner[s.spring_i[sp]], j = owner[s.spring_j[sp]];
    e.impulse_x[i] += row[0];
    e.impulse_x[j] -= row[0];
    e.work[i] += row[2];
    e.work[j] += row[3];
    e.force_time += row[4];
  }
  return e;
}

}  // namespace divcoll::collective
