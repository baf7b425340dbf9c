// the contact laws (src/sim/contact.cpp, src/MODEL.md "Contact laws"): what no_slip does to a whole episode
// (a mass in contact moves with the ground: at rest on still ground, with the belt on the treadmill; no mass
// ends below the floor), that the law is a property of the scene given to whatever builds it and reaches the
// engine from there (nothing process-wide: scenes of both laws in one process), that the environments' kappa_ns
// is the documented re-reading, and that coulomb ignores kappa_ns. Gradients are in gradient_test.cpp and
// stages_test.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "collective/builders.hpp"
#include "collective/pairs.hpp"
#include "config/environments.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

constexpr int kSteps = 300;

// the pair of the gradient tests in `env` under `law`, its features just ahead of its front
sim::Scene pair_in(const std::string& env, sim::ContactLaw law) {
  const testing::GradientPair& f = testing::gradient_pair();
  sim::Scene s = collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), env, law);
  double mx = -1e9;
  for (int i = 0; i < s.n_masses(); ++i) mx = std::max(mx, s.x0[2 * i]);
  s.env = config::place_environment(config::environment_table(env), mx - 0.047, law);
  return s;
}

sim::RunResult run(const sim::Scene& s, int steps = kSteps) {
  sim::RunOptions opt;
  opt.steps = steps;
  opt.record = true;
  return sim::simulate(s, opt);
}

// the terrain height under x (SPEC §3)
double ground(const sim::Environment& e, double x) {
  size_t k = e.terrain.size() - 1;
  while (k > 0 && x < e.terrain[k].x_start) --k;
  return e.terrain[k].y_start + e.terrain[k].slope * (x - e.terrain[k].x_start);
}

// under no_slip with kappa_ns = 0, a mass that touched the ground in a step ends it with the ground's velocity:
// zero on still flat ground, the belt's (−β, 0) on the treadmill
TEST(NoSlip, AMassInContactMovesWithTheGround) {
  for (const char* env : {"flat", "treadmill"}) {
    SCOPED_TRACE(env);
    const sim::Scene s = pair_in(env, sim::ContactLaw::no_slip);
    ASSERT_EQ(s.env.no_slip_keep, 0.0);
    const sim::RunResult r = run(s);
    ASSERT_EQ(r.status, sim::Status::ok) << r.message;
    ASSERT_EQ(r.substeps, 1) << "the recorded velocity is the last substep's";
    const int N = s.n_masses();
    long touching = 0;
    for (int t = 1; t <= kSteps; ++t)
      for (int i = 0; i < N; ++i) {
        if (!r.touch[static_cast<size_t>(t) * N + i]) continue;
        ++touching;
        const double* v = &r.v[(static_cast<size_t>(t) * N + i) * 2];
        EXPECT_EQ(v[0], -s.env.belt_speed) << "step " << t << " mass " << i;
        EXPECT_EQ(v[1], 0.0) << "step " << t << " mass " << i;
      }
    EXPECT_GT(touching, kSteps) << "masses touch the ground";
  }
}

// with kappa_ns > 0 a touching mass keeps that fraction of its tangential velocity (flat: v_y = 0, v_x free)
TEST(NoSlip, RetentionKeepsPartOfTheTangentialVelocity) {
  sim::Scene s = pair_in("ice", sim::ContactLaw::no_slip);
  EXPECT_NEAR(s.env.no_slip_keep, 1.0 / 3.0, 1e-15);
  const sim::RunResult r = run(s);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  const int N = s.n_masses();
  long sliding = 0;
  for (int t = 1; t <= kSteps; ++t)
    for (int i = 0; i < N; ++i) {
      if (!r.touch[static_cast<size_t>(t) * N + i]) continue;
      EXPECT_EQ(r.v[(static_cast<size_t>(t) * N + i) * 2 + 1], 0.0);
      sliding += r.v[(static_cast<size_t>(t) * N + i) * 2] != 0.0;
    }
  EXPECT_GT(sliding, 0) << "ice lets touching masses slide under no_slip";
}

// in every environment, under either law, no mass ends a step below the ground under it
TEST(NoSlip, NoMassEndsBelowTheFloor) {
  for (const std::string& env : config::environment_names())
    for (sim::ContactLaw law : {sim::ContactLaw::coulomb, sim::ContactLaw::no_slip}) {
      SCOPED_TRACE(env + " " + sim::contact_law_name(law));
      const sim::Scene s = pair_in(env, law);
      const sim::RunResult r = run(s);
      ASSERT_EQ(r.status, sim::Status::ok) << r.message;
      const int N = s.n_masses();
      double worst = 0;
      for (int t = 0; t <= kSteps; ++t)
        for (int i = 0; i < N; ++i) {
          const double* x = &r.x[(static_cast<size_t>(t) * N + i) * 2];
          worst = std::min(worst, x[1] - ground(s.env, x[0]));
        }
      EXPECT_GT(worst, -1e-12);
    }
}

