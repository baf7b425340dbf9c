// physics invariants and hard cases of the engine (SPEC §2): free fall, momentum, energy, no
// penetration, stability, NaN containment, tape-free forward runs
#include <gtest/gtest.h>

#include <cmath>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "config/environments.hpp"
#include "morph/body.hpp"
#include "testing.hpp"
#include "sim/engine.hpp"

namespace divcoll {
namespace {

morph::Agent make_agent(uint64_t seed) { return testing::agent_with_anchors(seed, 3); }

std::vector<double> make_conn(uint64_t seed) {
  Rng rng = make_rng(seed, 4, 0);
  return morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
}

// a scene of free masses (no springs, no agents), high above the ground
sim::Scene free_masses(int n) {
  sim::Scene s;
  for (int i = 0; i < n; ++i) {
    s.x0.push_back(0.1 * i);
    s.x0.push_back(10.0 + 0.01 * i);
    s.mass.push_back(1.0);
  }
  s.env = config::place_environment(config::environment_table("flat"), 1.0, testing::kCoulomb);
  return s;
}

// a pair with no ground, gravity or damping: the ground is far below, and 4 substeps keep the undamped, actuated
// springs well inside the stability limit
sim::Scene floating_pair(uint64_t seed_a, uint64_t seed_b, const std::vector<double>& conn) {
  sim::Scene s = collective::pair_scene(make_agent(seed_a), make_agent(seed_b), conn, testing::weak_connector(), "flat",
                                        testing::kCoulomb);
  s.env.gravity = 0;
  s.env.damping = 0;
  s.env.terrain = {sim::Segment{-1e9, -50, 0}};
  s.constants.substeps = 4;
  return s;
}

TEST(Engine, FreeFallMatchesClosedForm) {
  sim::Scene s = free_masses(3);
  const int T = 200;
  sim::RunOptions opt;
  opt.steps = T;
  opt.record = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok);
  // v_t = h g (1 − e^t)/(1 − e), y_t = y_0 + h Σ_{k=1..t} v_k with e = exp(−γ h)
  const double h = s.constants.dt, g = s.env.gravity, e = std::exp(-s.env.damping * h);
  double y = s.x0[1], v = 0;
  for (int t = 1; t <= T; ++t) {
    v = h * g * (1 - std::pow(e, t)) / (1 - e);
    y += h * v;
    ASSERT_NEAR(r.v[t * 6 + 1], v, 1e-12) << "step " << t;
    ASSERT_NEAR(r.x[t * 6 + 1], y, 1e-12) << "step " << t;
    ASSERT_EQ(r.x[t * 6], s.x0[0]) << "no horizontal motion";
  }
}

TEST(Engine, MomentumConservedWithoutGroundGravityOrDamping) {
  const sim::Scene s = floating_pair(1, 2, make_conn(1));
  sim::RunOptions opt;
  opt.steps = 500;
  opt.record = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  const int N = s.n_masses();
  double max_speed = 0;
  for (int t = 0; t <= opt.steps; ++t) {
    double px = 0, py = 0;
    for (int i = 0; i < N; ++i) {
      px += r.v[(t * N + i) * 2];
      py += r.v[(t * N + i) * 2 + 1];
      max_speed = std::max(max_speed, std::abs(r.v[(t * N + i) * 2]));
    }
    ASSERT_NEAR(px, 0.0, 1e-11) << "step " << t;
    ASSERT_NEAR(py, 0.0, 1e-11) << "step " << t;
  }
  EXPECT_GT(max_speed, 1e-3) << "the controllers should move the masses";
}

// record_tether: with no ground, gravity or damping the agents' own springs cancel inside each agent, so the change of
// an agent's momentum is exactly the impulse the tether's springs gave it
TEST(Engine, TetherImpulseIsEachAgentsMomentumChangeWithoutGroundGravityOrDamping) {
  const sim::Scene s = floating_pair(1, 2, make_conn(1));
  sim::RunOptions opt;
  opt.steps = 400;
  const double travel = sim::simulate(s, opt).travel;
  opt.record = true;
  opt.record_tether = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  EXPECT_EQ(r.travel, travel) << "recording changes nothing";
  const int N = s.n_masses(), T = opt.steps;
  ASSERT_EQ(r.tether.size(), s.connector_spring_index.size() * sim::kTetherColumns);
  std::vector<int> owner(N, -1);
  for (int q = 0; q < s.n_agents(); ++q)
    for (int k = 0; k < sim::kAgentMasses; ++k) owner[s.agent_mass_index[q * sim::kAgentMasses + k]] = q;
  for (int q = 0; q < 2; ++q) {
    double px = 0, py = 0, jx = 0, jy = 0;
    for (int i = 0; i < N; ++i)
      if (owner[i] == q) px += s.mass[i] * r.v[(T * N + i) * 2], py += s.mass[i] * r.v[(T * N + i) * 2 + 1];
    for (size_t c = 0; c < s.connector_spring_index.size(); ++c) {
      const int sp = s.connector_spring_index[c];
      const double* row = &r.tether[c * sim::kTetherColumns];
      if (owner[s.spring_i[sp]] == q) jx += row[0], jy += row[1];
      if (owner[s.spring_j[sp]] == q) jx -= row[0], jy -= row[1];
    }
    EXPECT_GT(std::abs(jx) + std::abs(jy), 1e-3) << "agent " << q << ": the tether should push it";
    EXPECT_NEAR(jx, px, 1e-9 * (1 + std::abs(px))) << "agent " << q;
    EXPECT_NEAR(jy, py, 1e-9 * (1 + std::abs(py))) << "agent " << q;
  }
}

// record_tether's five sums recomputed from the recorded states for a tether whose network outputs 0 (every weight 0:
// the springs hold their rest lengths, so f = −k (ℓ − L) d̂ − c ((v_i − v_j)·d̂) d̂ needs only x and v), one substep:
// impulse f h, work f on each mass's path (the mean of h v and Δx), ∫|f| dt
TEST(Engine, TetherSumsAreTheSpringForcesImpulseAndWorkOnEachMass) {
  const morph::Agent a = make_agent(5), b = make_agent(6);
  const std::vector<double> zero(sim::connector_param_count(), 0.0);
  const sim::Scene s = collective::pair_scene(a, b, zero, testing::weak_connector(), "flat", testing::kCoulomb);
  sim::RunOptions opt;
  opt.steps = 300;
  opt.record = true;
  opt.record_tether = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  ASSERT_EQ(r.substeps, 1);
  const int N = s.n_masses();
  const double h = s.constants.dt, eps2 = s.constants.eps_len * s.constants.eps_len;
  double largest = 0;
  for (size_t c = 0; c < s.connector_spring_index.size(); ++c) {
    const int sp = s.connector_spring_index[c], i = s.spring_i[sp], j = s.spring_j[sp];
    double want[sim::kTetherColumns] = {0, 0, 0, 0, 0};
    for (int t = 0; t < opt.steps; ++t) {
      const double* x = &r.x[static_cast<size_t>(t) * N * 2];
      const double* v = &r.v[static_cast<size_t>(t) * N * 2];
      const double dx = x[2 * i] - x[2 * j], dy = x[2 * i + 1] - x[2 * j + 1];
      const double l = std::sqrt(dx * dx + dy * dy + eps2), ux = dx / l, uy = dy / l;
      const double w = (v[2 * i] - v[2 * j]) * ux + (v[2 * i + 1] - v[2 * j + 1]) * uy;
      const double mag = -s.stiffness[sp] * (l - s.rest_length[sp]) - s.damping[sp] * w;
      const double fx = mag * ux, fy = mag * uy;
      want[0] += fx * h, want[1] += fy * h;
      const double* x1 = x + N * 2;  // the step's end (one substep)
      auto path = [&](int q, int a) { return 0.5 * (h * v[2 * q + a] + x1[2 * q + a] - x[2 * q + a]); };
      want[2] += fx * path(i, 0) + fy * path(i, 1);
      want[3] -= fx * path(j, 0) + fy * path(j, 1);
      want[4] += std::hypot(fx, fy) * h;
    }
    for (int k = 0; k < sim::kTetherColumns; ++k) {
      const double got = r.tether[c * sim::kTetherColumns + k];
      EXPECT_NEAR(got, want[k], 1e-9 * (1 + std::abs(want[k]))) << "spring " << c << ", " << sim::kTetherColumnNames[k];
    }
    largest = std::max(largest, want[4]);
  }
  EXPECT_GT(largest, 1e-3) << "the passive tether should pull";
}

// a held tether (weights 0) is a set of ordinary springs: with no ground, gravity or damping, the work its springs did
// on the masses is the elastic energy they hold at the end, negated (they start at rest length), to the O(h²) of the
// step; the work's estimate is what makes that hold (force times Δx alone, or times h·v alone, misses it by far more)
TEST(Engine, AHeldTethersWorkIsTheLossOfItsStoredEnergy) {
  const sim::Scene s = floating_pair(7, 8, std::vector<double>(sim::connector_param_count(), 0.0));
  sim::RunOptions opt;
  opt.steps = 600;
  opt.record = true;
  opt.record_tether = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  const int N = s.n_masses();
  const double* x = &r.x[static_cast<size_t>(opt.steps) * N * 2];
  double work = 0, stored = 0, force_time = 0;
  for (size_t c = 0; c < s.connector_spring_index.size(); ++c) {
    const int sp = s.connector_spring_index[c], i = s.spring_i[sp], j = s.spring_j[sp];
    work += r.tether[c * sim::kTetherColumns + 2] + r.tether[c * sim::kTetherColumns + 3];
    force_time += r.tether[c * sim::kTetherColumns + 4];
    const double e = std::hypot(x[2 * i] - x[2 * j], x[2 * i + 1] - x[2 * j + 1]) - s.rest_length[sp];
    stored += 0.5 * s.stiffness[sp] * e * e;
  }
  ASSERT_GT(force_time, 1e-2) << "the agents' gaits should stretch the tether";
  // scale: what one spring force does over the episode's path, |f| dt times a typical speed of 0.1 u/s
  EXPECT_NEAR(work, -stored, 0.1 * stored) << "stored " << stored << ", force·time " << force_time;
}

TEST(Engine, DampingRemovesEnergyFromPassiveBody) {
  morph::Agent a = make_agent(3);
  for (double& amp : a.amplitude) amp = 0;  // passive
  sim::Scene s = collective::agent_scene(a, "flat", testing::kCoulomb);
  s.env.gravity = 0;
  s.env.terrain = {sim::Segment{-1e9, -50, 0}};
  // stretch the body: scale the initial positions by 1.2
  for (double& x : s.x0) x *= 1.2;
  sim::RunOptions opt;
  opt.steps = 400;
  opt.record = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok);
  const int N = s.n_masses();
  auto energy = [&](int t) {
    double E = 0;
    for (int i = 0; i < N; ++i)
      E += 0.5 * (std::pow(r.v[(t * N + i) * 2], 2) + std::pow(r.v[(t * N + i) * 2 + 1], 2));
    for (int q = 0; q < s.n_springs(); ++q) {
      const int i = s.spring_i[q], j = s.spring_j[q];
      const double l = std::hypot(r.x[(t * N + i) * 2] - r.x[(t * N + j) * 2],
                                  r.x[(t * N + i) * 2 + 1] - r.x[(t * N + j) * 2 + 1]);
      E += 0.5 * s.stiffness[q] * std::pow(l - s.rest_length[q], 2);
    }
    return E;
  };
  const double E0 = energy(0);
  ASSERT_GT(E0, 0);
  // energy over windows of 20 steps never grows, and almost all of it is gone at the end
  double prev = E0;
  for (int t = 20; t <= opt.steps; t += 20) {
    const double E = energy(t);
    EXPECT_LE(E, prev * (1 + 1e-9)) << "step " << t;
    prev = E;
  }
  EXPECT_LT(energy(opt.steps), 1e-3 * E0);
}

