// each stage of the step (sim/stages.hpp) on its own: its adjoint against central differences of
// L = w · (the stage's outputs), w random, at a random state chosen away from branch changes — springs (with
// dashpots), free velocity (with wind and adhesion), contact (floor with time of impact, sliding and sticking
// friction, a resting mass, a wall, a belt, free masses; the branches are asserted; the same under the no_slip
// law) and control (agents and connectors). Whole-rollout gradients are in gradient_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <tuple>

#include "collective/builders.hpp"
#include "morph/body.hpp"
#include "sim/model.hpp"
#include "sim/stages.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

using Vec = std::vector<double>;

// a pair scene with dashpots, wind, adhesion and a belt, and a random state
struct StageState {
  sim::Scene scene;
  Vec x, v, o;
  std::vector<uint8_t> tau;
};

StageState make_state(uint64_t seed) {
  Rng rng = make_rng(seed, 3, 0);
  morph::Agent p = collective::random_agent(rng), a = collective::random_agent(rng);
  p.anchors = collective::compute_anchors(p, testing::kSpec, {}, 100);
  a.anchors = collective::compute_anchors(a, testing::kSpec, {}, 100);
  Vec conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
  for (double& w : conn) w += 0.05 * normal(rng);  // nonzero biases: every term matters
  StageState s;
  s.scene = collective::pair_scene(p, a, conn, testing::weak_connector(), "flat", testing::kCoulomb);
  for (double& c : s.scene.damping) c = 5.0 + uniform01(rng);
  s.scene.env.wind_amp = 1.5;
  s.scene.env.adhesion = 2.0;
  s.scene.env.belt_speed = 0.2;
  s.scene.env.friction = 0.8;
  s.scene.env.tangent_keep = 0.9;
  const int N = s.scene.n_masses();
  s.x = s.scene.x0;
  for (int i = 0; i < N; ++i) s.x[2 * i] += 0.004 * normal(rng), s.x[2 * i + 1] += 0.05 + 0.004 * normal(rng);
  s.v.resize(2 * N);
  for (double& q : s.v) q = 0.3 * normal(rng);
  s.o.resize(s.scene.n_springs());
  for (double& q : s.o) q = 2 * uniform01(rng) - 1;
  s.tau.resize(N);
  for (auto& q : s.tau) q = uniform01(rng) < 0.5;
  return s;
}

Vec random_weights(size_t n, uint64_t seed) {
  Rng rng = make_rng(seed, 4, n);
  Vec w(n);
  for (double& q : w) q = normal(rng);
  return w;
}

