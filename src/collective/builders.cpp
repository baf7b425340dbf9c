#include "collective/builders.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/check.hpp"
#include "config/environments.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"

namespace divcoll::collective {
namespace {

double min_x(const Agent& a) {
  double m = a.rest_pos[0];
  for (int q = 0; q < sim::kAgentMasses; ++q) m = std::min(m, a.rest_pos[2 * q]);
  return m;
}
double max_x(const Agent& a) {
  double m = a.rest_pos[0];
  for (int q = 0; q < sim::kAgentMasses; ++q) m = std::max(m, a.rest_pos[2 * q]);
  return m;
}
double min_y(const Agent& a) {
  double m = a.rest_pos[1];
  for (int q = 0; q < sim::kAgentMasses; ++q) m = std::min(m, a.rest_pos[2 * q + 1]);
  return m;
}

// appends an agent's masses, springs and controller, its rest positions shifted so that min x = x_left and
// the lowest mass sits at y = 0
void append_agent(sim::Scene& s, const Agent& a, double x_left) {
  DIVCOLL_THROW_UNLESS(a.rest_pos.size() == 2 * sim::kAgentMasses && a.spring_i.size() == sim::kAgentSprings,
                       "an agent needs 11 rest positions and 21 springs");
  const int base = s.n_masses();
  const double dx = x_left - min_x(a), dy = -min_y(a);
  for (int q = 0; q < sim::kAgentMasses; ++q) {
    s.x0.push_back(a.rest_pos[2 * q] + dx);
    s.x0.push_back(a.rest_pos[2 * q + 1] + dy);
    s.mass.push_back(1.0);
    s.agent_mass_index.push_back(base + q);
  }
  for (int r = 0; r < sim::kAgentSprings; ++r) {
    s.agent_spring_index.push_back(s.n_springs());
    s.spring_i.push_back(base + a.spring_i[r]);
    s.spring_j.push_back(base + a.spring_j[r]);
    s.rest_length.push_back(a.rest_length[r]);
    s.stiffness.push_back(morph::kAgentStiffness);
    s.amplitude.push_back(a.amplitude[r]);
    s.damping.push_back(morph::kAgentDashpot);
  }
  s.agent_params.insert(s.agent_params.end(), a.params.begin(), a.params.end());
}

// one connector between posterior agent p and anterior agent q (scene agent indices), SPEC §6.2
void append_connector(sim::Scene& s, int p, int q, const Anchors& P, const Anchors& A, const Tether& t) {
  DIVCOLL_THROW_UNLESS(P.front_foot >= 0 && P.front_upper >= 0 && P.back_upper >= 0 && A.back_foot >= 0 &&
                           A.back_upper >= 0,
                       "connector agents have no anchors (run compute_anchors first)");
  const int bp = s.agent_mass_index[p * sim::kAgentMasses], bq = s.agent_mass_index[q * sim::kAgentMasses];
  const int ends[5][2] = {{P.front_foot, A.back_foot},
                          {P.front_upper, A.back_upper},
                          {P.front_foot, A.back_upper},
                          {P.front_upper, A.back_foot},
                          {P.back_upper, A.back_upper}};
  for (const auto& e : ends) {
    const int i = bp + e[0], j = bq + e[1];
    const double dx = s.x0[2 * i] - s.x0[2 * j], dy = s.x0[2 * i + 1] - s.x0[2 * j + 1];
    s.connector_spring_index.push_back(s.n_springs());
    s.spring_i.push_back(i);
    s.spring_j.push_back(j);
    s.rest_length.push_back(std::sqrt(dx * dx + dy * dy));
    s.stiffness.push_back(t.stiffness);
    s.amplitude.push_back(t.amplitude);
    s.damping.push_back(t.damping);
  }
}

void place_env(sim::Scene& s, const std::string& env, sim::ContactLaw law, double feature_offset = 0) {
  double mx = s.x0[0];
  for (int i = 0; i < s.n_masses(); ++i) mx = std::max(mx, s.x0[2 * i]);
  s.env = config::place_environment(config::environment_table(env), feature_offset == 0 ? mx : mx + feature_offset, law);
}

}  // namespace

Agent random_agent(Rng& rng, const sim::Constants& c) {
  const uint32_t cells = morph::random_body(rng);
  const uint32_t springs = morph::random_springs(rng);
  return make_agent(cells, springs, rng, c);
}

Agent make_agent(uint32_t cells, uint32_t springs, Rng& rng, const sim::Constants& c) {
  Agent a = morph::agent_geometry(cells, springs);
  a.params = morph::init_agent_params(rng, sim::agent_input_size(c));
  return a;
}

sim::Scene agent_scene(const Agent& a, const std::string& env, sim::ContactLaw law, const sim::Constants& c,
                       double feature_offset) {
  sim::Scene s;
  s.constants = c;
  append_agent(s, a, 0.0);
  place_env(s, env, law, feature_offset);
  return s;
}

Anchors compute_anchors(const Agent& a, const sim::RunPhysics& physics, const sim::Constants& c, int steps) {
  const sim::Scene s = agent_scene(a, "flat", physics.contact, c);
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  opt.record = true;
  const sim::RunResult r = sim::simulate(s, opt);
  constexpr int M = sim::kAgentMasses;
  // contact counts and variance of (x − COM) over the run (the part that finished, if it failed)
  const int T = r.status == sim::Status::ok ? steps : std::max(r.bad_step - 1, 0);
  std::vector<int> contacts(M, 0);
  std::vector<double> mean(2 * M, 0.0), sq(2 * M, 0.0);
  for (int t = 1; t <= T; ++t) {
    const double* x = &r.x[static_cast<size_t>(t) * 2 * M];
    double cx = 0, cy = 0;
    for (int q = 0; q < M; ++q) cx += x[2 * q], cy += x[2 * q + 1];
    cx /= M, cy /= M;
    for (int q = 0; q < M; ++q) {
      contacts[q] += r.touch[static_cast<size_t>(t) * M + q];
      const double rx = x[2 * q] - cx, ry = x[2 * q + 1] - cy;
      mean[2 * q] += rx, mean[2 * q + 1] += ry;
      sq[2 * q] += rx * rx, sq[2 * q + 1] += ry * ry;
    }
  }
  std::vector<double> var(M, 0.0);
  for (int q = 0; q < M && T > 0; ++q)
    for (int d = 0; d < 2; ++d) {
      const double mu = mean[2 * q + d] / T;
      var[q] += sq[2 * q + d] / T - mu * mu;
    }

  // back masses: rest x below the rest centre of mass
  double com = 0;
  for (int q = 0; q < M; ++q) com += a.rest_pos[2 * q];
  com /= M;
  std::vector<int> back, front;
  for (int q = 0; q < M; ++q) (a.rest_pos[2 * q] < com ? back : front).push_back(q);
  // median rest y (the 6th of 11)
  std::vector<double> ys(M);
  for (int q = 0; q < M; ++q) ys[q] = a.rest_pos[2 * q + 1];
  std::nth_element(ys.begin(), ys.begin() + M / 2, ys.end());
  const double median_y = ys[M / 2];

  // feet: most contact steps; ties: lowest rest y, then lowest index
  auto foot = [&](const std::vector<int>& side) {
    int best = -1;
    for (int q : side) {
      if (best < 0 || contacts[q] > contacts[best] ||
          (contacts[q] == contacts[best] && a.rest_pos[2 * q + 1] < a.rest_pos[2 * best + 1]))
        best = q;
    }
    return best;
  };
  // upper: least variance among upper candidates that are not the foot; else among the whole side
  auto upper = [&](const std::vector<int>& side, int ft) {
    int best = -1;
    for (int pass = 0; pass < 2 && best < 0; ++pass)
      for (int q : side) {
        if (q == ft || (pass == 0 && a.rest_pos[2 * q + 1] < median_y)) continue;
        if (best < 0 || var[q] < var[best]) best = q;
      }
    return best;
  };
  Anchors an;
  DIVCOLL_DEMAND(!back.empty() && !front.empty());
  an.back_foot = foot(back);
  an.front_foot = foot(front);
  an.back_upper = upper(back, an.back_foot);
  an.front_upper = upper(front, an.front_foot);
  // a side of one mass has no separate upper mass: it uses the foot
  if (an.back_upper < 0) an.back_upper = an.back_foot;
  if (an.front_upper < 0) an.front_upper = an.front_foot;
  return an;
}

sim::Scene pair_scene(const Agent& P, const Agent& A, const std::vector<double>& conn, const Tether& tether,
                      const std::string& env, sim::ContactLaw law, const sim::Constants& c) {
  sim::Scene s;
  s.constants = c;
  append_agent(s, P, 0.0);
  append_agent(s, A, (max_x(P) - min_x(P)) + kAgentGap);
  append_connector(s, 0, 1, P.anchors, A.anchors, tether);
  s.connector_params = conn;
  place_env(s, env, law);
  return s;
}

sim::Scene chain_scene(const std::vector<const Agent*>& agents, const std::vector<double>& conn,
                       const Tether& tether, const std::string& env, sim::ContactLaw law, const sim::Constants& c) {
  const int n = static_cast<int>(agents.size());
  DIVCOLL_THROW_UNLESS(n >= 2, "a chain needs at least 2 agents (got " << n << ")");
  // x of each agent's left edge: agent 0 at 0, child k right edge at its parent's left edge − kAgentGap
  std::vector<double> left(n, 0.0);
  for (int k = 1; k < n; ++k) {
    const int parent = (k - 1) / 2;
    const double width = max_x(*agents[k]) - min_x(*agents[k]);
    left[k] = left[parent] - kAgentGap - width;
  }
  const double shift = -*std::min_element(left.begin(), left.end());
  sim::Scene s;
  s.constants = c;
  for (int k = 0; k < n; ++k) append_agent(s, *agents[k], left[k] + shift);
  for (int k = 1; k < n; ++k) append_connector(s, k, (k - 1) / 2, agents[k]->anchors, agents[(k - 1) / 2]->anchors,
                                               tether);
  s.connector_params = conn;
  place_env(s, env, law);
  return s;
}

}  // namespace divcoll::collective