// the lowest terrain height under x, over both sides of a boundary (a mass exactly on a wall face)
double ground_at(const sim::Environment& env, double x) {
  int k = static_cast<int>(env.terrain.size()) - 1;
  while (k > 0 && x < env.terrain[k].x_start) --k;
  return env.terrain[k].y_start + env.terrain[k].slope * (x - env.terrain[k].x_start);
}

// SPEC §2's contact removes the normal velocity but never pushes a mass back out. A mass that slides
// along one segment's tangent across a change of slope, or down a wall face past the lower floor, ends
// that step slightly inside the terrain and stays at that depth until it moves out: at most about one
// step's travel. Where the terrain has no such features the masses never enter it at all.
// A mass held at a wall face (within 1e-6 u of a segment boundary, where wall contact takes precedence
// over the floor) keeps sliding down the face for as many steps as its vertical speed lasts: measured
// 7.2e-3 u over 4 steps (step_up, seed 2, after the engine's MLP kernels changed the last bits); those
// masses are held to 2e-2 u, every other to the bound above.
bool at_wall_face(const sim::Environment& env, double x) {
  for (size_t k = 1; k < env.terrain.size(); ++k)
    if (std::abs(x - env.terrain[k].x_start) < 1e-6) return true;
  return false;
}
class NoPenetration : public ::testing::TestWithParam<std::string> {};

