#include "analysis/behaviour.hpp"

#include "common/check.hpp"

namespace divcoll::analysis {

std::vector<double> agent_behaviour(const sim::Scene& scene, const sim::RunResult& run, int agent, int every) {
  if (run.status != sim::Status::ok) return {};
  const int N = scene.n_masses();
  DIVCOLL_THROW_UNLESS(every >= 1, "behaviour frames every " << every << " steps: must be at least 1");
  DIVCOLL_THROW_UNLESS(agent >= 0 && agent < scene.n_agents(), "agent " << agent << " is not in the scene");
  DIVCOLL_THROW_UNLESS(!run.x.empty() && run.x.size() % (2 * static_cast<size_t>(N)) == 0,
                       "the episode was not recorded (RunOptions::record)");
  const int steps = static_cast<int>(run.x.size() / (2 * static_cast<size_t>(N))) - 1;
  const int frames = steps / every + 1;
  const int32_t* idx = &scene.agent_mass_index[static_cast<size_t>(agent) * sim::kAgentMasses];
  double m_total = 0;
  for (int k = 0; k < sim::kAgentMasses; ++k) m_total += scene.mass[idx[k]];
  std::vector<double> out(static_cast<size_t>(frames) * kBehaviourFeatures);
  for (int f = 0; f < frames; ++f) {
    const double* x = &run.x[static_cast<size_t>(f) * every * N * 2];
    double cx = 0, cy = 0;
    for (int k = 0; k < sim::kAgentMasses; ++k) cx += scene.mass[idx[k]] * x[2 * idx[k]], cy += scene.mass[idx[k]] * x[2 * idx[k] + 1];
    cx /= m_total, cy /= m_total;
    double* row = &out[static_cast<size_t>(f) * kBehaviourFeatures];
    for (int k = 0; k < sim::kAgentMasses; ++k) row[2 * k] = x[2 * idx[k]] - cx, row[2 * k + 1] = x[2 * idx[k] + 1] - cy;
  }
  return out;
}

}  // namespace divcoll::analysis
