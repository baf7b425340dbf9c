// scene model: parameter counts, validate() on hand-made scenes, the stability rule, body lengths
#include "sim/scene.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "common/check.hpp"

namespace divcoll::sim {
namespace {

using ::testing::HasSubstr;

// two unit masses 0.05 u apart joined by one spring, no agents, flat ground
Scene two_masses(double k = 100.0) {
  Scene s;
  s.x0 = {0.0, 0.0, 0.05, 0.0};
  s.mass = {1.0, 1.0};
  s.spring_i = {0};
  s.spring_j = {1};
  s.rest_length = {0.05};
  s.stiffness = {k};
  s.amplitude = {0.0};
  s.damping = {0.0};
  s.env.terrain = {Segment{-1e9, 0, 0}};
  return s;
}

// one agent of 11 masses on a line, `length` u long: springs (k, k+1) ×10, (k, k+2) ×9, (0, 3), (1, 4)
void add_agent(Scene& s, double x_off, double length) {
  const int base = s.n_masses();
  for (int k = 0; k < kAgentMasses; ++k) {
    s.x0.push_back(x_off + length * k / (kAgentMasses - 1));
    s.x0.push_back(0.0);
    s.mass.push_back(1.0);
    s.agent_mass_index.push_back(base + k);
  }
  auto spring = [&](int a, int b) {
    s.agent_spring_index.push_back(s.n_springs());
    s.spring_i.push_back(base + a);
    s.spring_j.push_back(base + b);
    s.rest_length.push_back(std::abs(s.x0[2 * (base + b)] - s.x0[2 * (base + a)]));
    s.stiffness.push_back(3e4);
    s.amplitude.push_back(0.15);
    s.damping.push_back(0.0);
  };
  for (int k = 0; k + 1 < kAgentMasses; ++k) spring(k, k + 1);
  for (int k = 0; k + 2 < kAgentMasses; ++k) spring(k, k + 2);
  spring(0, 3);
  spring(1, 4);
  s.agent_params.resize(s.agent_params.size() + agent_param_count(s.constants), 0.01);
}

Scene one_agent() {
  Scene s;
  s.env.terrain = {Segment{-1e9, 0, 0}};
  add_agent(s, 0.0, 0.3);
  return s;
}

// the message of the InputError validate throws, or "" if it accepts the scene
std::string refusal(const Scene& s) {
  try {
    validate(s);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneParams, CountsMatchTheLayerSizes) {
  Constants c;
  EXPECT_EQ(agent_input_size(c), 54);
  EXPECT_EQ(agent_param_count(c), 3509);
  EXPECT_EQ(connector_param_count(), 1473);
  c.n_sines = 4;
  EXPECT_EQ(agent_input_size(c), 48);
  EXPECT_EQ(agent_param_count(c), (32 * 48 + 32) + (32 * 32 + 32) + (21 * 32 + 21));
}

TEST(SceneValidate, AcceptsWellFormedScenes) {
  EXPECT_EQ(refusal(two_masses()), "");
  EXPECT_EQ(refusal(one_agent()), "");
  Scene s = one_agent();
  add_agent(s, 0.4, 0.2);
  EXPECT_EQ(s.n_agents(), 2);
  EXPECT_EQ(refusal(s), "");
}

TEST(SceneValidate, RefusesBadIndices) {
  Scene s = two_masses();
  s.spring_j[0] = 5;
  EXPECT_THAT(refusal(s), HasSubstr("springs/j[0] = 5 is not a mass index"));
  s.spring_j[0] = -1;
  EXPECT_THAT(refusal(s), HasSubstr("springs/j[0] = -1"));

  s = two_masses();
  s.spring_j[0] = 0;
  EXPECT_THAT(refusal(s), HasSubstr("joins mass 0 to itself"));

  s = one_agent();
  s.agent_mass_index[3] = 11;
  EXPECT_THAT(refusal(s), HasSubstr("agents/mass_index[3] = 11 is not a mass index"));
  s = one_agent();
  s.agent_mass_index[3] = 2;
  EXPECT_THAT(refusal(s), HasSubstr("agents/mass_index[3] = 2 repeats"));
  s = one_agent();
  s.agent_spring_index[20] = 21;
  EXPECT_THAT(refusal(s), HasSubstr("agents/spring_index[20] = 21 is not a spring index"));
}

TEST(SceneValidate, RefusesBadValues) {
  Scene s = two_masses();
  s.rest_length[0] = -0.05;
  EXPECT_THAT(refusal(s), HasSubstr("springs/rest_length[0] = -0.05 u must be positive"));
  s.rest_length[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(refusal(s), HasSubstr("springs/rest_length[0] is NaN"));
  s = two_masses();
  s.stiffness[0] = std::numeric_limits<double>::infinity();
  EXPECT_THAT(refusal(s), HasSubstr("springs/stiffness[0] is infinite"));
  s = two_masses();
  s.stiffness[0] = -1;
  EXPECT_THAT(refusal(s), HasSubstr("springs/stiffness[0] = -1"));
  s = two_masses();
  s.damping[0] = -1;
  EXPECT_THAT(refusal(s), HasSubstr("springs/damping[0] = -1"));
  s = two_masses();
  s.mass[1] = 0;
  EXPECT_THAT(refusal(s), HasSubstr("masses/m[1] = 0 must be positive"));
  s = two_masses();
  s.x0[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(refusal(s), HasSubstr("masses/x0[3] is NaN"));
  s = one_agent();
  s.agent_params[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(refusal(s), HasSubstr("agents/params[7] is NaN"));
  // a simulator may accept non-finite weights (the episode then ends with status nan), nothing else
  EXPECT_NO_THROW(validate(s, ValidateOptions{.finite_params = false}));
  s.x0[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(validate(s, ValidateOptions{.finite_params = false}), InputError);
}

TEST(SceneValidate, RefusesBadShapes) {
  Scene s = two_masses();
  s.x0.pop_back();
  EXPECT_THAT(refusal(s), HasSubstr("masses/x0 has 3 values, expected 4"));
  s = two_masses();
  s.damping.push_back(0);
  EXPECT_THAT(refusal(s), HasSubstr("springs/damping has 2 values, expected 1"));
  s = one_agent();
  s.agent_params.pop_back();
  EXPECT_THAT(refusal(s), HasSubstr("agents/params has 3508 values, expected 3509"));
  s = two_masses();
  s.connector_params = {1.0};
  EXPECT_THAT(refusal(s), HasSubstr("connector_params has 1 values, expected 0"));
  s = two_masses();
  s.connector_spring_index = {0, 0, 0, 0, 0};
  EXPECT_THAT(refusal(s), HasSubstr("connector_params has 0 values, expected 1473"));
}

TEST(SceneValidate, RefusesBadEnvironmentAndConstants) {
  Scene s = two_masses();
  s.env.terrain.clear();
  EXPECT_THAT(refusal(s), HasSubstr("env/terrain is empty"));
  s.env.terrain = {Segment{-1e9, 0, 0}, Segment{0.2, 0, 0}, Segment{0.1, 0, 0}};
  EXPECT_THAT(refusal(s), HasSubstr("segment 2 starts at 0.1 u, before segment 1"));
  s.env.terrain = {Segment{-1e9, 0, 0}, Segment{0.1, 0, 0}, Segment{0.105, 0, 0}};
  EXPECT_THAT(refusal(s), HasSubstr("only 0.005 u after segment 1 (the minimum width is 0.01 u)"));
  // the first segment extends to -inf: its x_start is not compared
  s.env.terrain = {Segment{5.0, 0, 0}, Segment{0.1, 0.04, 0}, Segment{0.11, 0, 0}};
  EXPECT_EQ(refusal(s), "");

  s = two_masses();
  s.env.friction = -1;
  EXPECT_THAT(refusal(s), HasSubstr("env/friction = -1 is out of range [0, 100]"));
  s = two_masses();
  s.env.wind_period = 0;
  EXPECT_THAT(refusal(s), HasSubstr("env/wind_period"));
  s = two_masses();
  s.constants.dt = 0;
  EXPECT_THAT(refusal(s), HasSubstr("dt = 0 s must be positive"));
  s = two_masses();
  s.constants.substeps = -1;
  EXPECT_THAT(refusal(s), HasSubstr("substeps = -1"));
}

TEST(SceneStability, TwoMassesMatchTheClosedForm) {
  // two springs between mass 0 (m = 1) and mass 1 (m = 4): Σk = 400 at both, worst is mass 0
  Scene s = two_masses(100.0);
  s.spring_i.push_back(1);
  s.spring_j.push_back(0);
  s.rest_length.push_back(0.05);
  s.stiffness.push_back(300.0);
  s.amplitude.push_back(0.0);
  s.damping.push_back(0.0);
  s.mass[1] = 4.0;
  ASSERT_EQ(refusal(s), "");
  const double dt = 0.004;
  EXPECT_DOUBLE_EQ(stability_number(s, dt), dt * std::sqrt(400.0 / 1.0));
  EXPECT_DOUBLE_EQ(stability_number(s, 0.01), 0.01 * 20.0);
  s.mass[0] = 16.0;  // now mass 1 is the worst: sqrt(400 / 4) = 10
  EXPECT_DOUBLE_EQ(stability_number(s, dt), dt * 10.0);
}

TEST(SceneStability, SubstepsGrowWithStiffness) {
  int prev = 0;
  for (double k : {1e2, 1e4, 1e5, 1e6, 1e7, 1e8}) {
    const Scene s = two_masses(k);
    const int n = substeps_needed(s);
    const double number = s.constants.dt * std::sqrt(k);
    EXPECT_EQ(n, std::max(1, static_cast<int>(std::ceil(number / 1.9)))) << "k = " << k;
    EXPECT_LT(number / n, 1.9);
    EXPECT_GE(n, prev);
    prev = n;
  }
  EXPECT_EQ(substeps_needed(two_masses(1e2)), 1);
  EXPECT_GT(prev, 10);
  // a tighter limit needs more substeps
  EXPECT_GT(substeps_needed(two_masses(1e6), 0.5), substeps_needed(two_masses(1e6), 1.9));
}

TEST(SceneBodyLength, PerAgentAndMean) {
  Scene s = one_agent();
  add_agent(s, 0.5, 0.2);
  EXPECT_NEAR(body_length(s, 0), 0.3, 1e-15);
  EXPECT_NEAR(body_length(s, 1), 0.2, 1e-15);
  EXPECT_NEAR(mean_body_length(s), 0.25, 1e-15);
  EXPECT_THROW(body_length(s, 2), InputError);
  // without agents: the extent of all masses
  EXPECT_DOUBLE_EQ(mean_body_length(two_masses()), 0.05);
}

}  // namespace
}  // namespace divcoll::sim
