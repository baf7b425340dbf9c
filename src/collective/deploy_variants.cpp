#include "collective/deploy_variants.hpp"

#include <limits>

#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "config/pipeline.hpp"

namespace divcoll::collective {

Tether tether(const config::RunConfig::Connectors& connectors, std::string_view kind) {
  return {connectors.follower ? 0.0 : config::stiffness(connectors, kind), connectors.amplitude, connectors.damping};
}

Tether strength_tether(const config::RunConfig::Connectors& connectors, std::string_view strength) {
  return {connectors.follower ? 0.0 : config::strength_stiffness(connectors, strength), connectors.amplitude,
          connectors.damping};
}

std::vector<std::pair<int, int>> deploy_uniform_pairs(const config::RunConfig::Deploy& deploy,
                                                      const config::RunConfig::Connectors& connectors) {
  std::vector<std::pair<int, int>> p = uniform_pairs(deploy.pairs);
  if (deploy.uniform_agents == "held_out")
    for (auto& [a, b] : p) a += connectors.batch_pairs, b += connectors.batch_pairs;
  return p;
}

double alone_feature_offset(const config::RunConfig::Deploy& deploy, const Agent& a) {
  const std::string& f = deploy.feature_placement;
  if (f == "pair_mean") return 0.5 * (body_length(a) + kAgentGap);
  if (f == "rear") return body_length(a) + kAgentGap;
  return 0.0;
}

double travel_at(const sim::RunResult& r, int masses, int step) {
  if (r.status != sim::Status::ok) return std::numeric_limits<double>::quiet_NaN();
  const int N = masses;
  DIVCOLL_DEMAND(N > 0 && step >= 0 && r.x.size() >= static_cast<size_t>(step + 1) * N * 2);
  const double* x0 = r.x.data();
  const double* xs = r.x.data() + static_cast<size_t>(step) * N * 2;
  double s = 0, s0 = 0;
  for (int i = 0; i < N; ++i) {
    s += xs[2 * i];
    s0 += x0[2 * i];
  }
  return s / N - s0 / N;
}

}  // namespace divcoll::collective
