#include "stages/deploy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "collective/references.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "stages/driver.hpp"
#include "stages/payload.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {
namespace {

// one episode: an agent alone (type = −1) or a pair of a collective type
struct Episode {
  int32_t type = -1, replicate = 0, a = 0, b = 0, pair = 0;
};
template <class Ar>
void serialize(Ar& ar, Episode& e, unsigned) {
  ar & e.type & e.replicate & e.a & e.b & e.pair;
}
// an episode's result, with the hidden states it keeps (weak connectors deployed as trained)
struct DeployDone {
  EpisodeDone done;
  std::vector<float> hidden;          // K × sim::kHidden
  std::vector<int32_t> hidden_index;  // K: step · 5 + connector spring
  double early_bl = 0;                // travel at deploy.early_step, BL (when it is recorded)
  std::vector<float> inputs;          // K × 11, the network inputs at hidden_index (analysis.familiarity_on = inputs)
};
template <class Ar>
void serialize(Ar& ar, DeployDone& d, unsigned) {
  ar & d.done & d.hidden & d.hidden_index & d.early_bl & d.inputs;
}

// the deployment (SPEC §8) as a plan: one round per environment, one item per episode (every agent alone,
// then every collective type × replicate × pair); the rows of round e are row e of every dataset
class DeployPlan final : public Plan {
 public:
  DeployPlan(const DeployDef& def, const std::vector<morph::Agent>& agents, DeployTypes types)
      : def_(def), agents_(agents), types_(std::move(types.names)), weights_(std::move(types.weights)),
        tethers_(std::move(types.tethers)), diverse_(std::move(types.diverse)), E_(static_cast<int>(D_.environments.size())),
        NP_(D_.pairs), pop_(static_cast<int>(agents.size())), R_(def_.connectors.replicates),
        T_(static_cast<int>(types_.size())), per_episode_(D_.episode_steps * 5),
        K_(D_.hidden_subsample == 0 ? per_episode_ : std::min(per_episode_, (D_.hidden_subsample + NP_ - 1) / NP_)),
        early_(D_.early_step > 0), inputs_(def_.analysis.familiarity_on == "inputs") {
    // hidden states (SPEC §8.2) of the weak connectors deployed as trained, at most deploy.hidden_subsample
    // per (type, replicate, environment): K per episode, drawn from the episode's own stream. The joint network
    // (connectors.network) has none per spring: its runs keep no hidden states (and run no analysis)
    for (int t = 0; t < T_ && def_.connectors.network != "joint"; ++t)
      if (types_[t] == "weak_uniform@uniform" || types_[t] == "weak_diverse@diverse") hidden_types_.push_back(t);
    // the reference connectors (deploy.references), each on uniform and on diverse pairs, after the trained types
    if (D_.references)
      for (std::string_view name : collective::kReferenceConnectors) {
        refs_.push_back(collective::reference_connector(def_.connectors, name));
        for (const char* dep : {"uniform", "diverse"}) ref_names_.push_back(std::string(name) + "@" + dep);
      }
    RT_ = static_cast<int>(ref_names_.size());
    Rng prng = make_rng(def_.seed, kDeployStage, 0);
    diverse_pairs_ = collective::random_pairs(prng, pop_, NP_);
    uniform_pairs_ = collective::deploy_uniform_pairs(D_, def_.connectors);
  }
  Info info() const override { return {"deploy", "deploy", "envs_done", "environment", "episodes", 1}; }
  int rounds() const override { return E_; }
  std::vector<Attribute> attributes() const override {
    std::vector<Attribute> a = {{"environments", io::join(D_.environments)}, {"types", io::join(types_)}};
    if (RT_ > 0) a.push_back({"references", io::join(ref_names_)});
    return a;
  }
  Records setup() override {
    Record r{"deploy/diverse_pairs", {static_cast<uint64_t>(NP_), 2}, {}, std::vector<int32_t>{}};
    for (int q = 0; q < NP_; ++q) {
      r.rows.push_back(q);
      std::get<std::vector<int32_t>>(r.values).insert(std::get<std::vector<int32_t>>(r.values).end(),
                                                      {diverse_pairs_[q].first, diverse_pairs_[q].second});
    }
    return {r};
  }
  void start(int, const StoredState&) override {}
  void take_input(int round, const std::string&) override { env_ = round; }
  std::vector<std::string> items(int) override {
    std::vector<std::string> items;
    for (int i = 0; i < pop_; ++i) items.push_back(pack(Episode{-1, 0, i, i}));
    for (int t = 0; t < T_; ++t)
      for (int r = 0; r < R_; ++r)
        for (int q = 0; q < NP_; ++q) {
          const auto& pr = diverse_[t] ? diverse_pairs_[q] : uniform_pairs_[q];
          items.push_back(pack(Episode{t, r, pr.first, pr.second, q}));
        }
    // reference type T + rt: reference rt / 2 on uniform (rt even) or diverse (rt odd) pairs
    for (int rt = 0; rt < RT_; ++rt)
      for (int q = 0; q < NP_; ++q) {
        const auto& pr = rt % 2 ? diverse_pairs_[q] : uniform_pairs_[q];
        items.push_back(pack(Episode{T_ + rt, 0, pr.first, pr.second, q}));
      }
    done_.assign(items.size(), {});
    return items;
  }
  // pairs (two agents' networks and a connector's) before agents alone, so that a round ends on cheap items
  std::vector<double> item_costs(int) const override {
    std::vector<double> c(done_.size(), 3.0);
    std::fill(c.begin(), c.begin() + std::min<size_t>(c.size(), pop_), 1.0);
    return c;
  }
  std::string compute(const std::string& bytes) override {
    const Episode e = unpack<Episode>(bytes);
    const std::string& env = D_.environments[env_];
    DeployDone d;
    const bool hidden = e.type >= 0 && std::find(hidden_types_.begin(), hidden_types_.end(), e.type) != hidden_types_.end();
    collective::PairOutcome o;
    sim::RunOptions opt = physics_.options();
    opt.steps = D_.episode_steps;
    opt.record = early_;
    sim::RunResult full;
    if (e.type < 0) {
      o = collective::run_alone(sim_, agents_[e.a], env, physics_.contact, opt, &full, collective::alone_feature_offset(D_, agents_[e.a]));
      if (early_) d.early_bl = collective::travel_at(full, sim::kAgentMasses, D_.early_step) / morph::body_length(agents_[e.a]);
    } else {
      opt.record_hidden = hidden;
      opt.record_inputs = hidden && inputs_;
      const bool ref = e.type >= T_;
      const std::vector<double>& w = ref ? refs_[(e.type - T_) / 2].weights : weights_[e.type][e.replicate];
      const collective::Tether& tether = ref ? refs_[(e.type - T_) / 2].tether : tethers_[e.type];
      o = collective::run_pair(sim_, agents_[e.a], agents_[e.b], w, tether, env, physics_.contact, opt, &full);
      if (early_)
        d.early_bl = collective::travel_at(full, 2 * sim::kAgentMasses, D_.early_step) /
                     (0.5 * (morph::body_length(agents_[e.a]) + morph::body_length(agents_[e.b])));
      if (hidden) {
        // the episode's stream: (seed, deploy + 1, the episode's index in every environment's list)
        const uint64_t item = ((static_cast<uint64_t>(env_) * T_ + e.type) * R_ + e.replicate) * NP_ + e.pair;
        Rng rng = make_rng(def_.seed, kDeployStage + 1, item);
        const std::vector<int64_t> picked = sorted_sample(rng, per_episode_, K_);
        d.hidden_index.assign(picked.begin(), picked.end());
        constexpr int H = sim::kHidden;
        d.hidden.assign(d.hidden_index.size() * H, std::numeric_limits<float>::quiet_NaN());
        if (o.status == sim::Status::ok)
          for (size_t k = 0; k < d.hidden_index.size(); ++k)
            for (int q = 0; q < H; ++q) d.hidden[k * H + q] = static_cast<float>(full.hidden[d.hidden_index[k] * H + q]);
        if (inputs_) {
          constexpr int I = sim::kConnectorInputs;
          d.inputs.assign(d.hidden_index.size() * I, std::numeric_limits<float>::quiet_NaN());
          if (o.status == sim::Status::ok)
            for (size_t k = 0; k < d.hidden_index.size(); ++k)
              for (int q = 0; q < I; ++q) d.inputs[k * I + q] = static_cast<float>(full.inputs[d.hidden_index[k] * I + q]);
        }
      }
    }
    d.done = EpisodeDone{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status)};
    return pack(d);
  }
  void reduce(int, int64_t i, const std::string& bytes) override { done_[i] = unpack<DeployDone>(bytes); }
  // row ei of every dataset
  Records end_round(int ei) override {
    std::vector<double> au, ab, cu, cb, ae, ce, ru, rb, re;
    std::vector<uint8_t> as, cs, rs;
    ref_mean_.assign(RT_, 0.0), ref_ok_.assign(RT_, 0);
    const size_t trained_end = static_cast<size_t>(pop_) + static_cast<size_t>(T_) * R_ * NP_;
    type_mean_.assign(T_, 0.0), type_ok_.assign(T_, 0), type_bad_.assign(T_, 0);
    std::vector<std::vector<float>> hid(hidden_types_.size());
    std::vector<std::vector<int32_t>> hid_index(hidden_types_.size());
    std::vector<std::vector<float>> hid_inputs(hidden_types_.size());
    for (size_t q = 0; q < done_.size(); ++q) {
      const DeployDone& dd = done_[q];
      const EpisodeDone& d = dd.done;
      if (q >= trained_end) {  // a reference connector's pair
        const int rt = static_cast<int>((q - trained_end) / NP_);
        ru.push_back(d.travel_u), rb.push_back(d.travel_bl), rs.push_back(d.status), re.push_back(dd.early_bl);
        if (d.status == 0 && std::isfinite(d.travel_bl)) ref_mean_[rt] += d.travel_bl, ++ref_ok_[rt];
        continue;
      }
      const bool alone = q < static_cast<size_t>(pop_);
      const int t = alone ? -1 : static_cast<int>((q - pop_) / (static_cast<size_t>(R_) * NP_));
      if (!dd.hidden_index.empty()) {
        const int h = static_cast<int>(std::find(hidden_types_.begin(), hidden_types_.end(), t) - hidden_types_.begin());
        hid[h].insert(hid[h].end(), dd.hidden.begin(), dd.hidden.end());
        hid_index[h].insert(hid_index[h].end(), dd.hidden_index.begin(), dd.hidden_index.end());
        hid_inputs[h].insert(hid_inputs[h].end(), dd.inputs.begin(), dd.inputs.end());
      }
      (alone ? au : cu).push_back(d.travel_u);
      (alone ? ab : cb).push_back(d.travel_bl);
      (alone ? as : cs).push_back(d.status);
      (alone ? ae : ce).push_back(dd.early_bl);
      if (!alone) {
        if (d.status == 0 && std::isfinite(d.travel_bl)) type_mean_[t] += d.travel_bl, ++type_ok_[t];
        else ++type_bad_[t];
      }
    }
    alone_mean_ = 0;
    int an = 0;
    for (size_t i = 0; i < ab.size(); ++i)
      if (as[i] == 0 && std::isfinite(ab[i])) alone_mean_ += ab[i], ++an;
    alone_mean_ = an ? alone_mean_ / an : NAN;
    const uint64_t E = E_, P = pop_, T = T_, R = R_, N = NP_, K = K_;
    Records out = {{"deploy/agents/travel_u", {E, P}, {ei}, au},
                   {"deploy/agents/travel_bl", {E, P}, {ei}, ab},
                   {"deploy/agents/status", {E, P}, {ei}, as},
                   {"deploy/collectives/travel_u", {E, T, R, N}, {ei}, cu},
                   {"deploy/collectives/travel_bl", {E, T, R, N}, {ei}, cb},
                   {"deploy/collectives/status", {E, T, R, N}, {ei}, cs}};
    if (early_) {
      out.push_back({"deploy/agents/travel_bl_early", {E, P}, {ei}, ae});
      out.push_back({"deploy/collectives/travel_bl_early", {E, T, R, N}, {ei}, ce});
    }
    if (RT_ > 0) {
      const uint64_t RT = RT_;
      out.push_back({"deploy/references/travel_u", {E, RT, N}, {ei}, ru});
      out.push_back({"deploy/references/travel_bl", {E, RT, N}, {ei}, rb});
      out.push_back({"deploy/references/status", {E, RT, N}, {ei}, rs});
      if (early_) out.push_back({"deploy/references/travel_bl_early", {E, RT, N}, {ei}, re});
    }
    for (size_t h = 0; h < hidden_types_.size(); ++h) {
      out.push_back({"deploy/hidden/" + types_[hidden_types_[h]] + "/states", {E, R, N, K, static_cast<uint64_t>(sim::kHidden)},
                     {ei}, hid[h]});
      out.push_back({"deploy/hidden/" + types_[hidden_types_[h]] + "/index", {E, R, N, K}, {ei}, hid_index[h]});
      if (inputs_)
        out.push_back({"deploy/hidden/" + types_[hidden_types_[h]] + "/inputs",
                       {E, R, N, K, static_cast<uint64_t>(sim::kConnectorInputs)}, {ei}, hid_inputs[h]});
    }
    return out;
  }
  std::string summary(int ei) const override {
    char b[256];
    std::snprintf(b, sizeof b, "%s: agents alone %.3f BL |", D_.environments[ei].c_str(), alone_mean_);
    std::string s = b;
    for (int t = 0; t < T_; ++t) {
      std::snprintf(b, sizeof b, " %s %.3f%s", types_[t].c_str(), type_ok_[t] ? type_mean_[t] / type_ok_[t] : NAN,
                    type_bad_[t] ? (" (" + std::to_string(type_bad_[t]) + " not ok)").c_str() : "");
      s += b;
    }
    for (int rt = 0; rt < RT_; ++rt) {
      std::snprintf(b, sizeof b, " %s %.3f", ref_names_[rt].c_str(), ref_ok_[rt] ? ref_mean_[rt] / ref_ok_[rt] : NAN);
      s += b;
    }
    return s;
  }