double dot(const Vec& a, const Vec& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

// central difference of f along coordinate q of `in` (f reads `in`)
double central(Vec& in, size_t q, double eps, const std::function<double()>& f) {
  const double keep = in[q];
  in[q] = keep + eps;
  const double fp = f();
  in[q] = keep - eps;
  const double fm = f();
  in[q] = keep;
  return (fp - fm) / (2 * eps);
}

// every coordinate of `grad` against central differences of f w.r.t. `in`
void expect_gradient(const char* what, const Vec& grad, Vec& in, double eps, double tol,
                     const std::function<double()>& f, size_t stride = 1) {
  ASSERT_EQ(grad.size(), in.size()) << what;
  int checked = 0;
  for (size_t q = 0; q < in.size(); q += stride) {
    const double num = central(in, q, eps, f);
    EXPECT_NEAR(grad[q], num, tol * std::max(1.0, std::abs(num))) << what << " [" << q << "]";
    ++checked;
  }
  EXPECT_GT(checked, 0) << what;
}

TEST(StageAdjoint, SpringsMatchCentralDifferences) {
  StageState s = make_state(1);
  sim::Model m;
  m.compile(s.scene, 1);
  ASSERT_TRUE(m.has_dashpots);
  const Vec wF = random_weights(s.x.size(), 11);
  auto L = [&] {
    Vec F(s.x.size());
    sim::springs_forward(m, s.x.data(), s.v.data(), s.o.data(), F.data());
    return dot(wF, F);
  };
  Vec xb(s.x.size(), 0.0), vb(s.v.size(), 0.0), ob(s.o.size(), 0.0), Lb(s.o.size(), 0.0);
  sim::springs_adjoint(m, s.x.data(), s.v.data(), s.o.data(), wF.data(), xb.data(), vb.data(), ob.data(), Lb.data());
  expect_gradient("x", xb, s.x, 1e-7, 1e-6, L);
  expect_gradient("v", vb, s.v, 1e-6, 1e-6, L);
  expect_gradient("o", ob, s.o, 1e-6, 1e-6, L);
  expect_gradient("rest_length", Lb, s.scene.rest_length, 1e-8, 1e-6, L);
}

TEST(StageAdjoint, FreeVelocityMatchesCentralDifferences) {
  StageState s = make_state(2);
  sim::Model m;
  m.compile(s.scene, 1);
  ASSERT_TRUE(m.has_wind && m.has_adhesion);
  const int t = 37;  // the wind is nonzero
  Vec F = random_weights(s.x.size(), 21);
  const Vec w = random_weights(s.x.size(), 22);
  // two masses inside the adhesion band (flat ground at y = 0, band 0.01 u)
  s.x[1] = 0.004;
  s.x[3] = 0.007;
  auto L = [&] {
    Vec vp(s.x.size());
    sim::velocity_forward(m, t, s.x.data(), s.v.data(), F.data(), vp.data());
    return dot(w, vp);
  };
  Vec vp(s.x.size());
  sim::velocity_forward(m, t, s.x.data(), s.v.data(), F.data(), vp.data());
  EXPECT_LT(vp[1], m.decay * s.v[1] + m.h * (F[1] * m.inv_mass[0] + s.scene.env.gravity)) << "adhesion pulls mass 0";
  Vec vb(s.v.size(), 0.0), Fb(F.size(), 0.0);
  sim::velocity_adjoint(m, w.data(), vb.data(), Fb.data());
  expect_gradient("v", vb, s.v, 1e-6, 1e-8, L);
  expect_gradient("F", Fb, F, 1e-6, 1e-8, L);
  // adhesion switches on a band, a step in x: no derivative w.r.t. x away from the band's edge
  const Vec zero(s.x.size(), 0.0);
  expect_gradient("x", zero, s.x, 1e-9, 1e-8, L);
}

// the contact stage under `law` on masses 0..4 placed on purpose, the rest free above the ground. Terrain: a slope
// (so that n and the belt have two components), then a step up at x = 1 (a wall). Filled in place: the model
// points into the scene
struct ContactCase {
  StageState s;
  sim::Model m;
  Vec wx, wv;                            // L = wx·x'' + wv·v''
  std::vector<sim::ContactRecord> rec;  // the records of the forward pass
  Vec xn, vn;                            // x'', v''
};

std::pair<Vec, Vec> contact_run(ContactCase& c, sim::ContactRecord* r) {
  Vec xn(c.s.x.size()), vn(c.s.x.size());
  std::vector<uint8_t> tn(c.s.scene.n_masses());
  sim::contact_forward(c.m, c.s.x.data(), c.s.v.data(), xn.data(), vn.data(), tn.data(), r);
  return {xn, vn};
}

void setup_contact_case(ContactCase& c, sim::ContactLaw law, double keep) {
  c.s = make_state(3);
  c.s.scene.env.terrain = {sim::Segment{-1.0, -0.1, 0.1}, sim::Segment{1.0, 0.3, 0.0}};
  if (law == sim::ContactLaw::no_slip) {
    c.s.scene.env.contact = law;
    c.s.scene.env.no_slip_keep = keep;
  }
  c.m.compile(c.s.scene, 1);
  StageState& s = c.s;
  auto floor_y = [](double x) { return -0.1 + 0.1 * (x + 1.0); };
  const int N = s.scene.n_masses();
  for (int i = 0; i < N; ++i) s.x[2 * i] = -0.5 + 0.05 * i, s.x[2 * i + 1] = floor_y(s.x[2 * i]) + 0.2;
  auto place = [&](int i, double px, double above, double vx, double vy) {
    s.x[2 * i] = px;
    s.x[2 * i + 1] = floor_y(px) + above;
    s.v[2 * i] = vx;
    s.v[2 * i + 1] = vy;
  };
  place(0, 0.2, 0.001, 1.5, -0.5);    // floor, time of impact inside the step, sliding
  place(1, 0.4, -0.0005, 0.8, -0.3);  // floor, already below (no time of impact), sliding
  place(2, 0.6, 0.0005, 0.05, -1.0);  // floor, time of impact, slow tangentially (sticking under coulomb)
  place(3, 0.995, 0.05, 2.0, 0.1);    // wall of the step at x = 1
  place(4, 0.1, 0.001, 0.3, 0.5);     // above the floor, moving up: free
  c.wx = random_weights(s.x.size(), 31);
  c.wv = random_weights(s.x.size(), 32);
  c.rec.assign(N, sim::ContactRecord{});
  std::tie(c.xn, c.vn) = contact_run(c, c.rec.data());
}

// the adjoint of the stage (the stage's input velocity v' is s.v) against central differences of L
void expect_contact_adjoint(ContactCase& c) {
  auto L = [&] {
    auto [xn, vn] = contact_run(c, nullptr);
    return dot(c.wx, xn) + dot(c.wv, vn);
  };
  Vec vpb(c.s.x.size(), 0.0), xb(c.s.x.size(), 0.0);
  sim::contact_adjoint(c.m, c.s.v.data(), c.vn.data(), c.rec.data(), c.wx.data(), c.wv.data(), vpb.data(), xb.data());
  expect_gradient("x", xb, c.s.x, 1e-8, 1e-6, L);
  expect_gradient("v'", vpb, c.s.v, 1e-8, 1e-6, L);
}

TEST(StageAdjoint, ContactMatchesCentralDifferencesOnEveryBranch) {
  ContactCase c;
  setup_contact_case(c, sim::ContactLaw::coulomb, 0.0);
  ASSERT_TRUE(c.m.has_walls && c.m.has_belt);
  const std::vector<sim::ContactRecord>& rec = c.rec;
  // the branches asked for
  EXPECT_EQ(rec[0].kind, 1);
  EXPECT_TRUE(rec[0].toi_active && rec[0].friction_active);
  EXPECT_EQ(rec[1].kind, 1);
  EXPECT_TRUE(!rec[1].toi_active && rec[1].friction_active);
  EXPECT_EQ(rec[2].kind, 1);
  EXPECT_TRUE(rec[2].toi_active && !rec[2].friction_active);
  EXPECT_EQ(rec[3].kind, 2);
  EXPECT_TRUE(rec[3].toi_active);
  EXPECT_EQ(rec[4].kind, 0);
  EXPECT_NE(rec[0].b[0], 0.0) << "the belt moves the floor";
  EXPECT_LT(rec[0].tstar, c.m.h);
  expect_contact_adjoint(c);
}

// the same placements under the no_slip law (src/MODEL.md "Contact laws"): v'' = b + kappa_ns v_t, with
// kappa_ns = 0 (DiffTaichi's no-slip) and 0.4; the time of impact and the branches are coulomb's
TEST(StageAdjoint, NoSlipContactMatchesCentralDifferencesOnEveryBranch) {
  for (double keep : {0.0, 0.4}) {
    SCOPED_TRACE(keep);
    ContactCase c;
    setup_contact_case(c, sim::ContactLaw::no_slip, keep);
    const std::vector<sim::ContactRecord>& rec = c.rec;
    for (int i : {0, 2}) {
      EXPECT_EQ(rec[i].kind, 1);
      EXPECT_TRUE(rec[i].toi_active);
      EXPECT_EQ(rec[i].friction_active, keep > 0);
    }
    EXPECT_EQ(rec[1].kind, 1);
    EXPECT_FALSE(rec[1].toi_active);
    EXPECT_EQ(rec[3].kind, 2);
    EXPECT_TRUE(rec[3].toi_active);
    EXPECT_EQ(rec[4].kind, 0);
    // v'' − b has no normal part, and its tangential part is kappa_ns times v_t
    const Vec& vp = c.s.v;
    for (int i : {0, 1, 2, 3}) {
      const sim::ContactRecord& r = rec[i];
      const double rx = vp[2 * i] - r.b[0], ry = vp[2 * i + 1] - r.b[1];
      const double vnrm = rx * r.n[0] + ry * r.n[1];
      const double ux = c.vn[2 * i] - r.b[0], uy = c.vn[2 * i + 1] - r.b[1];
      EXPECT_NEAR(ux, keep * (rx - vnrm * r.n[0]), 1e-15) << i;
      EXPECT_NEAR(uy, keep * (ry - vnrm * r.n[1]), 1e-15) << i;
    }
    expect_contact_adjoint(c);
  }
}

TEST(StageAdjoint, ControlMatchesCentralDifferences) {
  StageState s = make_state(4);
  const int t = 123;
  const Vec wo = random_weights(s.o.size(), 41);
  const nn::Layout la = nn::agent_layout(sim::agent_input_size(s.scene.constants));
  const nn::Layout lc = nn::connector_layout();
  const int A = s.scene.n_agents(), cols = sim::kConnectorSprings * s.scene.n_connectors();
  Vec agent_acts(static_cast<size_t>(A) * la.activation_count()), conn_acts(static_cast<size_t>(lc.activation_count()) * cols);
  Vec o_in = s.o;
  sim::Model m;
  // the model packs the weights: recompiled for every evaluation, so that parameter perturbations count
  auto L = [&] {
    m.compile(s.scene, 1);
    Vec o = o_in;
    sim::control_forward(m, t, s.x.data(), s.v.data(), s.tau.data(), o.data(),
                         sim::ControlBuffers{agent_acts.data(), conn_acts.data()});
    return dot(wo, o);
  };
  L();
  Vec ob = wo, xb(s.x.size(), 0.0), vb(s.v.size(), 0.0), Lb(s.o.size(), 0.0);
  Vec ga(s.scene.agent_params.size(), 0.0), gc(s.scene.connector_params.size(), 0.0);
  Vec scratch(std::max<size_t>(la.in() + la.scratch_count(),
                               static_cast<size_t>(cols) * (1 + sim::kConnectorInputs + lc.scratch_count())));
  sim::control_adjoint(m, t, s.x.data(), s.v.data(), sim::ControlBuffers{agent_acts.data(), conn_acts.data()},
                       ob.data(), xb.data(), vb.data(), Lb.data(), ga.data(), gc.data(), scratch.data());
  expect_gradient("x", xb, s.x, 1e-7, 1e-6, L);
  expect_gradient("v", vb, s.v, 1e-6, 1e-6, L);
  expect_gradient("o", ob, o_in, 1e-6, 1e-6, L);
  expect_gradient("rest_length", Lb, s.scene.rest_length, 1e-8, 1e-6, L);
  expect_gradient("agent_params", ga, s.scene.agent_params, 1e-6, 1e-6, L, 17);
  expect_gradient("connector_params", gc, s.scene.connector_params, 1e-6, 1e-6, L, 7);

  // without the agents' parameter gradient every other block is the same, bit for bit
  L();
  Vec ob2 = wo, xb2(s.x.size(), 0.0), vb2(s.v.size(), 0.0), Lb2(s.o.size(), 0.0), gc2(gc.size(), 0.0);
  sim::control_adjoint<double>(m, t, s.x.data(), s.v.data(), sim::ControlBuffers{agent_acts.data(), conn_acts.data()},
                               ob2.data(), xb2.data(), vb2.data(), Lb2.data(), nullptr, gc2.data(), scratch.data());
  EXPECT_EQ(xb2, xb);
  EXPECT_EQ(vb2, vb);
  EXPECT_EQ(ob2, ob);
  EXPECT_EQ(Lb2, Lb);
  EXPECT_EQ(gc2, gc);
}

}  // namespace
}  // namespace divcoll
