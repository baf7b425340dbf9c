#include "stages/specialists.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "io/run_read.hpp"
#include "stages/connectors.hpp"
#include "stages/deploy.hpp"
#include "stages/driver.hpp"
#include "stages/episodes.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {

SpecialistsDef specialists_def(const config::RunConfig& cfg) {
  return {cfg.run.seed, cfg.specialists, cfg.connectors, cfg.deploy, config::run_physics(cfg)};
}

void run_specialists_stage(Driver& driver) {
  const SpecialistsDef def = specialists_def(driver.config());
  io::h5::File& file = driver.file();
  const auto& S = def.specialists;
  const auto& C = def.connectors;
  const std::vector<std::string> envs = novel_environments(def.deploy);
  const int E = static_cast<int>(envs.size()), R = S.replicates, NP = def.deploy.pairs;
  const std::vector<morph::Agent> agents = load_population(def.physics, file);
  const int pop = static_cast<int>(agents.size());

  io::h5::Node stage = file.group("specialists");
  stage.write_string("environments", io::join(envs));
  stage.write_int("replicates", R);

  // 1. train: weak connectors on diverse pairs, each in its own environment
  std::vector<ConnectorSlot> slots;
  for (int e = 0; e < E; ++e)
    for (int r = 0; r < R; ++r)
      slots.push_back({collective::tether(C, "weak_diverse"), true, envs[e], kSpecialistsStage + e * R + r,
                       "specialists/" + envs[e], r});
  TrainSpec spec{"specialists", "specialists", S.iterations, C.batch_pairs, C.episode_steps};
  const std::vector<std::vector<double>> weights = train_connectors(driver, agents, slots, spec);

  // 2. deploy each in its environment on the deployment stage's diverse pairs: one round per environment
  Rng prng = make_rng(def.seed, kDeployStage, 0);
  const auto pairs = collective::random_pairs(prng, pop, NP);
  auto round_items = [&](int e) {
    std::vector<GroupEpisode> eps;
    for (int r = 0; r < R; ++r)
      for (const auto& [a, b] : pairs) eps.push_back({e * R + r, e, {a, b}});
    return eps;
  };
  // the best replicate in the environment
  auto summary = [&](int e, const std::vector<EpisodeDone>& d) {
    double best = -INFINITY;
    int br = -1, bad = 0;
    for (int r = 0; r < R; ++r) {
      const auto [m, nb] = ok_mean(d, static_cast<size_t>(r) * NP, static_cast<size_t>(r + 1) * NP);
      bad += nb;
      if (std::isfinite(m) && m > best) best = m, br = r;
    }
    char b[256];
    std::snprintf(b, sizeof b, "%s: best replicate %d: %.3f BL%s", envs[e].c_str(), br, best,
                  bad ? (" (" + std::to_string(bad) + " episodes not ok)").c_str() : "");
    return std::string(b);
  };
  EpisodesPlan plan("specialists deploy", "specialists", agents, weights, collective::tether(C, "weak_diverse"), def.physics, envs,
                    def.deploy.episode_steps, {{"specialists", {static_cast<uint64_t>(R), static_cast<uint64_t>(NP)}}},
                    round_items, summary);
  driver.drive(plan);
}

}  // namespace divcoll::stages