TEST_P(NoPenetration, LongRandomRunsStayAboveFloorsAndOutOfWalls) {
  const bool features = config::environment_table(GetParam()).relative.size() > 0;
  const double allowed = features ? 5e-3 : 1e-9;  // u
  for (uint64_t seed = 0; seed < 3; ++seed) {
    const morph::Agent a = make_agent(10 + seed), b = make_agent(20 + seed);
    std::vector<double> conn = make_conn(seed);
    for (double& w : conn) w *= 3.0;  // vigorous actuation
    sim::Scene s = collective::pair_scene(a, b, conn, testing::weak_connector(), GetParam(), testing::kCoulomb);
    double mx = -1e9;
    for (int i = 0; i < s.n_masses(); ++i) mx = std::max(mx, s.x0[2 * i]);
    s.env = config::place_environment(config::environment_table(GetParam()), mx - 0.047, testing::kCoulomb);
    sim::RunOptions opt;
    opt.steps = 2000;
    opt.record = true;
    const sim::RunResult r = sim::simulate(s, opt);
    ASSERT_EQ(r.status, sim::Status::ok) << r.message;
    const int N = s.n_masses();
    double worst = 0, worst_end = 0, worst_face = 0;
    for (int t = 0; t <= opt.steps; ++t)
      for (int i = 0; i < N; ++i) {
        const double x = r.x[(t * N + i) * 2], y = r.x[(t * N + i) * 2 + 1];
        const double depth = ground_at(s.env, x) - y;
        if (at_wall_face(s.env, x)) {
          worst_face = std::max(worst_face, depth);
          continue;
        }
        worst = std::max(worst, depth);
        if (t == opt.steps) worst_end = std::max(worst_end, depth);
      }
    EXPECT_LT(worst, allowed) << GetParam() << " seed " << seed << ": a mass went " << worst << " u into the terrain";
    EXPECT_LT(worst_end, allowed) << GetParam() << " seed " << seed;
    EXPECT_LT(worst_face, features ? 2e-2 : 1e-9)
        << GetParam() << " seed " << seed << ": a mass at a wall face went " << worst_face << " u into the terrain";
  }
}

