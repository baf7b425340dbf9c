// the stages of one step (SPEC §2), each with its adjoint beside it and with the same arguments.
//
//   control      reads x_t, v_t, τ_t, o_t        writes o'_t (and the controllers' activations)
//   springs      reads x_k, v_k, o'_t            writes F_k                      (per substep k)
//   velocity     reads v_k, F_k, x_k             writes v'_k                     (per substep k)
//   contact      reads x_k, v'_k                 writes x_k+1, v_k+1, τ_k+1      (per substep k)
//
// Adjoints take the gradient of the stage's outputs and add the gradient w.r.t. its inputs
// (x̄, v̄, ō, L̄, parameter gradients). Branches (contact or not, floor or wall, clamps) are read back
// from the forward records and held fixed. Internal to src/sim.
#pragma once

#include <cstdint>

#include "sim/model.hpp"

namespace divcoll::sim {

// ---- control -----------------------------------------------------------------------------------
// activation buffers: agents (A × agent act count, one column each), connectors (conn act count × 5C,
// one column per connector spring). o is updated in place: o ← α tanh(net) + (1 − α) o.
// T is the networks' scalar: double (the spec's), or float (RunOptions::float_networks: the networks' inputs,
// weights, activations and gradients in float; everything outside the networks stays double)
template <class T>
struct ControlBuffers {
  T* agent_acts;   // A × agent_layout.activation_count()
  T* conn_acts;    // conn_layout.activation_count() × 5C
};

template <class T>
void control_forward(const Model& m, int t, const double* x, const double* v, const uint8_t* tau, double* o,
                     const ControlBuffers<T>& buf);
// ob: in ō'_t, out ō_t; adds into xb, vb, Lb, g_agent (A × P_a; null: not wanted), g_conn (P_c); the parameter
// gradients are in T (with float the engine adds them into its double sums every few steps); scratch: as
// control_scratch_count (nn::backward's scratch, the larger of the agents' and the 5C connector columns', plus
// 11 × 5C for the connector input gradient)
template <class T>
void control_adjoint(const Model& m, int t, const double* x, const double* v, const ControlBuffers<T>& buf,
                     double* ob, double* xb, double* vb, double* Lb, T* g_agent, T* g_conn, T* scratch);
// values (of the networks' scalar, double or float) the adjoint's scratch needs
size_t control_scratch_count(const Model& m);

// ---- springs -----------------------------------------------------------------------------------
void springs_forward(const Model& m, const double* x, const double* v, const double* o, double* F);
// adds the connector springs' impulse and work of a substep into `tether` (C*5 rows of kTetherColumns,
// RunResult::tether): their forces are springs_forward's, still in m.spring_scratch; x0, v0 the substep's starting
// positions and velocities, x1 its final positions
void tether_accumulate(const Model& m, const double* x0, const double* v0, const double* x1, double* tether);
// Fb: gradient w.r.t. F; adds into xb, vb, ob, Lb
void springs_adjoint(const Model& m, const double* x, const double* v, const double* o, const double* Fb,
                     double* xb, double* vb, double* ob, double* Lb);

// ---- free velocity ------------------------------------------------------------------------------
// v' = e^(−γh) v + h (F/m + (w(t), g) + adhesion(x))
void velocity_forward(const Model& m, int t, const double* x, const double* v, const double* F, double* vp);
// vpb: gradient w.r.t. v'; adds into vb and writes Fb
void velocity_adjoint(const Model& m, const double* vpb, double* vb, double* Fb);

// ---- contact ------------------------------------------------------------------------------------
// what the adjoint needs of one mass's contact (kind 0: none, 1: floor, 2: wall)
struct ContactRecord {
  uint8_t kind = 0;
  uint8_t toi_active = 0;       // t* = φ / (−v'·n) inside [0, h]: differentiable
  uint8_t friction_active = 0;  // coulomb: v'' = κ max(0, 1 + μ v_n/|v_t|) v_t + b with the max and |v_t| > 0;
                                // no_slip: v'' = κ_ns v_t + b with κ_ns > 0 and v_t ≠ 0 (counted, not branched on)
  double n[2] = {0, 0};
  double b[2] = {0, 0};
  double dphi[2] = {0, 0};      // ∂φ/∂p
  double phi = 0;
  double tstar = 0;
};

// rec may be null (no tape)
void contact_forward(const Model& m, const double* x, const double* vp, double* x_next, double* v_next,
                     uint8_t* tau_next, ContactRecord* rec);
// given x̄_{k+1}, v̄_{k+1}: writes vpb (gradient w.r.t. v') and adds into xb (gradient w.r.t. x_k)
void contact_adjoint(const Model& m, const double* vp, const double* v_next, const ContactRecord* rec,
                     const double* xb_next, const double* vb_next, double* vpb, double* xb);

// segment index of x: the k with x_k ≤ x < x_(k+1)
inline int segment_of(const Model& m, double x) {
  int k = m.K - 1;
  while (k > 0 && x < m.seg_x[k]) --k;
  return k;
}
inline double terrain_height(const Model& m, int k, double x) {
  return m.seg_y[k] + m.seg_s[k] * (x - m.seg_x[k]);
}

}  // namespace divcoll::sim