 private:
  const DeployDef def_;
  const sim::RunPhysics& physics_ = def_.physics;  // run.contact, run.precision
  const config::RunConfig::Deploy& D_ = def_.deploy;
  const std::vector<morph::Agent>& agents_;
  const std::vector<std::string> types_;
  const std::vector<std::vector<std::vector<double>>> weights_;  // [type][replicate] → params
  const std::vector<collective::Tether> tethers_;
  const std::vector<bool> diverse_;
  const int E_, NP_, pop_, R_, T_, per_episode_, K_;
  const bool early_;  // deploy.early_step: travel at that step too (from the recorded run)
  const bool inputs_;  // analysis.familiarity_on = inputs: the connectors' inputs beside the hidden states
  std::vector<int> hidden_types_;
  std::vector<collective::ReferenceConnector> refs_;  // deploy.references: free, passive, follower
  std::vector<std::string> ref_names_;               // <name>@uniform, <name>@diverse per reference
  int RT_ = 0;                                       // reference types: 2 per reference
  std::vector<double> ref_mean_;
  std::vector<int> ref_ok_;
  std::vector<std::pair<int, int>> diverse_pairs_, uniform_pairs_;
  sim::Simulator sim_;
  int env_ = 0;
  std::vector<DeployDone> done_;
  std::vector<double> type_mean_;
  std::vector<int> type_ok_, type_bad_;
  double alone_mean_ = 0;
};

}  // namespace