INSTANTIATE_TEST_SUITE_P(EveryEnvironment, NoPenetration, ::testing::ValuesIn(config::environment_names()),
                         [](const auto& info) { return info.param; });

TEST(Engine, ForwardWithoutTapeIsBitIdenticalToTapedRun) {
  const morph::Agent a = make_agent(4), b = make_agent(5);
  const sim::Scene s = collective::pair_scene(a, b, make_conn(4), testing::weak_connector(), "gap", testing::kCoulomb);
  sim::RunOptions opt;
  opt.steps = 300;
  opt.record = true;
  const sim::RunResult plain = sim::simulate(s, opt);
  opt.grad = true;
  const sim::RunResult taped = sim::simulate(s, opt);
  ASSERT_EQ(plain.x, taped.x);
  ASSERT_EQ(plain.travel, taped.travel);
}

TEST(Engine, StrongConnectorPairIsSubsteppedAndFinite) {
  const morph::Agent a = make_agent(6), b = make_agent(7);
  const sim::Scene s = collective::pair_scene(a, b, make_conn(6), testing::strong_connector(), "flat", testing::kCoulomb);
  sim::RunOptions opt;
  opt.steps = 1000;
  opt.grad = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  EXPECT_TRUE(std::isfinite(r.travel));
  EXPECT_EQ(r.substeps, sim::substeps_needed(s));
  for (double g : r.grad_connector_params) ASSERT_TRUE(std::isfinite(g));
}

