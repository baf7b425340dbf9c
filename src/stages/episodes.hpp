// episodes of agents alone, pairs and chains, forward only, in several environments: the deployments of the
// specialists and of the graded populations (EpisodesPlan), and the helpers the scaling chains share with them
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"
#include "config/config.hpp"
#include "sim/engine.hpp"
#include "stages/payload.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

// a pair or chain episode: the agents (heap order), which connector weights, which environment
struct GroupEpisode {
  int32_t weights = 0, env = 0;
  std::vector<int32_t> agents;
};
template <class Ar>
void serialize(Ar& ar, GroupEpisode& e, unsigned) {
  ar & e.weights & e.env & e.agents;
}

// the novel environments of deploy.environments (every one but flat), in order
std::vector<std::string> novel_environments(const config::RunConfig::Deploy& deploy);

// n distinct agents out of `population` (partial Fisher–Yates)
std::vector<int32_t> distinct_agents(Rng& rng, int population, int n);

// one agent alone, a pair (or, with `chains`, a heap-order chain), forward only
EpisodeDone group_episode(sim::Simulator& sim, const GroupEpisode& e, const std::vector<morph::Agent>& agents,
                          const std::vector<std::vector<double>>& weights, const collective::Tether& tether,
                          const sim::RunPhysics& physics, const std::vector<std::string>& envs, int steps, bool chains);

// an episode's cost for the farm's order: its agents (a connector costs about as much as an agent's network)
double episode_cost(const GroupEpisode& e);

// mean over ok episodes [b, e) of `d`, and how many were not ok
std::pair<double, int> ok_mean(const std::vector<EpisodeDone>& d, size_t b, size_t e);

// pairs (and agents alone) in several environments, forward only, as a plan: one round per environment,
// its items from `round_items`; the round's results, in item order, are cut into consecutive parts, and
// part k is row e of <parts[k].group>/travel_u, travel_bl and status (dims: environments × parts[k].dims).
// It keeps a reference to `agents`, which must outlive it
class EpisodesPlan final : public Plan {
 public:
  struct Part {
    std::string group;
    std::vector<uint64_t> dims;  // after the environment axis; the part's items: their product
  };
  using Summary = std::function<std::string(int env, const std::vector<EpisodeDone>& round)>;
  EpisodesPlan(std::string label, std::string group, const std::vector<morph::Agent>& agents,
               std::vector<std::vector<double>> weights, collective::Tether tether, sim::RunPhysics physics,
               std::vector<std::string> envs, int steps,
               std::vector<Part> parts, std::function<std::vector<GroupEpisode>(int env)> round_items, Summary summary)
      : label_(std::move(label)), group_(std::move(group)), agents_(agents), weights_(std::move(weights)),
        tether_(tether), physics_(physics), envs_(std::move(envs)), steps_(steps), parts_(std::move(parts)),
        round_items_(std::move(round_items)), summary_(std::move(summary)) {}
  Info info() const override {
    Info i{label_, group_, "envs_done", "environment", "episodes", 1};
    i.independent_rounds = true;  // an episode's task names its environment; nothing passes between rounds
    return i;
  }
  int rounds() const override { return static_cast<int>(envs_.size()); }
  void start(int, const StoredState&) override {}
  std::vector<std::string> items(int e) override {
    std::vector<std::string> items;
    costs_.clear();
    for (const GroupEpisode& g : round_items_(e)) items.push_back(pack(g)), costs_.push_back(episode_cost(g));
    done_[e].clear();
    return items;
  }
  std::vector<double> item_costs(int) const override { return costs_; }
  std::string compute(const std::string& bytes) override {
    return pack(group_episode(sim_, unpack<GroupEpisode>(bytes), agents_, weights_, tether_, physics_, envs_, steps_, false));
  }
  void reduce(int e, int64_t, const std::string& bytes) override { done_[e].push_back(unpack<EpisodeDone>(bytes)); }
  Records end_round(int e) override {
    const std::vector<EpisodeDone>& done = done_.at(e);
    Records out;
    size_t at = 0;
    for (const Part& p : parts_) {
      std::vector<uint64_t> dims = {static_cast<uint64_t>(envs_.size())};
      dims.insert(dims.end(), p.dims.begin(), p.dims.end());
      const size_t n = std::accumulate(p.dims.begin(), p.dims.end(), size_t{1}, std::multiplies<>());
      DIVCOLL_DEMAND(at + n <= done.size());
      std::vector<double> tu, tb;
      std::vector<uint8_t> st;
      for (size_t q = at; q < at + n; ++q)
        tu.push_back(done[q].travel_u), tb.push_back(done[q].travel_bl), st.push_back(done[q].status);
      at += n;
      out.push_back({p.group + "/travel_u", dims, {e}, std::move(tu)});
      out.push_back({p.group + "/travel_bl", dims, {e}, std::move(tb)});
      out.push_back({p.group + "/status", dims, {e}, std::move(st)});
    }
    DIVCOLL_DEMAND(at == done.size());
    return out;
  }
  std::string summary(int e) const override { return summary_(e, done_.at(e)); }

 private:
  const std::string label_, group_;
  const std::vector<morph::Agent>& agents_;
  const std::vector<std::vector<double>> weights_;
  const collective::Tether tether_;
  const sim::RunPhysics physics_;  // run.contact, run.precision
  const std::vector<std::string> envs_;
  const int steps_;
  const std::vector<Part> parts_;
  const std::function<std::vector<GroupEpisode>(int)> round_items_;
  const Summary summary_;
  sim::Simulator sim_;
  std::map<int, std::vector<EpisodeDone>> done_;  // each environment's results (several are farmed at once)
  std::vector<double> costs_;  // the last items()' costs (episode_cost)
};

}  // namespace divcoll::stages
