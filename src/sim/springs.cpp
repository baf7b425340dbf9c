// stage: spring forces (SPEC §2.2) and their adjoint
#include <cmath>

#include "sim/stages.hpp"

namespace divcoll::sim {

void springs_forward(const Model& m, const double* x, const double* v, const double* o, double* F) {
  const Scene& sc = *m.scene;
  const double eps2 = sc.constants.eps_len * sc.constants.eps_len;
  // the scene's arrays in locals: F may not alias them, so nothing is reloaded inside the loop
  const int32_t* __restrict si = sc.spring_i.data();
  const int32_t* __restrict sj = sc.spring_j.data();
  const double* __restrict rest = sc.rest_length.data();
  const double* __restrict amp = sc.amplitude.data();
  const double* __restrict stiff = sc.stiffness.data();
  const double* __restrict damp = sc.damping.data();
  const bool dashpots = m.has_dashpots;
  const int S = m.S;
  for (int q = 0; q < 2 * m.N; ++q) F[q] = 0;
  for (int s = 0; s < S; ++s) {
    const int i = si[s], j = sj[s];
    // d = x_i − x_j, ℓ = sqrt(d·d + ε²), d̂ = d/ℓ
    const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
    const double l = std::sqrt(dx * dx + dy * dy + eps2);
    const double ux = dx / l, uy = dy / l;
    // f = −k (ℓ − L (1 + a o)) d̂ − c ((v_i − v_j)·d̂) d̂
    const double e = l - rest[s] * (1.0 + amp[s] * o[s]);
    double mag = -stiff[s] * e;
    if (dashpots) {
      const double w = (v[2 * i] - v[2 * j]) * ux + (v[2 * i + 1] - v[2 * j + 1]) * uy;
      mag -= damp[s] * w;
    }
    const double fx = mag * ux, fy = mag * uy;
    F[2 * i] += fx;
    F[2 * i + 1] += fy;
    F[2 * j] -= fx;
    F[2 * j + 1] -= fy;
  }
}

void springs_adjoint(const Model& m, const double* x, const double* v, const double* o, const double* Fb,
                     double* xb, double* vb, double* ob, double* Lb) {
  const Scene& sc = *m.scene;
  const double eps2 = sc.constants.eps_len * sc.constants.eps_len;
  for (int s = 0; s < m.S; ++s) {
    const int i = sc.spring_i[s], j = sc.spring_j[s];
    const double fbx = Fb[2 * i] - Fb[2 * j], fby = Fb[2 * i + 1] - Fb[2 * j + 1];
    // recompute the forward quantities
    const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
    const double l = std::sqrt(dx * dx + dy * dy + eps2);
    const double ux = dx / l, uy = dy / l;
    const double L = sc.rest_length[s], a = sc.amplitude[s], k = sc.stiffness[s];
    const double e = l - L * (1.0 + a * o[s]);
    double mag = -k * e;
    const double fu = fbx * ux + fby * uy;  // f̄·d̂
    double ubx = 0, uby = 0;                // gradient w.r.t. d̂
    if (m.has_dashpots) {
      const double c = sc.damping[s];
      const double dvx = v[2 * i] - v[2 * j], dvy = v[2 * i + 1] - v[2 * j + 1];
      const double w = dvx * ux + dvy * uy;
      mag -= c * w;
      const double wb = -c * fu;
      ubx += wb * dvx;
      uby += wb * dvy;
      vb[2 * i] += wb * ux;
      vb[2 * i + 1] += wb * uy;
      vb[2 * j] -= wb * ux;
      vb[2 * j + 1] -= wb * uy;
    }
    ubx += mag * fbx;
    uby += mag * fby;
    // e = ℓ − L (1 + a o)
    const double eb = -k * fu;
    Lb[s] -= eb * (1.0 + a * o[s]);
    ob[s] -= eb * L * a;
    // d̂ = d/ℓ and ℓ = sqrt(d·d + ε²): d̄ = (ū − d̂ (d̂·ū))/ℓ + ℓ̄ d̂
    const double uu = ubx * ux + uby * uy;
    const double dbx = (ubx - ux * uu) / l + eb * ux;
    const double dby = (uby - uy * uu) / l + eb * uy;
    xb[2 * i] += dbx;
    xb[2 * i + 1] += dby;
    xb[2 * j] -= dbx;
    xb[2 * j + 1] -= dby;
  }
}

}  // namespace divcoll::sim
