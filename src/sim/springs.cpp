// stage: spring forces (SPEC §2.2) and their adjoint
//
// Each stage runs in two loops: the per-spring arithmetic (gathers, a square root and a division per spring:
// vectorised by the compiler, AVX-512 gathers on this machine), then the scatter of each spring's share into its
// two masses in spring order, as one loop did before: the same operations on every value and the same order of
// every sum, so the same bits.
#include <cmath>

#include "sim/engine.hpp"
#include "sim/stages.hpp"

namespace divcoll::sim {

namespace {
// the scene's spring arrays in a local: the outputs may not alias them, so nothing is reloaded inside the loops
struct SpringArrays {
  const int32_t *si, *sj;
  const double *rest, *amp, *stiff, *damp;
  double eps2;
  int S;
  explicit SpringArrays(const Model& m)
      : si(m.scene->spring_i.data()), sj(m.scene->spring_j.data()), rest(m.scene->rest_length.data()),
        amp(m.scene->amplitude.data()), stiff(m.scene->stiffness.data()), damp(m.scene->damping.data()),
        eps2(m.scene->constants.eps_len * m.scene->constants.eps_len), S(m.S) {}
};

// each spring's share (ax, ay) added to its mass i and subtracted from its mass j, in spring order
void scatter(const SpringArrays& d, const double* __restrict ax, const double* __restrict ay, double* __restrict out) {
  for (int s = 0; s < d.S; ++s) {
    const int i = d.si[s], j = d.sj[s];
    out[2 * i] += ax[s];
    out[2 * i + 1] += ay[s];
    out[2 * j] -= ax[s];
    out[2 * j + 1] -= ay[s];
  }
}

// the per-spring force f = −k (ℓ − L (1 + a o)) d̂ − c ((v_i − v_j)·d̂) d̂ into fx, fy
template <bool DASHPOTS>
void spring_forces(const Model& m, const double* __restrict x, const double* __restrict v, const double* __restrict o,
                   double* __restrict fx, double* __restrict fy) {
  const SpringArrays d(m);
  for (int s = 0; s < d.S; ++s) {
    const int i = d.si[s], j = d.sj[s];
    // d = x_i − x_j, ℓ = sqrt(d·d + ε²), d̂ = d/ℓ
    const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
    const double l = std::sqrt(dx * dx + dy * dy + d.eps2);
    const double ux = dx / l, uy = dy / l;
    const double e = l - d.rest[s] * (1.0 + d.amp[s] * o[s]);
    double mag = -d.stiff[s] * e;
    if constexpr (DASHPOTS) {
      const double w = (v[2 * i] - v[2 * j]) * ux + (v[2 * i + 1] - v[2 * j + 1]) * uy;
      mag -= d.damp[s] * w;
    }
    fx[s] = mag * ux;
    fy[s] = mag * uy;
  }
}
}  // namespace

void springs_forward(const Model& m, const double* x, const double* v, const double* o, double* F) {
  const int S = m.S;
  double* __restrict fx = m.spring_scratch.data();
  double* __restrict fy = fx + S;
  if (m.has_dashpots)
    spring_forces<true>(m, x, v, o, fx, fy);
  else
    spring_forces<false>(m, x, v, o, fx, fy);
  for (int q = 0; q < 2 * m.N; ++q) F[q] = 0;
  scatter(SpringArrays(m), fx, fy, F);
}

void tether_accumulate(const Model& m, const double* x0, const double* v0, const double* x1, double* tether) {
  const double* fx = m.spring_scratch.data();
  const double* fy = fx + m.S;
  const int32_t* si = m.scene->spring_i.data();
  const int32_t* sj = m.scene->spring_j.data();
  const std::vector<int32_t>& springs = m.scene->connector_spring_index;
  // a mass's path over the substep, the mean of h·v (its start) and Δx (its end): the work of a force held over the
  // substep on either alone is off by the same O(h²) per substep in opposite directions, which over an episode adds
  // up to the size of what a tether exchanges
  auto path = [&](int q, int axis) { return 0.5 * (m.h * v0[2 * q + axis] + (x1[2 * q + axis] - x0[2 * q + axis])); };
  for (size_t c = 0; c < springs.size(); ++c) {
    const int s = springs[c], i = si[s], j = sj[s];
    double* row = tether + c * kTetherColumns;
    row[0] += fx[s] * m.h;
    row[1] += fy[s] * m.h;
    row[2] += fx[s] * path(i, 0) + fy[s] * path(i, 1);
    row[3] -= fx[s] * path(j, 0) + fy[s] * path(j, 1);
    row[4] += std::sqrt(fx[s] * fx[s] + fy[s] * fy[s]) * m.h;
  }
}

namespace {
// the per-spring part of the adjoint: each spring's d̄ (dbx, dby) and, with dashpots, its v̄ share (wbx, wby);
// L̄ and ō of the spring itself are updated here (one spring each)
template <bool DASHPOTS>
void spring_adjoints(const Model& m, const double* __restrict x, const double* __restrict v,
                     const double* __restrict o, const double* __restrict Fb, double* __restrict ob,
                     double* __restrict Lb, double* __restrict dbxs, double* __restrict dbys,
                     double* __restrict wbxs, double* __restrict wbys) {
  const SpringArrays d(m);
  for (int s = 0; s < d.S; ++s) {
    const int i = d.si[s], j = d.sj[s];
    const double fbx = Fb[2 * i] - Fb[2 * j], fby = Fb[2 * i + 1] - Fb[2 * j + 1];
    // recompute the forward quantities
    const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
    const double l = std::sqrt(dx * dx + dy * dy + d.eps2);
    const double ux = dx / l, uy = dy / l;
    const double L = d.rest[s], a = d.amp[s], k = d.stiff[s];
    const double e = l - L * (1.0 + a * o[s]);
    double mag = -k * e;
    const double fu = fbx * ux + fby * uy;  // f̄·d̂
    double ubx = 0, uby = 0;                // gradient w.r.t. d̂
    if constexpr (DASHPOTS) {
      const double c = d.damp[s];
      const double dvx = v[2 * i] - v[2 * j], dvy = v[2 * i + 1] - v[2 * j + 1];
      const double w = dvx * ux + dvy * uy;
      mag -= c * w;
      const double wb = -c * fu;
      ubx += wb * dvx;
      uby += wb * dvy;
      wbxs[s] = wb * ux;
      wbys[s] = wb * uy;
    }
    ubx += mag * fbx;
    uby += mag * fby;
    // e = ℓ − L (1 + a o)
    const double eb = -k * fu;
    Lb[s] -= eb * (1.0 + a * o[s]);
    ob[s] -= eb * L * a;
    // d̂ = d/ℓ and ℓ = sqrt(d·d + ε²): d̄ = (ū − d̂ (d̂·ū))/ℓ + ℓ̄ d̂
    const double uu = ubx * ux + uby * uy;
    dbxs[s] = (ubx - ux * uu) / l + eb * ux;
    dbys[s] = (uby - uy * uu) / l + eb * uy;
  }
}
}  // namespace

void springs_adjoint(const Model& m, const double* x, const double* v, const double* o, const double* Fb,
                     double* xb, double* vb, double* ob, double* Lb) {
  const int S = m.S;
  double* dbx = m.spring_scratch.data();
  double* dby = dbx + S;
  double* wbx = dby + S;
  double* wby = wbx + S;
  if (m.has_dashpots) {
    spring_adjoints<true>(m, x, v, o, Fb, ob, Lb, dbx, dby, wbx, wby);
    scatter(SpringArrays(m), wbx, wby, vb);
  } else {
    spring_adjoints<false>(m, x, v, o, Fb, ob, Lb, dbx, dby, wbx, wby);
  }
  scatter(SpringArrays(m), dbx, dby, xb);
}

}  // namespace divcoll::sim
