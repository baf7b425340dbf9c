#include "sim/model.hpp"

#include <cmath>

#include "common/dmath.hpp"

namespace divcoll::sim {

void Model::compile(const Scene& s, int n_substeps) {
  scene = &s;
  N = s.n_masses();
  S = s.n_springs();
  A = s.n_agents();
  C = s.n_connectors();
  K = static_cast<int>(s.env.terrain.size());
  substeps = n_substeps;
  dt = s.constants.dt;
  h = dt / substeps;
  decay = dmath::exp(-s.env.damping * h);

  seg_x.resize(K);
  seg_y.resize(K);
  seg_s.resize(K);
  for (int k = 0; k < K; ++k) {
    seg_x[k] = s.env.terrain[k].x_start;
    seg_y[k] = s.env.terrain[k].y_start;
    seg_s[k] = s.env.terrain[k].slope;
  }
  has_walls = K > 1;
  has_wind = s.env.wind_amp != 0;
  has_adhesion = s.env.adhesion != 0;
  has_belt = s.env.belt_speed != 0;
  has_dashpots = false;
  for (double c : s.damping) has_dashpots = has_dashpots || c != 0;
  has_connectors = C > 0;

  inv_mass.resize(N);
  spring_scratch.resize(4 * static_cast<size_t>(S));
  for (int i = 0; i < N; ++i) inv_mass[i] = 1.0 / s.mass[i];

  agent_layout = nn::agent_layout(agent_input_size(s.constants));
  const bool joint = joint_connector_params(s.connector_params.size());
  conn_layout = joint ? nn::joint_connector_layout() : nn::connector_layout();
  conn_cols = joint ? C : kConnectorSprings * C;
  agent_params = agent_layout.param_count();
  conn_params = conn_layout.param_count();
  agent_packed_count = nn::packed_count(agent_layout);
  agent_packed.resize(static_cast<size_t>(A) * agent_packed_count);
  for (int a = 0; a < A; ++a)
    nn::pack(agent_layout, &s.agent_params[static_cast<size_t>(a) * agent_params],
             &agent_packed[static_cast<size_t>(a) * agent_packed_count]);
  conn_packed.resize(C > 0 ? nn::packed_count(conn_layout) : 0);
  if (C > 0) nn::pack(conn_layout, s.connector_params.data(), conn_packed.data());

  // the sine table holds for these constants only
  const Constants& k = s.constants;
  if (k.omega != sine_omega_ || k.dt != sine_dt_ || k.n_sines != sine_n_) sine_steps = 0;

  // distinct anchors of each connector, in order of first appearance (i then j, spring by spring)
  conn_anchor_start.assign(1, 0);
  conn_anchor.clear();
  for (int c = 0; c < C; ++c) {
    const int first = conn_anchor_start.back();
    for (int r = 0; r < kConnectorSprings; ++r) {
      const int sp = s.connector_spring_index[c * kConnectorSprings + r];
      for (int end : {s.spring_i[sp], s.spring_j[sp]}) {
        bool seen = false;
        for (int q = first; q < static_cast<int>(conn_anchor.size()); ++q) seen = seen || conn_anchor[q] == end;
        if (!seen) conn_anchor.push_back(end);
      }
    }
    conn_anchor_start.push_back(static_cast<int32_t>(conn_anchor.size()));
  }
}

void Model::pack_float() {
  const Scene& s = *scene;
  agent_packed_count_f = nn::packed_count<float>(agent_layout);
  agent_packed_f.resize(static_cast<size_t>(A) * agent_packed_count_f);
  for (int a = 0; a < A; ++a)
    nn::pack(agent_layout, &s.agent_params[static_cast<size_t>(a) * agent_params],
             &agent_packed_f[static_cast<size_t>(a) * agent_packed_count_f]);
  conn_packed_f.resize(C > 0 ? nn::packed_count<float>(conn_layout) : 0);
  if (C > 0) nn::pack(conn_layout, s.connector_params.data(), conn_packed_f.data());
}

void Model::prepare_sines(int steps) {
  if (steps <= sine_steps) return;
  const Constants& k = scene->constants;
  sine_omega_ = k.omega;
  sine_dt_ = k.dt;
  sine_n_ = k.n_sines;
  sines.resize(static_cast<size_t>(steps) * k.n_sines);
  // the expression of control_forward's fallback, term for term: the same bits
  for (int t = sine_steps; t < steps; ++t)
    for (int j = 0; j < k.n_sines; ++j)
      sines[static_cast<size_t>(t) * k.n_sines + j] = dmath::sin(k.omega * t * k.dt + 2.0 * M_PI * j / k.n_sines);
  sine_steps = steps;
}

}  // namespace divcoll::sim
