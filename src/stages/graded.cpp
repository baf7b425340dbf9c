#include "stages/graded.hpp"

#include <cstdio>
#include <map>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "io/run_read.hpp"
#include "stages/connectors.hpp"
#include "stages/driver.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {

GradedShape graded_shape(const std::vector<evo::Individual>& main) {
  GradedShape g;
  std::map<uint32_t, int> bodies;
  for (const auto& x : main) ++bodies[x.agent.cells];
  int best = -1;
  for (const auto& [c, n] : bodies)
    if (n > best) best = n, g.cells = c;
  std::map<uint32_t, int> sp;
  for (const auto& x : main)
    if (x.agent.cells == g.cells) ++sp[x.agent.springs];
  best = -1;
  for (const auto& [c, n] : sp)
    if (n > best) best = n, g.springs = c;
  return g;
}

GradedDef graded_def(const config::RunConfig& cfg) {
  return {cfg.run.seed, cfg.graded, cfg.agents, cfg.connectors, cfg.deploy, config::run_physics(cfg)};
}

std::pair<AgentsDef, AgentsSpec> graded_agents(const GradedDef& gdef, int v, GradedShape shape) {
  const std::string base = std::string("graded/") + kGradedPopulations[v];
  AgentsDef def{gdef.seed, gdef.agents, gdef.physics};
  def.agents.population = gdef.graded.population;
  def.agents.body_fixed = true;
  def.agents.rest_moves = false;
  AgentsSpec spec;
  spec.group = base + "/agents";
  spec.label = std::string("graded ") + kGradedPopulations[v];
  spec.stream = kGradedStage + 100000 * v;
  spec.fixed_cells = shape.cells;
  spec.spring_descriptor = true;
  if (v == 1) {
    // no evolution: GP controllers from different seeds, each with a lineage's gradient budget
    def.agents.springs_fixed = true;
    def.agents.epochs = (gdef.agents.generations + 1) * gdef.agents.epochs;
    def.agents.generations = 0;
    spec.fixed_springs = shape.springs;
  }
  return {def, spec};
}

std::unique_ptr<EpisodesPlan> make_graded_deploy_plan(const GradedDef& def, int v,
                                                      const std::vector<morph::Agent>& agents,
                                                      std::vector<std::vector<double>> weights,
                                                      std::vector<std::pair<int, int>> pairs) {
  const std::vector<std::string>& envs = def.deploy.environments;
  const int R = def.connectors.replicates, NP = def.deploy.pairs;
  const int GP = def.graded.population;
  const std::string base = std::string("graded/") + kGradedPopulations[v];
  auto round_items = [R, GP, pairs = std::move(pairs)](int e) {
    std::vector<GroupEpisode> eps;
    for (int i = 0; i < GP; ++i) eps.push_back({0, e, {i}});
    for (int r = 0; r < R; ++r)
      for (const auto& [a, b] : pairs) eps.push_back({r, e, {a, b}});
    return eps;
  };
  auto summary = [envs, R, NP, GP](int e, const std::vector<EpisodeDone>& d) {
    const size_t n = static_cast<size_t>(R) * NP;
    char b[256];
    std::snprintf(b, sizeof b, "%s: alone %.2f, pairs %.2f BL", envs[e].c_str(), ok_mean(d, 0, GP).first,
                  ok_mean(d, GP, GP + n).first);
    return std::string(b);
  };
  const uint64_t uG = GP, uR = R, uN = NP;
  return std::make_unique<EpisodesPlan>(std::string("graded ") + kGradedPopulations[v] + " deploy", base, agents,
                                        std::move(weights), collective::tether(def.connectors, "weak_diverse"), def.physics, envs,
                                        def.deploy.episode_steps,
                                        std::vector<EpisodesPlan::Part>{{base + "/deploy/agents", {uG}},
                                                                        {base + "/deploy/pairs", {uR, uN}}},
                                        round_items, summary);
}

void run_graded_stage(Driver& driver) {
  const GradedDef gdef = graded_def(driver.config());
  const auto& C = gdef.connectors;
  io::h5::File& file = driver.file();
  const int R = C.replicates, NP = gdef.deploy.pairs;
  const int GP = gdef.graded.population;
  io::h5::Node stage = file.group("graded");
  stage.write_string("environments", io::join(gdef.deploy.environments));
  stage.write_string("populations", "same_shape,same_shape_springs");

  const GradedShape shape = graded_shape(io::read_final_population(file));
  stage.write_int("shape_cells", shape.cells);
  stage.write_int("shape_springs", shape.springs);

  const char* sources[2] = {"behaviour,springs,pairing", "behaviour,pairing"};
  for (int v = 0; v < 2; ++v) {
    const std::string base = std::string("graded/") + kGradedPopulations[v];
    driver.with_status(base, [&] {
      file.group(base).write_string("diversity_sources", sources[v]);

      // 1. the population: one body (and for v = 1 one spring genotype), rest positions fixed
      const auto [def, spec] = graded_agents(gdef, v, shape);
      driver.with_status(spec.group, [&] { run_agents(driver, def, spec); });
      const std::vector<morph::Agent> agents = load_population(gdef.physics, file, spec.group);

      // 2. weak connectors trained on diverse pairs of this population, on flat (its anchors stored beside them)
      if (!file.has(base + "/connectors")) file.create_group(base + "/connectors");
      store_anchors(driver, spec.group, agents);
      std::vector<ConnectorSlot> slots;
      for (int r = 0; r < R; ++r)
        slots.push_back({collective::tether(C, "weak_diverse"), true, "flat", kGradedStage + 100000 * v + 50000 + r,
                         base + "/connectors/weak_diverse", r});
      TrainSpec ts{base + "/connectors", std::string("graded ") + kGradedPopulations[v] + " connectors",
                   C.iterations, C.batch_pairs, C.episode_steps};
      auto weights = train_connectors(driver, agents, slots, ts);

      // 3. agents alone and diverse pairs in every environment
      Rng prng = make_rng(gdef.seed, kGradedStage + 100000 * v + 90000, 0);
      auto pairs = collective::random_pairs(prng, GP, NP);
      Record dp{base + "/diverse_pairs", {static_cast<uint64_t>(NP), 2}, {}, std::vector<int32_t>{}};
      for (int q = 0; q < NP; ++q) {
        dp.rows.push_back(q);
        std::get<std::vector<int32_t>>(dp.values).insert(std::get<std::vector<int32_t>>(dp.values).end(),
                                                         {pairs[q].first, pairs[q].second});
      }
      driver.write({dp});
      const auto plan = make_graded_deploy_plan(gdef, v, agents, std::move(weights), std::move(pairs));
      driver.drive(*plan);
    });
  }
}

}  // namespace divcoll::stages
