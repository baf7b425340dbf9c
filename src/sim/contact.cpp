// stage: contact with the terrain (SPEC §2.4): walls, floor, belt, Coulomb friction, time of impact;
// and its adjoint with the branches of the forward pass held fixed. Under env.contact = no_slip the
// velocity after contact is DiffTaichi's no-slip one instead of Coulomb's (src/MODEL.md, "Contact laws")
#include <cmath>

#include "sim/stages.hpp"

namespace divcoll::sim {

void contact_forward(const Model& m, const double* x, const double* vp, double* x_next, double* v_next,
                     uint8_t* tau_next, ContactRecord* rec) {
  const Environment& env = m.scene->env;
  const bool no_slip = env.contact == ContactLaw::no_slip;
  const double h = m.h;
  for (int i = 0; i < m.N; ++i) {
    const double px = x[2 * i], py = x[2 * i + 1];
    const double vx = vp[2 * i], vy = vp[2 * i + 1];
    const double qx = px + h * vx, qy = py + h * vy;
    const int kq = segment_of(m, qx);
    ContactRecord r;

    // wall: the path crosses into a segment that is higher at the boundary, below its top
    if (m.has_walls) {
      const int kp = segment_of(m, px);
      if (kq != kp) {
        const bool right = qx > px;
        const double X = right ? m.seg_x[kq] : m.seg_x[kq + 1];
        const double hq = terrain_height(m, kq, X), hp = terrain_height(m, kp, X);
        const double yX = py + (qy - py) * (X - px) / (qx - px);
        if (hq > hp + 1e-9 && yX < hq) {
          r.kind = 2;
          r.n[0] = right ? -1.0 : 1.0;
          r.phi = std::abs(X - px) - 1e-7;
          r.dphi[0] = X > px ? -1.0 : 1.0;
        }
      }
    }
    // floor: the destination is below its segment's line
    if (r.kind == 0 && qy < terrain_height(m, kq, qx)) {
      const double s = m.seg_s[kq];
      const double inv = 1.0 / std::sqrt(1.0 + s * s);
      r.kind = 1;
      r.n[0] = -s * inv;
      r.n[1] = inv;
      if (m.has_belt) {
        r.b[0] = -env.belt_speed * inv;
        r.b[1] = -env.belt_speed * s * inv;
      }
      r.phi = (py - terrain_height(m, kq, px)) * inv;
      r.dphi[0] = r.n[0];
      r.dphi[1] = r.n[1];
    }
    // moving out of the surface: no contact
    const double rx = vx - r.b[0], ry = vy - r.b[1];
    const double vn = rx * r.n[0] + ry * r.n[1];
    if (r.kind == 0 || vn >= 0) {
      x_next[2 * i] = qx;
      x_next[2 * i + 1] = qy;
      v_next[2 * i] = vx;
      v_next[2 * i + 1] = vy;
      tau_next[i] = 0;
      if (rec) rec[i] = ContactRecord{};
      continue;
    }
    // Coulomb friction on the tangential relative velocity, plus the belt
    const double tx = rx - vn * r.n[0], ty = ry - vn * r.n[1];
    double wx = r.b[0], wy = r.b[1];
    if (no_slip) {
      // no-slip (DiffTaichi's advance_toi): the surface's velocity, plus κ_ns of the tangential relative
      // velocity (κ_ns = 0: no sliding, no bounce)
      if (env.no_slip_keep != 0) {
        r.friction_active = tx != 0 || ty != 0;
        wx += env.no_slip_keep * tx;
        wy += env.no_slip_keep * ty;
      }
    } else {
      const double tn = std::sqrt(tx * tx + ty * ty);
      if (tn > 0) {
        const double f = 1.0 + env.friction * vn / tn;
        if (f > 0) {
          r.friction_active = 1;
          wx += env.tangent_keep * f * tx;
          wy += env.tangent_keep * f * ty;
        }
      }
    }
    // time of impact: move with v' until the surface, then with v''
    const double D = -(vx * r.n[0] + vy * r.n[1]);
    // at φ = 0 exactly (a mass resting on the ground) the gradient passes through the clamp, as a
    // clamp's does in autodiff frameworks: that is what the independent implementation does too
    if (r.phi >= 0) {
      const double ratio = r.phi / D;
      if (ratio <= h) {
        r.tstar = ratio;
        r.toi_active = 1;
      } else {
        r.tstar = h;
      }
    }
    x_next[2 * i] = px + r.tstar * vx + (h - r.tstar) * wx;
    x_next[2 * i + 1] = py + r.tstar * vy + (h - r.tstar) * wy;
    v_next[2 * i] = wx;
    v_next[2 * i + 1] = wy;
    tau_next[i] = 1;
    if (rec) rec[i] = r;
  }
}

void contact_adjoint(const Model& m, const double* vp, const double* v_next, const ContactRecord* rec,
                     const double* xb_next, const double* vb_next, double* vpb, double* xb) {
  const Environment& env = m.scene->env;
  const bool no_slip = env.contact == ContactLaw::no_slip;
  const double h = m.h;
  for (int i = 0; i < m.N; ++i) {
    const ContactRecord& r = rec[i];
    const double xbx = xb_next[2 * i], xby = xb_next[2 * i + 1];
    xb[2 * i] += xbx;
    xb[2 * i + 1] += xby;
    if (r.kind == 0) {
      // x' = p + h v', v_next = v'
      vpb[2 * i] = h * xbx + vb_next[2 * i];
      vpb[2 * i + 1] = h * xby + vb_next[2 * i + 1];
      continue;
    }
    const double vx = vp[2 * i], vy = vp[2 * i + 1];
    const double wx = v_next[2 * i], wy = v_next[2 * i + 1];
    // x' = p + t* v' + (h − t*) v'', v_next = v''
    const double wbx = vb_next[2 * i] + (h - r.tstar) * xbx;
    const double wby = vb_next[2 * i + 1] + (h - r.tstar) * xby;
    double gx = r.tstar * xbx, gy = r.tstar * xby;  // gradient w.r.t. v'
    if (r.toi_active) {
      // t* = φ / D with D = −v'·n
      const double tsb = xbx * (vx - wx) + xby * (vy - wy);
      const double D = -(vx * r.n[0] + vy * r.n[1]);
      const double phib = tsb / D;
      const double Db = -tsb * r.phi / (D * D);
      gx -= Db * r.n[0];
      gy -= Db * r.n[1];
      xb[2 * i] += phib * r.dphi[0];
      xb[2 * i + 1] += phib * r.dphi[1];
    }
    if (no_slip) {
      // v'' = κ_ns (v_rel − (v_rel·n) n) + b: ∂v''/∂v' = κ_ns (I − n nᵀ), whatever the branch
      const double kap = env.no_slip_keep;
      if (kap != 0) {
        const double wn = wbx * r.n[0] + wby * r.n[1];
        gx += kap * (wbx - wn * r.n[0]);
        gy += kap * (wby - wn * r.n[1]);
      }
    } else if (r.friction_active) {
      // v'' = κ (1 + μ v_n/|u|) u + b with u = v_rel − v_n n, v_n = v_rel·n, v_rel = v' − b
      const double rx = vx - r.b[0], ry = vy - r.b[1];
      const double vn = rx * r.n[0] + ry * r.n[1];
      const double ux = rx - vn * r.n[0], uy = ry - vn * r.n[1];
      const double un = std::sqrt(ux * ux + uy * uy);
      const double kap = env.tangent_keep, mu = env.friction;
      const double f = 1.0 + mu * vn / un;
      const double uw = ux * wbx + uy * wby;
      double ubx = kap * f * wbx - kap * mu * vn * uw * ux / (un * un * un);
      double uby = kap * f * wby - kap * mu * vn * uw * uy / (un * un * un);
      double vnb = kap * mu * uw / un;
      vnb -= ubx * r.n[0] + uby * r.n[1];
      gx += ubx + vnb * r.n[0];
      gy += uby + vnb * r.n[1];
    }
    vpb[2 * i] = gx;
    vpb[2 * i + 1] = gy;
  }
}

}  // namespace divcoll::sim
