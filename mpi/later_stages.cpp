#include "mpi/later_stages.hpp"

#include <functional>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>

#include "collective/pairs.hpp"
#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "mpi/agents_stage.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/deploy_stage.hpp"
#include "mpi/driver.hpp"
#include "mpi/protocol.hpp"

namespace divcoll::mpi {
namespace {


// a pair or chain episode: the agents (heap order), which connector weights, which environment
struct GroupEpisode {
  int32_t weights = 0, env = 0;
  std::vector<int32_t> agents;
};
template <class Ar>
void serialize(Ar& ar, GroupEpisode& e, unsigned) {
  ar & e.weights & e.env & e.agents;
}


std::vector<std::string> novel_environments(const io::RunConfig& cfg) {
  std::vector<std::string> out;
  for (const auto& e : cfg.deploy.environments)
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
EpisodeDone group_episode(sim::Simulator& sim, const GroupEpisode& e, const std::vector<collective::Agent>& agents,
                          const std::vector<std::vector<double>>& weights, const collective::Tether& tether,
                          const sim::RunPhysics& physics, const std::vector<std::string>& envs, int steps, bool chains) {
  std::vector<const collective::Agent*> ptr;
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

// pairs (and agents alone) in several environments, forward only, as a plan: one round per environment,
// its items from `round_items`; the round's results, in item order, are cut into consecutive parts, and
// part k is row e of <parts[k].group>/travel_u, travel_bl and status (dims: environments × parts[k].dims)
class EpisodesPlan final : public Plan {
 public:
  struct Part {
    std::string group;
    std::vector<uint64_t> dims;  // after the environment axis; the part's items: their product
  };
  using Summary = std::function<std::string(int env, const std::vector<EpisodeDone>& round)>;
  EpisodesPlan(std::string label, std::string group, const std::vector<collective::Agent>& agents,
               std::vector<std::vector<double>> weights, collective::Tether tether, sim::RunPhysics physics, std::vector<std::string> envs, int steps,
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
  const std::vector<collective::Agent>& agents_;
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


}  // namespace

void run_specialists_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                           const std::function<void()>& checkpoint) {
  const auto& S = cfg.specialists;
  const std::vector<std::string> envs = novel_environments(cfg);
  const int E = static_cast<int>(envs.size()), R = S.replicates, NP = cfg.deploy.pairs;
  const std::vector<collective::Agent> agents = load_population(comm, cfg, file);
  const int pop = static_cast<int>(agents.size());

  io::h5::Node stage = file.group("specialists");
  stage.write_string("environments", join(envs));
  stage.write_int("replicates", R);

  // 1. train: weak connectors on diverse pairs, each in its own environment
  std::vector<ConnectorSlot> slots;
  for (int e = 0; e < E; ++e)
    for (int r = 0; r < R; ++r)
      slots.push_back({collective::tether(cfg, "weak_diverse"), true, envs[e], kSpecialistsStage + e * R + r,
                       "specialists/" + envs[e], r});
  TrainSpec spec{"specialists", "specialists", S.iterations, cfg.connectors.batch_pairs, cfg.connectors.episode_steps};
  const std::vector<std::vector<double>> weights = train_connectors(comm, cfg, file, agents, slots, spec, checkpoint);

  // 2. deploy each in its environment on the deployment stage's diverse pairs: one round per environment
  Rng prng = make_rng(cfg.run.seed, kDeployStage, 0);
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
  EpisodesPlan plan("specialists deploy", "specialists", agents, weights, collective::tether(cfg, "weak_diverse"), io::run_physics(cfg), envs,
                    cfg.deploy.episode_steps, {{"specialists", {static_cast<uint64_t>(R), static_cast<uint64_t>(NP)}}},
                    round_items, summary);
  drive(comm, cfg, file, plan, checkpoint);
}

namespace {

// the scaling chains (SPEC §7.4) as a plan: one round per environment, one item per chain
// (size × variant × replicate × draw); the chains: uniform = N clones of agent `draw`; diverse = N distinct
// agents drawn per (size, replicate, draw); both in heap order. Weights 0..R−1: weak uniform-trained;
// R..2R−1: weak diverse-trained
class ScalingPlan final : public Plan {
 public:
  ScalingPlan(const io::RunConfig& cfg, const std::vector<collective::Agent>& agents, std::vector<std::vector<double>> weights)
      : cfg_(cfg), S_(cfg.scaling), agents_(agents), weights_(std::move(weights)),
        E_(static_cast<int>(cfg.deploy.environments.size())), NS_(static_cast<int>(S_.sizes.size())), D_(S_.draws),
        R_(cfg.connectors.replicates), chains_(NS_ * 2) {
    const int pop = static_cast<int>(agents.size());
    for (int si = 0; si < NS_; ++si)
      for (int r = 0; r < R_; ++r)
        for (int q = 0; q < D_; ++q) {
          chains_[si * 2].push_back(std::vector<int32_t>(S_.sizes[si], q));
          Rng rng = make_rng(cfg.run.seed, kScalingStage + si, static_cast<uint64_t>(r) * D_ + q);
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
    return {{"environments", join(cfg_.deploy.environments)}, {"variants", std::string("uniform,diverse")}};
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
    return pack(group_episode(sim_, unpack<GroupEpisode>(bytes), agents_, weights_, collective::tether(cfg_, "weak_uniform"),
                              io::run_physics(cfg_), cfg_.deploy.environments, S_.episode_steps, true));
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
    std::string s = cfg_.deploy.environments[ei] + ":";
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
  const io::RunConfig& cfg_;
  const io::RunConfig::Scaling& S_;
  const std::vector<collective::Agent>& agents_;
  const std::vector<std::vector<double>> weights_;
  const int E_, NS_, D_, R_;
  std::vector<std::vector<std::vector<int32_t>>> chains_;  // [size·2 + variant][replicate·D + draw]
  sim::Simulator sim_;
  std::map<int, std::vector<EpisodeDone>> done_;  // each environment's results (several are farmed at once)
  std::vector<double> costs_;  // the last items()' costs (episode_cost)
};

}  // namespace

void run_scaling_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                       const std::function<void()>& checkpoint) {
  const int R = cfg.connectors.replicates;
  const std::vector<collective::Agent> agents = load_population(comm, cfg, file);
  std::vector<std::vector<double>> weights = io::read_weights(file, "connectors/weak_uniform", R);
  for (auto& w : io::read_weights(file, "connectors/weak_diverse", R)) weights.push_back(std::move(w));
  ScalingPlan plan(cfg, agents, std::move(weights));
  drive(comm, cfg, file, plan, checkpoint);
}

void run_graded_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                      const std::function<void()>& checkpoint) {
  const std::vector<std::string>& envs = cfg.deploy.environments;
  const int R = cfg.connectors.replicates, NP = cfg.deploy.pairs;
  const int GP = cfg.graded.population;
  io::h5::Node stage = file.group("graded");
  stage.write_string("environments", join(envs));
  stage.write_string("populations", "same_shape,same_shape_springs");

  // the most common body of the main population (ties: the lowest genotype), and the most common spring
  // genotype among its agents of that body
  uint32_t shape = 0, springs = 0;
  {
    const auto main = io::read_final_population(file);
    std::map<uint32_t, int> bodies;
    for (const auto& x : main) ++bodies[x.agent.cells];
    int best = -1;
    for (const auto& [c, n] : bodies)
      if (n > best) best = n, shape = c;
    std::map<uint32_t, int> sp;
    for (const auto& x : main)
      if (x.agent.cells == shape) ++sp[x.agent.springs];
    best = -1;
    for (const auto& [c, n] : sp)
      if (n > best) best = n, springs = c;
  }
  stage.write_int("shape_cells", shape);
  stage.write_int("shape_springs", springs);

  const char* names[2] = {"same_shape", "same_shape_springs"};
  const char* sources[2] = {"behaviour,springs,pairing", "behaviour,pairing"};
  for (int v = 0; v < 2; ++v) {
    const std::string base = std::string("graded/") + names[v];
    run_with_status(file, base, checkpoint, [&] {
      file.group(base).write_string("diversity_sources", sources[v]);

      // 1. the population: one body (and for v = 1 one spring genotype), rest positions fixed
      io::RunConfig pc = cfg;
      pc.agents.population = GP;
      pc.agents.body_fixed = true;
      pc.agents.rest_moves = false;
      AgentsSpec spec;
      spec.group = base + "/agents";
      spec.label = std::string("graded ") + names[v];
      spec.stream = kGradedStage + 100000 * v;
      spec.fixed_cells = shape;
      spec.spring_descriptor = true;
      if (v == 1) {
        // no evolution: GP controllers from different seeds, each with a lineage's gradient budget
        pc.agents.springs_fixed = true;
        pc.agents.epochs = (cfg.agents.generations + 1) * cfg.agents.epochs;
        pc.agents.generations = 0;
        spec.fixed_springs = springs;
      }
      run_with_status(file, spec.group, checkpoint, [&] { run_agents_stage(comm, pc, file, checkpoint, spec); });
      const std::vector<collective::Agent> agents = load_population(comm, cfg, file, spec.group);

      // 2. weak connectors trained on diverse pairs of this population, on flat (its anchors stored beside them)
      if (!file.has(base + "/connectors")) file.create_group(base + "/connectors");
      store_anchors(comm, file, spec.group, agents);
      std::vector<ConnectorSlot> slots;
      for (int r = 0; r < R; ++r)
        slots.push_back({collective::tether(cfg, "weak_diverse"), true, "flat", kGradedStage + 100000 * v + 50000 + r,
                         base + "/connectors/weak_diverse", r});
      TrainSpec ts{base + "/connectors", std::string("graded ") + names[v] + " connectors", cfg.connectors.iterations,
                   cfg.connectors.batch_pairs, cfg.connectors.episode_steps};
      const auto weights = train_connectors(comm, cfg, file, agents, slots, ts, checkpoint);

      // 3. agents alone and diverse pairs in every environment
      Rng prng = make_rng(cfg.run.seed, kGradedStage + 100000 * v + 90000, 0);
      const auto pairs = collective::random_pairs(prng, GP, NP);
      Record dp{base + "/diverse_pairs", {static_cast<uint64_t>(NP), 2}, {}, std::vector<int32_t>{}};
      for (int q = 0; q < NP; ++q) {
        dp.rows.push_back(q);
        std::get<std::vector<int32_t>>(dp.values).insert(std::get<std::vector<int32_t>>(dp.values).end(),
                                                         {pairs[q].first, pairs[q].second});
      }
      write_records(comm, file, {dp});
      auto round_items = [&](int e) {
        std::vector<GroupEpisode> eps;
        for (int i = 0; i < GP; ++i) eps.push_back({0, e, {i}});
        for (int r = 0; r < R; ++r)
          for (const auto& [a, b] : pairs) eps.push_back({r, e, {a, b}});
        return eps;
      };
      auto summary = [&](int e, const std::vector<EpisodeDone>& d) {
        const size_t n = static_cast<size_t>(R) * NP;
        char b[256];
        std::snprintf(b, sizeof b, "%s: alone %.2f, pairs %.2f BL", envs[e].c_str(), ok_mean(d, 0, GP).first,
                      ok_mean(d, GP, GP + n).first);
        return std::string(b);
      };
      const uint64_t uG = GP, uR = R, uN = NP;
      EpisodesPlan plan(std::string("graded ") + names[v] + " deploy", base, agents, weights,
                        collective::tether(cfg, "weak_diverse"), io::run_physics(cfg), envs, cfg.deploy.episode_steps,
                        {{base + "/deploy/agents", {uG}}, {base + "/deploy/pairs", {uR, uN}}}, round_items, summary);
      drive(comm, cfg, file, plan, checkpoint);
    });
  }
}

}  // namespace divcoll::mpi
