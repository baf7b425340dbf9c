// parity with an independent implementation of SPEC §2–§3: the five scenes of shared/testdata/parity,
// 300 steps with gradients; positions within 1e-7 u at every step, every gradient block within 1e-5
// relative (L2)
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "io/scene_file.hpp"
#include "io/trajectory_file.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

double rel_l2(const std::vector<double>& got, const std::vector<double>& want) {
  double num = 0, den = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    num += (got[i] - want[i]) * (got[i] - want[i]);
    den += want[i] * want[i];
  }
  return std::sqrt(num) / std::max(std::sqrt(den), 1e-300);
}

class Parity : public ::testing::TestWithParam<std::string> {};

TEST_P(Parity, TrajectoryAndGradientsMatchIndependentImplementation) {
  const std::string dir = testing::parity_dir();
  const sim::Scene scene = io::read_scene(dir + "/scene" + GetParam() + ".h5");
  const io::Trajectory want = io::read_trajectory(dir + "/expected" + GetParam() + ".h5");

  sim::RunOptions opt;
  opt.steps = want.steps;
  opt.grad = true;
  opt.record = true;
  const sim::RunResult got = sim::simulate(scene, opt);
  ASSERT_EQ(got.status, sim::Status::ok) << got.message;
  ASSERT_EQ(got.x.size(), want.x.size());

  // positions at every step
  double worst = 0;
  size_t worst_at = 0;
  for (size_t q = 0; q < want.x.size(); ++q) {
    const double d = std::abs(got.x[q] - want.x[q]);
    if (d > worst) worst = d, worst_at = q;
  }
  const size_t per_step = 2 * static_cast<size_t>(scene.n_masses());
  EXPECT_LT(worst, 1e-7) << "largest position error at step " << worst_at / per_step << ", mass "
                         << (worst_at % per_step) / 2;
  EXPECT_NEAR(got.travel, want.travel, 1e-7);

  // gradient blocks
  EXPECT_LT(rel_l2(got.grad_x0, want.grad_x0), 1e-5) << "grad/x0";
  EXPECT_LT(rel_l2(got.grad_rest_length, want.grad_rest_length), 1e-5) << "grad/rest_length";
  EXPECT_LT(rel_l2(got.grad_agent_params, want.grad_agent_params), 1e-5) << "grad/agent_params";
  if (scene.n_connectors() > 0) {
    EXPECT_LT(rel_l2(got.grad_connector_params, want.grad_connector_params), 1e-5) << "grad/connector_params";
  }
}

INSTANTIATE_TEST_SUITE_P(SharedVectors, Parity,
                         ::testing::Values("0_flat", "1_step_up", "2_gap", "3_sticky", "4_treadmill"),
                         [](const auto& info) { return info.param.substr(2); });

}  // namespace
}  // namespace divcoll