TEST(Engine, StiffSceneIsSubsteppedAutomaticallyOrRefusedWhenItForbidsSubsteps) {
  sim::Scene s = free_masses(2);
  s.x0 = {0.0, 0.5, 0.06, 0.5};
  s.spring_i = {0};
  s.spring_j = {1};
  s.rest_length = {0.05};  // stretched by 0.01 u
  s.stiffness = {1e6};     // Δt·sqrt(Σk/m) = 4: explicit Euler at one substep would blow up
  s.amplitude = {0};
  s.damping = {0};
  ASSERT_GT(sim::substeps_needed(s), 2);
  sim::RunOptions opt;
  opt.steps = 500;
  opt.record = true;
  // substeps = 0 (the default): chosen from the stability rule, finite and bounded
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  EXPECT_EQ(r.substeps, sim::substeps_needed(s));
  for (double x : r.x) ASSERT_LT(std::abs(x), 10.0);
  // a scene that insists on one substep is refused with a message, never run into NaN
  s.constants.substeps = 1;
  try {
    sim::simulate(s, opt);
    FAIL() << "an unstable scene was simulated";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("substeps"), std::string::npos) << e.what();
  }
}

TEST(Engine, TwentyAgentChainIsFiniteInEveryEnvironment) {
  std::vector<morph::Agent> agents;
  for (int q = 0; q < 20; ++q) agents.push_back(make_agent(100 + q));
  std::vector<const morph::Agent*> ptr;
  for (const auto& a : agents) ptr.push_back(&a);
  for (const std::string& env : config::environment_names()) {
    const sim::Scene s = collective::chain_scene(ptr, make_conn(9), testing::weak_connector(), env, testing::kCoulomb);
    sim::RunOptions opt;
    opt.steps = 500;
    const sim::RunResult r = sim::simulate(s, opt);
    EXPECT_EQ(r.status, sim::Status::ok) << env << ": " << r.message;
    EXPECT_TRUE(std::isfinite(r.travel)) << env;
  }
}

TEST(Engine, BodyDroppedFromOneUnitOntoAStepEdgeStaysFinite) {
  sim::Scene s = collective::agent_scene(make_agent(8), "flat", testing::kCoulomb);
  // a step whose edge is under the body's middle, the body 1 u above it
  double cx = 0;
  for (int i = 0; i < s.n_masses(); ++i) cx += s.x0[2 * i] / s.n_masses();
  s.env.terrain = {sim::Segment{-1e9, 0, 0}, sim::Segment{cx, 0.04, 0}};
  for (int i = 0; i < s.n_masses(); ++i) s.x0[2 * i + 1] += 1.04;
  sim::RunOptions opt;
  opt.steps = 1000;
  opt.grad = true;
  opt.record = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  for (double x : r.x) ASSERT_TRUE(std::isfinite(x));
  for (double g : r.grad_x0) ASSERT_TRUE(std::isfinite(g));
  EXPECT_GT(r.contacts.toi, 0);
}

TEST(Engine, SpringOfNearZeroLengthStaysFinite) {
  sim::Scene s = free_masses(2);
  s.x0 = {0.0, 0.5, 1e-12, 0.5};  // two masses almost on top of each other
  s.spring_i = {0};
  s.spring_j = {1};
  s.rest_length = {1e-9};
  s.stiffness = {3e4};
  s.amplitude = {0};
  s.damping = {0};
  sim::RunOptions opt;
  opt.steps = 300;
  opt.grad = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  for (double g : r.grad_x0) EXPECT_TRUE(std::isfinite(g));
  for (double g : r.grad_rest_length) EXPECT_TRUE(std::isfinite(g));
}