DeployDef deploy_def(const config::RunConfig& cfg) {
  return {cfg.run.seed, cfg.deploy, cfg.connectors, cfg.analysis, config::run_physics(cfg)};
}

std::unique_ptr<Plan> make_deploy_plan(const DeployDef& def, const std::vector<morph::Agent>& agents,
                                       DeployTypes types) {
  return std::make_unique<DeployPlan>(def, agents, std::move(types));
}

void run_deploy_stage(Driver& driver) {
  const DeployDef def = deploy_def(driver.config());
  io::h5::File& file = driver.file();
  const std::vector<morph::Agent> agents = load_population(def.physics, file);
  const int R = def.connectors.replicates;
  DeployTypes types;
  for (const std::string& kind : def.connectors.kinds) {
    DIVCOLL_THROW_UNLESS(file.has("connectors/" + kind + "/params"),
                         file.file() << " has no trained " << kind << " connectors: run the connectors stage first");
    const std::vector<std::vector<double>> reps = io::read_weights(file, "connectors/" + kind, R);
    for (const char* dep : {"uniform", "diverse"}) {
      types.names.push_back(kind + "@" + dep);
      types.weights.push_back(reps);
      types.tethers.push_back(collective::tether(def.connectors, kind));
      types.diverse.push_back(std::string(dep) == "diverse");
    }
  }
  DeployPlan plan(def, agents, std::move(types));
  driver.drive(plan);
}

}  // namespace divcoll::stages
