#include "stages/scaling.hpp"

#include <cstdio>
#include <map>
#include <string>

#include "collective/deploy_variants.hpp"
#include "io/run_read.hpp"
#include "stages/driver.hpp"
#include "stages/episodes.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {
namespace {

// the scaling chains (SPEC §7.4) as a plan: one round per environment, one item per chain
// (size × variant × replicate × draw); the chains: uniform = N clones of agent `draw`; diverse = N distinct
// agents drawn per (size, replicate, draw); both in heap order. Weights 0..R−1: weak uniform-trained;
// R..2R−1: weak diverse-trained
class ScalingPlan final : public Plan {
 public:
  ScalingPlan(const ScalingDef& def, const std::vector<morph::Agent>& agents, std::vector<std::vector<double>> weights)
      : def_(def), agents_(agents), weights_(std::move(weights)), tether_(collective::tether(def_.connectors, "weak_uniform")),
        E_(static_cast<int>(envs_.size())), NS_(static_cast<int>(S_.sizes.size())), D_(S_.draws),
        R_(def_.connectors.replicates), chains_(NS_ * 2) {
    const int pop = static_cast<int>(agents.size());
    for (int si = 0; si < NS_; ++si)
      for (int r = 0; r < R_; ++r)
        for (int q = 0; q < D_; ++q) {
          chains_[si * 2].push_back(std::vector<int32_t>(S_.sizes[si], q));
          Rng rng = make_rng(def_.seed, kScalingStage + si, static_cast<uint64_t>(r) * D_ + q);
          chains_[si * 2 + 1].push_back(distinct_agents(rng, pop, S_.sizes[si]));
        }
  }
  Info info() const override {
    Info i{"scaling", "scaling", "envs_done", "environment", "chains", 1};
    i.independent_rounds = true;  // a chain's task names its environment; nothing passes between rounds
    return i;
  }
  int rounds() const override { return E_; }
  std::vector<Attribute> attributes() const override {
    return {{"environments", io::join(envs_)}, {"variants", std::string("uniform,diverse")}};
  }
  Records setup() override {
    Records out = {{"scaling/sizes", {static_cast<uint64_t>(NS_)}, {}, std::vector<int64_t>{}}};
    for (int si = 0; si < NS_; ++si) {
      out[0].rows.push_back(si);
      std::get<std::vector<int64_t>>(out[0].values).push_back(S_.sizes[si]);
      const int n = S_.sizes[si];
      Record r{"scaling/n" + std::to_string(n) + "/diverse_agents", {static_cast<uint64_t>(R_) * D_, static_cast<uint64_t>(n)}, {},
               std::vector<int32_t>{}};
      for (size_t k = 0; k < chains_[si * 2 + 1].size(); ++k) {
        r.rows.push_back(static_cast<int64_t>(k));
        auto& v = std::get<std::vector<int32_t>>(r.values);
        v.insert(v.end(), chains_[si * 2 + 1][k].begin(), chains_[si * 2 + 1][k].end());
      }
      out.push_back(std::move(r));
    }
    return out;
  }
  void start(int, const StoredState&) override {}
  std::vector<std::string> items(int ei) override {
    std::vector<std::string> items;
    costs_.clear();
    for (int si = 0; si < NS_; ++si)
      for (int v = 0; v < 2; ++v)
        for (int r = 0; r < R_; ++r)
          for (int q = 0; q < D_; ++q) {
            const GroupEpisode g{v * R_ + r, ei, chains_[si * 2 + v][static_cast<size_t>(r) * D_ + q]};
            items.push_back(pack(g)), costs_.push_back(episode_cost(g));
          }
    done_[ei].clear();
    return items;
  }
  // the 20-agent chains first, so that an environment's round ends on 5-agent ones
  std::vector<double> item_costs(int) const override { return costs_; }
  std::string compute(const std::string& bytes) override {
    return pack(group_episode(sim_, unpack<GroupEpisode>(bytes), agents_, weights_, tether_, physics_, envs_,
                              S_.episode_steps, true));
  }
  void reduce(int ei, int64_t, const std::string& bytes) override { done_[ei].push_back(unpack<EpisodeDone>(bytes)); }
  Records end_round(int ei) override {
    std::vector<double> tu, tb;
    std::vector<uint8_t> st;
    for (const auto& x : done_.at(ei)) tu.push_back(x.travel_u), tb.push_back(x.travel_bl), st.push_back(x.status);
    const std::vector<uint64_t> dims = {static_cast<uint64_t>(E_), static_cast<uint64_t>(NS_), 2, static_cast<uint64_t>(R_),
                                        static_cast<uint64_t>(D_)};
    return {{"scaling/travel_u", dims, {ei}, tu}, {"scaling/travel_bl", dims, {ei}, tb}, {"scaling/status", dims, {ei}, st}};
  }
  std::string summary(int ei) const override {
    std::string s = envs_[ei] + ":";
    char b[160];
    for (int si = 0; si < NS_; ++si)
      for (int v = 0; v < 2; ++v) {
        const size_t at = (static_cast<size_t>(si) * 2 + v) * R_ * D_;
        const auto [m, bad] = ok_mean(done_.at(ei), at, at + static_cast<size_t>(R_) * D_);
        std::snprintf(b, sizeof b, " N=%d %s %.3f%s", S_.sizes[si], v ? "diverse" : "uniform", m,
                      bad ? (" (" + std::to_string(bad) + " not ok)").c_str() : "");
        s += b;
      }
    return s + " BL";
  }

 private:
  const ScalingDef def_;
  const config::RunConfig::Scaling& S_ = def_.scaling;
  const std::vector<std::string>& envs_ = def_.deploy.environments;
  const sim::RunPhysics& physics_ = def_.physics;  // run.contact, run.precision
  const std::vector<morph::Agent>& agents_;
  const std::vector<std::vector<double>> weights_;
  const collective::Tether tether_;  // the weak connector's springs
  const int E_, NS_, D_, R_;
  std::vector<std::vector<std::vector<int32_t>>> chains_;  // [size·2 + variant][replicate·D + draw]
  sim::Simulator sim_;
  std::map<int, std::vector<EpisodeDone>> done_;  // each environment's results (several are farmed at once)
  std::vector<double> costs_;  // the last items()' costs (episode_cost)
};

}  // namespace

ScalingDef scaling_def(const config::RunConfig& cfg) {
  return {cfg.run.seed, cfg.scaling, cfg.deploy, cfg.connectors, config::run_physics(cfg)};
}

std::unique_ptr<Plan> make_scaling_plan(const ScalingDef& def, const std::vector<morph::Agent>& agents,
                                        std::vector<std::vector<double>> weights) {
  return std::make_unique<ScalingPlan>(def, agents, std::move(weights));
}

void run_scaling_stage(Driver& driver) {
  const ScalingDef def = scaling_def(driver.config());
  io::h5::File& file = driver.file();
  const int R = def.connectors.replicates;
  const std::vector<morph::Agent> agents = load_population(def.physics, file);
  std::vector<std::vector<double>> weights = io::read_weights(file, "connectors/weak_uniform", R);
  for (auto& w : io::read_weights(file, "connectors/weak_diverse", R)) weights.push_back(std::move(w));
  ScalingPlan plan(def, agents, std::move(weights));
  driver.drive(plan);
}

}  // namespace divcoll::stages
