// stage: free velocity (SPEC §2.3): damping, spring forces, gravity, wind, adhesion; and its adjoint
#include <cmath>

#include "common/dmath.hpp"
#include "sim/stages.hpp"

namespace divcoll::sim {

void velocity_forward(const Model& m, int t, const double* x, const double* v, const double* F, double* vp) {
  const Environment& env = m.scene->env;
  const double h = m.h;
  // uniform accelerations: wind w(t) = A_w sin(2π t Δt / P_w) and gravity
  const double ax = m.has_wind ? env.wind_amp * dmath::sin(2.0 * M_PI * t * m.dt / env.wind_period) : 0.0;
  const double ay = env.gravity;
  for (int i = 0; i < m.N; ++i) {
    double adh = 0;
    // adhesion: a mass within the band above the surface below it is pulled down
    if (m.has_adhesion) {
      const int k = segment_of(m, x[2 * i]);
      if (x[2 * i + 1] - terrain_height(m, k, x[2 * i]) < env.adhesion_band) adh = -env.adhesion;
    }
    vp[2 * i] = m.decay * v[2 * i] + h * (F[2 * i] * m.inv_mass[i] + ax);
    vp[2 * i + 1] = m.decay * v[2 * i + 1] + h * (F[2 * i + 1] * m.inv_mass[i] + ay + adh);
  }
}

void velocity_adjoint(const Model& m, const double* vpb, double* vb, double* Fb) {
  for (int i = 0; i < m.N; ++i) {
    for (int d = 0; d < 2; ++d) {
      vb[2 * i + d] += m.decay * vpb[2 * i + d];
      Fb[2 * i + d] = m.h * vpb[2 * i + d] * m.inv_mass[i];
    }
  }
}

}  // namespace divcoll::sim
