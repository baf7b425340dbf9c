#include "stages/episodes.hpp"

#include <cmath>
#include <numeric>

#include "collective/pairs.hpp"

namespace divcoll::stages {

std::vector<std::string> novel_environments(const config::RunConfig::Deploy& deploy) {
  std::vector<std::string> out;
  for (const auto& e : deploy.environments)
    if (e != "flat") out.push_back(e);
  return out;
}

// n distinct agents out of `population` (partial Fisher–Yates)
std::vector<int32_t> distinct_agents(Rng& rng, int population, int n) {
  std::vector<int32_t> idx(population);
  std::iota(idx.begin(), idx.end(), 0);
  for (int k = 0; k < n; ++k) std::swap(idx[k], idx[k + uniform_int(rng, population - k)]);
  idx.resize(n);
  return idx;
}

// one agent alone, a pair (or, with `chains`, a heap-order chain), forward only
EpisodeDone group_episode(sim::Simulator& sim, const GroupEpisode& e, const std::vector<morph::Agent>& agents,
                          const std::vector<std::vector<double>>& weights, const collective::Tether& tether,
                          const sim::RunPhysics& physics, const std::vector<std::string>& envs, int steps, bool chains) {
  std::vector<const morph::Agent*> ptr;
  for (int32_t a : e.agents) ptr.push_back(&agents[a]);
  const collective::PairOutcome o =
      ptr.size() == 1 ? collective::run_alone(sim, *ptr[0], envs[e.env], physics, steps)
      : !chains ? collective::run_pair(sim, *ptr[0], *ptr[1], weights[e.weights], tether, envs[e.env], physics, steps, false)
                      : collective::run_chain(sim, ptr, weights[e.weights], tether, envs[e.env], physics, steps);
  return EpisodeDone{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status)};
}

// an episode's cost for the farm's order: its agents (a connector costs about as much as an agent's network)
double episode_cost(const GroupEpisode& e) { return 2.0 * static_cast<double>(e.agents.size()) - 1.0; }

// mean over ok episodes [b, e) of `d`, and how many were not ok
std::pair<double, int> ok_mean(const std::vector<EpisodeDone>& d, size_t b, size_t e) {
  double s = 0;
  int n = 0, bad = 0;
  for (size_t q = b; q < e; ++q)
    if (d[q].status == 0 && std::isfinite(d[q].travel_bl)) s += d[q].travel_bl, ++n;
    else ++bad;
  return {n ? s / n : NAN, bad};
}

}  // namespace divcoll::stages
