// stage: the controllers (SPEC §2.1, §4.3, §6.3) and their adjoint
//
// agents: 54 inputs (10 sines, then per mass (x − c)κ_a and v κ_a), one network per agent, o ← α y + (1−α) o
// connectors: 11 inputs per spring, one weight set for all 5·C connector springs (a single GEMM); or, with the
// joint network (Model::conn_cols = C), the same 11·5 inputs of a connector as one column of a 55 → 32 → 32 → 5 net
// T: the networks' scalar (stages.hpp). The inputs are computed in double and stored as T; the outputs are read
// as T and enter o in double. With T = double this is the spec's step, operation for operation.
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "common/dmath.hpp"
#include "sim/stages.hpp"

namespace divcoll::sim {

template <class T>
void control_forward(const Model& m, int t, const double* x, const double* v, const uint8_t* tau, double* o,
                     const ControlBuffers<T>& buf) {
  const Scene& sc = *m.scene;
  const Constants& k = sc.constants;
  const int na = m.agent_layout.activation_count();
  const int n_in = m.agent_layout.in();
  const double ka = k.agent_kappa;

  // agents
  for (int a = 0; a < m.A; ++a) {
    T* act = buf.agent_acts + static_cast<size_t>(a) * na;
    const int32_t* mi = &sc.agent_mass_index[a * kAgentMasses];
    // the sines are the same for every agent: computed for the first, copied to the others
    if (a == 0 && t < m.sine_steps)
      std::copy(&m.sines[static_cast<size_t>(t) * k.n_sines], &m.sines[static_cast<size_t>(t + 1) * k.n_sines], act);
    else if (a == 0)
      for (int j = 0; j < k.n_sines; ++j) act[j] = dmath::sin(k.omega * t * k.dt + 2.0 * M_PI * j / k.n_sines);
    else
      std::copy(buf.agent_acts, buf.agent_acts + k.n_sines, act);
    double cx = 0, cy = 0;
    for (int q = 0; q < kAgentMasses; ++q) {
      cx += x[2 * mi[q]];
      cy += x[2 * mi[q] + 1];
    }
    cx /= kAgentMasses;
    cy /= kAgentMasses;
    T* in = act + k.n_sines;
    for (int q = 0; q < kAgentMasses; ++q) {
      in[4 * q + 0] = (x[2 * mi[q]] - cx) * ka;
      in[4 * q + 1] = (x[2 * mi[q] + 1] - cy) * ka;
      in[4 * q + 2] = v[2 * mi[q]] * ka;
      in[4 * q + 3] = v[2 * mi[q] + 1] * ka;
    }
    (void)n_in;
  }
  // every agent's network in one call: two agents' layers at a time, each filling the other's latency
  if (m.A > 0)
    nn::forward_packed_nets(m.agent_layout, m.agent_packed_for<T>(), m.agent_packed_count_for<T>(), m.A, buf.agent_acts);
  for (int a = 0; a < m.A; ++a) {
    const T* y = buf.agent_acts + static_cast<size_t>(a) * na + m.agent_layout.activation_offset(m.agent_layout.n_layers());
    const int32_t* si = &sc.agent_spring_index[a * kAgentSprings];
    for (int r = 0; r < kAgentSprings; ++r) o[si[r]] = k.agent_alpha * y[r] + (1.0 - k.agent_alpha) * o[si[r]];
  }

  // connectors
  if (!m.has_connectors) return;
  const int cols = kConnectorSprings * m.C;
  const double kx = k.conn_kappa_x, kv = k.conn_kappa_v;
  const double eps2 = k.eps_len * k.eps_len;
  T* in = buf.conn_acts;  // input block: 11 × cols, column-major
  for (int c = 0; c < m.C; ++c) {
    double mx = 0, my = 0;
    const int a0 = m.conn_anchor_start[c], a1 = m.conn_anchor_start[c + 1];
    for (int q = a0; q < a1; ++q) {
      mx += x[2 * m.conn_anchor[q]];
      my += x[2 * m.conn_anchor[q] + 1];
    }
    mx /= (a1 - a0);
    my /= (a1 - a0);
    for (int r = 0; r < kConnectorSprings; ++r) {
      const int s = sc.connector_spring_index[c * kConnectorSprings + r];
      const int i = sc.spring_i[s], j = sc.spring_j[s];
      T* col = in + static_cast<size_t>(c * kConnectorSprings + r) * kConnectorInputs;
      const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
      col[0] = (x[2 * i] - mx) * kx;
      col[1] = (x[2 * i + 1] - my) * kx;
      col[2] = (x[2 * j] - mx) * kx;
      col[3] = (x[2 * j + 1] - my) * kx;
      col[4] = v[2 * i] * kv;
      col[5] = v[2 * i + 1] * kv;
      col[6] = v[2 * j] * kv;
      col[7] = v[2 * j + 1] * kv;
      col[8] = tau[i];
      col[9] = tau[j];
      col[10] = std::sqrt(dx * dx + dy * dy + eps2) / sc.rest_length[s];
    }
  }
  nn::forward_packed(m.conn_layout, m.conn_packed_for<T>(), m.conn_cols, buf.conn_acts);
  const T* y =
      buf.conn_acts + static_cast<size_t>(m.conn_layout.activation_offset(m.conn_layout.n_layers())) * m.conn_cols;
  for (int c = 0; c < cols; ++c) {
    const int s = sc.connector_spring_index[c];
    o[s] = k.conn_alpha * y[c] + (1.0 - k.conn_alpha) * o[s];
  }
}

size_t control_scratch_count(const Model& m) {
  const size_t cols = static_cast<size_t>(m.conn_cols);
  const size_t agent = m.agent_layout.in() + m.agent_layout.scratch_count();
  const size_t conn = cols * (m.conn_layout.out() + m.conn_layout.in() + m.conn_layout.scratch_count());
  return std::max(agent, conn);
}

template <class T>
void control_adjoint(const Model& m, int /*t*/, const double* x, const double* v, const ControlBuffers<T>& buf,
                     double* ob, double* xb, double* vb, double* Lb, T* g_agent, T* g_conn, T* scratch) {
  const Scene& sc = *m.scene;
  const Constants& k = sc.constants;
  const int na = m.agent_layout.activation_count();
  const double ka = k.agent_kappa;
  const double alpha = k.agent_alpha;

  // agents
  for (int a = 0; a < m.A; ++a) {
    const T* act = buf.agent_acts + static_cast<size_t>(a) * na;
    const int32_t* mi = &sc.agent_mass_index[a * kAgentMasses];
    const int32_t* si = &sc.agent_spring_index[a * kAgentSprings];
    // o' = α y + (1 − α) o
    T yb[kAgentSprings];
    for (int r = 0; r < kAgentSprings; ++r) {
      yb[r] = alpha * ob[si[r]];
      ob[si[r]] *= (1.0 - alpha);
    }
    T* in_grad = scratch;
    T* nn_scratch = scratch + m.agent_layout.in();
    nn::backward_packed(m.agent_layout, m.agent_packed_for<T>() + static_cast<size_t>(a) * m.agent_packed_count_for<T>(), 1,
                        act, yb, g_agent ? g_agent + static_cast<size_t>(a) * m.agent_params : nullptr, in_grad, nn_scratch);
    // inputs (x − c) κ and v κ, c = mean of the agent's masses
    const T* g = in_grad + k.n_sines;
    double cbx = 0, cby = 0;
    for (int q = 0; q < kAgentMasses; ++q) {
      xb[2 * mi[q]] += ka * g[4 * q + 0];
      xb[2 * mi[q] + 1] += ka * g[4 * q + 1];
      vb[2 * mi[q]] += ka * g[4 * q + 2];
      vb[2 * mi[q] + 1] += ka * g[4 * q + 3];
      cbx -= ka * g[4 * q + 0];
      cby -= ka * g[4 * q + 1];
    }
    for (int q = 0; q < kAgentMasses; ++q) {
      xb[2 * mi[q]] += cbx / kAgentMasses;
      xb[2 * mi[q] + 1] += cby / kAgentMasses;
    }
  }

  // connectors
  if (!m.has_connectors) return;
  const int cols = kConnectorSprings * m.C;
  const double kx = k.conn_kappa_x, kv = k.conn_kappa_v;
  const double eps2 = k.eps_len * k.eps_len;
  const double ac = k.conn_alpha;
  T* yb = scratch;                                  // 1 × cols (5 × C joint: the same values)
  T* in_grad = scratch + cols;                      // 11 × cols (55 × C joint)
  T* nn_scratch = in_grad + static_cast<size_t>(kConnectorInputs) * cols;
  for (int c = 0; c < cols; ++c) {
    const int s = sc.connector_spring_index[c];
    yb[c] = ac * ob[s];
    ob[s] *= (1.0 - ac);
  }
  nn::backward_packed(m.conn_layout, m.conn_packed_for<T>(), m.conn_cols, buf.conn_acts, yb, g_conn, in_grad, nn_scratch);
  for (int c = 0; c < m.C; ++c) {
    double mbx = 0, mby = 0;
    for (int r = 0; r < kConnectorSprings; ++r) {
      const int s = sc.connector_spring_index[c * kConnectorSprings + r];
      const int i = sc.spring_i[s], j = sc.spring_j[s];
      const T* g = in_grad + static_cast<size_t>(c * kConnectorSprings + r) * kConnectorInputs;
      xb[2 * i] += kx * g[0];
      xb[2 * i + 1] += kx * g[1];
      xb[2 * j] += kx * g[2];
      xb[2 * j + 1] += kx * g[3];
      mbx -= kx * (g[0] + g[2]);
      mby -= kx * (g[1] + g[3]);
      vb[2 * i] += kv * g[4];
      vb[2 * i + 1] += kv * g[5];
      vb[2 * j] += kv * g[6];
      vb[2 * j + 1] += kv * g[7];
      // ℓ / L
      const double L = sc.rest_length[s];
      const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
      const double l = std::sqrt(dx * dx + dy * dy + eps2);
      const double lb = g[10] / L;
      Lb[s] -= g[10] * l / (L * L);
      xb[2 * i] += lb * dx / l;
      xb[2 * i + 1] += lb * dy / l;
      xb[2 * j] -= lb * dx / l;
      xb[2 * j + 1] -= lb * dy / l;
    }
    const int a0 = m.conn_anchor_start[c], a1 = m.conn_anchor_start[c + 1];
    for (int q = a0; q < a1; ++q) {
      xb[2 * m.conn_anchor[q]] += mbx / (a1 - a0);
      xb[2 * m.conn_anchor[q] + 1] += mby / (a1 - a0);
    }
  }
  (void)v;
}

#define DIVCOLL_CONTROL_INSTANTIATE(T)                                                                            \
  template void control_forward<T>(const Model&, int, const double*, const double*, const uint8_t*, double*,      \
                                   const ControlBuffers<T>&);                                                     \
  template void control_adjoint<T>(const Model&, int, const double*, const double*, const ControlBuffers<T>&,     \
                                   double*, double*, double*, double*, T*, T*, T*);
DIVCOLL_CONTROL_INSTANTIATE(double)
DIVCOLL_CONTROL_INSTANTIATE(float)
#undef DIVCOLL_CONTROL_INSTANTIATE

}  // namespace divcoll::sim