TEST(Engine, NanInOneControllerEndsOnlyThatEpisode) {
  const morph::Agent a = make_agent(30), b = make_agent(31), c = make_agent(32);
  const std::vector<double> conn = make_conn(30);
  std::vector<sim::Scene> batch = {
      collective::pair_scene(a, b, conn, testing::weak_connector(), "flat", testing::kCoulomb),
      collective::pair_scene(b, c, conn, testing::weak_connector(), "flat", testing::kCoulomb),
      collective::pair_scene(c, a, conn, testing::weak_connector(), "flat", testing::kCoulomb),
  };
  batch[1].agent_params[100] = std::nan("");
  sim::RunOptions opt;
  opt.steps = 200;
  opt.grad = true;
  sim::Simulator sim;
  const std::vector<sim::RunResult> rs = sim.run_batch(batch, opt);
  EXPECT_EQ(rs[1].status, sim::Status::nan);
  EXPECT_EQ(rs[1].bad_step, 1);
  EXPECT_NE(rs[1].message.find("step 1"), std::string::npos) << rs[1].message;
  EXPECT_TRUE(std::isnan(rs[1].travel));
  // the others are exactly what they are alone
  for (int q : {0, 2}) {
    ASSERT_EQ(rs[q].status, sim::Status::ok);
    const sim::RunResult alone = sim::simulate(batch[q], opt);
    EXPECT_EQ(rs[q].travel, alone.travel);
    EXPECT_EQ(rs[q].grad_connector_params, alone.grad_connector_params);
  }
}

// record_inputs (analysis.familiarity_on = inputs): the connectors' 11 network inputs per spring (SPEC §6.3) at the
// steps where hidden states are recorded, beside them; recording changes nothing else. At step 0 the velocities and
// touch flags are 0 and every spring is at its rest length (ℓ/L = 1 up to ε)
TEST(Engine, RecordedConnectorInputsSitBesideTheHiddenStates) {
  const testing::GradientPair& f = testing::gradient_pair();
  const sim::Scene s = collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), "flat", testing::kCoulomb);
  sim::RunOptions opt;
  opt.steps = 60;
  opt.record_hidden = true;
  opt.hidden_every = 7;
  const sim::RunResult h = sim::simulate(s, opt);
  opt.record_inputs = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok);
  EXPECT_EQ(r.travel, h.travel);
  EXPECT_EQ(r.hidden, h.hidden);
  EXPECT_TRUE(h.inputs.empty());
  const size_t records = (60 + 7 - 1) / 7, cols = 5;
  ASSERT_EQ(r.hidden.size(), records * cols * sim::kHidden);
  ASSERT_EQ(r.inputs.size(), records * cols * sim::kConnectorInputs);
  for (size_t c = 0; c < cols; ++c) {
    const double* in = &r.inputs[c * sim::kConnectorInputs];
    for (int q = 4; q < 10; ++q) EXPECT_EQ(in[q], 0.0) << "spring " << c << " input " << q;
    EXPECT_NEAR(in[10], 1.0, 1e-9);
  }
  // later records move
  double moved = 0;
  for (size_t q = 0; q < r.inputs.size() / records; ++q)
    moved = std::max(moved, std::abs(r.inputs[(records - 1) * cols * sim::kConnectorInputs + q] - r.inputs[q]));
  EXPECT_GT(moved, 1e-3);
}

TEST(Engine, BatchOfDifferentShapesIsRefused) {
  const morph::Agent a = make_agent(40), b = make_agent(41);
  std::vector<sim::Scene> batch = {collective::agent_scene(a, "flat", testing::kCoulomb),
                                   collective::pair_scene(a, b, make_conn(40), testing::weak_connector(), "flat", testing::kCoulomb)};
  sim::Simulator sim;
  EXPECT_THROW(sim.run_batch(batch, sim::RunOptions{}), InputError);
}

}  // namespace
}  // namespace divcoll