// the law travels with the scene: every builder stamps the law it is given, whatever was built before it
TEST(NoSlip, ScenesCarryTheLawTheyAreGiven) {
  const testing::GradientPair& f = testing::gradient_pair();
  const std::vector<const morph::Agent*> chain = {&f.p, &f.a, &f.p};
  for (int round = 0; round < 2; ++round)  // the other law built in between: nothing carries over
    for (sim::ContactLaw law : {sim::ContactLaw::no_slip, sim::ContactLaw::coulomb}) {
      SCOPED_TRACE(sim::contact_law_name(law));
      EXPECT_EQ(config::place_environment(config::environment_table("ice"), 0.3, law).contact, law);
      EXPECT_EQ(collective::agent_scene(f.p, "sand", law).env.contact, law);
      EXPECT_EQ(collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), "flat", law).env.contact, law);
      EXPECT_EQ(collective::chain_scene(chain, f.conn, testing::weak_connector(), "ice", law).env.contact, law);
    }
}

// the law a scene is built with is the law the engine runs: a pair built no_slip runs bit for bit as the same
// scene with its environment's law set to no_slip by hand, and not as the coulomb one; scenes of the two laws
// alternate in one simulator (and the collective runners, given the law, run the same episodes)
TEST(NoSlip, TheLawASceneIsBuiltWithReachesTheEngine) {
  const testing::GradientPair& f = testing::gradient_pair();
  const sim::Scene coulomb = collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                    sim::ContactLaw::coulomb);
  const sim::Scene no_slip = collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                    sim::ContactLaw::no_slip);
  sim::Scene by_hand = coulomb;
  by_hand.env.contact = sim::ContactLaw::no_slip;
  sim::RunOptions opt;
  opt.steps = 200;
  opt.grad = true;
  sim::Simulator sim;
  const sim::RunResult n1 = sim.run(no_slip, opt), c1 = sim.run(coulomb, opt), n2 = sim.run(no_slip, opt);
  const sim::RunResult ref = sim::simulate(by_hand, opt), cref = sim::simulate(coulomb, opt);
  ASSERT_EQ(ref.status, sim::Status::ok) << ref.message;
  EXPECT_EQ(n1.travel, ref.travel);
  EXPECT_EQ(n1.grad_connector_params, ref.grad_connector_params);
  EXPECT_EQ(n2.travel, ref.travel);
  EXPECT_EQ(c1.travel, cref.travel);
  EXPECT_NE(n1.travel, c1.travel);
  EXPECT_GT(ref.contacts.floor, 0);

  // the runners: a pair's and an agent's episodes under RunPhysics{no_slip}, then {coulomb}
  const sim::RunPhysics ns{sim::ContactLaw::no_slip, false};
  const collective::PairOutcome pn = collective::run_pair(sim, f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                          ns, 200, true);
  const collective::PairOutcome pc = collective::run_pair(sim, f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                          testing::kSpec, 200, true);
  sim::RunOptions frozen = opt;
  frozen.agent_param_grad = false;
  EXPECT_EQ(pn.travel_u, sim::simulate(by_hand, frozen).travel);
  EXPECT_EQ(pn.grad, sim::simulate(by_hand, frozen).grad_connector_params);
  EXPECT_EQ(pc.travel_u, cref.travel);
  sim::Scene alone = collective::agent_scene(f.p, "flat", sim::ContactLaw::coulomb);
  alone.env.contact = sim::ContactLaw::no_slip;
  sim::RunOptions fwd;
  fwd.steps = 200;
  EXPECT_EQ(collective::run_alone(sim, f.p, "flat", ns, 200).travel_u, sim::simulate(alone, fwd).travel);
  EXPECT_NE(collective::run_alone(sim, f.p, "flat", ns, 200).travel_u,
            collective::run_alone(sim, f.p, "flat", testing::kSpec, 200).travel_u);
}

// the re-reading of the paper's friction f as kappa_ns = max(0, 1 − 1/f): ice 1.5 → 1/3, every other
// environment (default 1.0, sticky 0.85, sand) 0
TEST(NoSlip, EnvironmentsKeepTheDocumentedTangentialShare) {
  for (const std::string& env : config::environment_names()) {
    const double keep = config::environment_table(env).physics.no_slip_keep;
    if (env == "ice") {
      EXPECT_NEAR(keep, 1.0 - 1.0 / 1.5, 1e-15);
    } else {
      EXPECT_EQ(keep, 0.0) << env;
    }
  }
}

// coulomb reads neither kappa_ns nor anything else of no_slip: the same bits whatever kappa_ns is
TEST(NoSlip, CoulombIgnoresTheNoSlipRetention) {
  const sim::Scene s = pair_in("treadmill", sim::ContactLaw::coulomb);
  sim::Scene t = s;
  t.env.no_slip_keep = 0.7;
  const sim::RunResult a = run(s), b = run(t);
  ASSERT_EQ(a.status, sim::Status::ok);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  // and no_slip is a different law
  EXPECT_NE(run(pair_in("treadmill", sim::ContactLaw::no_slip)).x, a.x);
}

}  // namespace
}  // namespace divcoll
