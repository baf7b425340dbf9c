#include "stages/analysis.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include "analysis/behaviour.hpp"
#include "analysis/dtw.hpp"
#include "analysis/pacmap.hpp"
#include "analysis/stats.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "io/run_file.hpp"
#include "io/run_read.hpp"
#include "stages/deploy.hpp"
#include "stages/driver.hpp"
#include "stages/episodes.hpp"
#include "stages/payload.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {
namespace {

using io::h5::Dims;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::array<std::string, 2>& kTypes = kAnalysisTypes;

// round 1: an agent alone, recorded
struct AloneDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;
  std::vector<double> behaviour;  // frames × 22, empty unless ok
};
template <class Ar>
void serialize(Ar& ar, AloneDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status & d.behaviour;
}

// round 2: a pair of one of the two types, recorded, with each agent's DTW against its alone behaviour
struct PairTask {
  int32_t type = 0, replicate = 0, a = 0, b = 0;
};
template <class Ar>
void serialize(Ar& ar, PairTask& t, unsigned) {
  ar & t.type & t.replicate & t.a & t.b;
}
struct PairDone {
  double travel_u = 0;
  uint8_t status = 0;
  double dtw[2] = {kNaN, kNaN};
};
template <class Ar>
void serialize(Ar& ar, PairDone& d, unsigned) {
  ar & d.travel_u & d.status & d.dtw;
}

// familiarity: one PaCMAP fit of a replicate's training and novel hidden states. The task names the fit;
// the rank that computes it samples the states from its own copy of deploy's hidden states (every rank
// reads them), so a task is a few bytes rather than up to 2 × max_states × 32 floats
struct FitTask {
  int32_t novel = 0, type = 0, replicate = 0;  // novel environment (index into the novel list), type, replicate
};
template <class Ar>
void serialize(Ar& ar, FitTask& t, unsigned) {
  ar & t.novel & t.type & t.replicate;
}
struct FitDone {
  int32_t n_train = 0, n_novel = 0;  // the states of the fit, training first
  std::vector<int64_t> counts;       // 6
  std::vector<int64_t> counts_calibrated;  // 6 at analysis.calibrated_cell_scale; empty when it is 0
  std::vector<float> embedding;      // (n_train + n_novel) × 2
};
template <class Ar>
void serialize(Ar& ar, FitDone& d, unsigned) {
  ar & d.n_train & d.n_novel & d.counts & d.counts_calibrated & d.embedding;
}

bool same_bits(double x, double y) { return (std::isnan(x) && std::isnan(y)) || x == y; }

// the finite states (width `dim`: hidden states or network inputs) of replicate r in environment e (ok episodes
// only), at most max_states of them
std::vector<float> states_of(const std::vector<float>& all, int dim, int e, int r, int R, int NP, int K, int max_states,
                             Rng& rng) {
  std::vector<int64_t> rows;
  for (int q = 0; q < NP; ++q)
    for (int k = 0; k < K; ++k) {
      const int64_t row = ((static_cast<int64_t>(e) * R + r) * NP + q) * K + k;
      const float* s = &all[row * dim];
      if (std::all_of(s, s + dim, [](float v) { return std::isfinite(v); })) rows.push_back(row);
    }
  std::vector<float> out;
  for (int64_t i : sorted_sample(rng, static_cast<int64_t>(rows.size()), max_states))
    out.insert(out.end(), &all[rows[i] * dim], &all[rows[i] * dim] + dim);
  return out;
}

std::vector<double> finite(const std::vector<double>& v) {
  std::vector<double> out;
  for (double x : v)
    if (std::isfinite(x)) out.push_back(x);
  return out;
}

// the adversity analysis (§8.1) as a plan: one round per environment, of two passes: every agent alone
// (its behaviour kept), then every pair of the two types (each agent's DTW against its alone behaviour,
// which every rank gets as the pass's input). Its rows stay its state: the statistics (finish()) are
// taken over every environment's rows, restored after a resume
class AdversityPlan final : public Plan {
 public:
  AdversityPlan(const AnalysisDef& def, const std::vector<morph::Agent>& agents,
                std::array<std::vector<std::vector<double>>, 2> weights,
                std::array<std::vector<std::pair<int, int>>, 2> pairs,
                std::array<int, 2> type_index, int deploy_types, std::vector<std::string> novel, Deployed deployed)
      : def_(def), agents_(agents), weights_(std::move(weights)), pairs_(std::move(pairs)), type_index_(type_index),
        novel_(std::move(novel)), deployed_(std::move(deployed)), E_(static_cast<int>(envs_.size())),
        NP_(def_.deploy.pairs), R_(def_.connectors.replicates), T_(deploy_types), pop_(static_cast<int>(agents.size())),
        tether_(collective::strength_tether(def_.connectors, "weak")) {
    rec_ = physics_.options();
    rec_.steps = def_.deploy.episode_steps;
    rec_.record = true;
    const int frames = def_.deploy.episode_steps / A_.dtw_every + 1;
    dopt_.band = static_cast<int>(std::ceil(A_.dtw_band * frames));
    dopt_.cost = A_.dtw_cost == "squared_sqrt" ? analysis::DtwCost::squared_sqrt : analysis::DtwCost::euclidean;
    dopt_.step = A_.dtw_step == "symmetric2" ? analysis::DtwStep::symmetric2 : analysis::DtwStep::symmetric1;
  }
  Info info() const override {
    Info i{"analysis adversity", "analysis", "dtw_envs_done", "environment", "episodes", 1};
    i.passes = 2;
    return i;
  }
  int rounds() const override { return E_; }
  std::vector<Attribute> attributes() const override {
    return {{"types", kTypes[0] + "," + kTypes[1]},
            {"environments", io::join(envs_)},
            {"novel_environments", io::join(novel_)}};
  }
  std::vector<std::string> state_paths() const override {
    std::vector<std::string> p;
    for (const std::string& t : kTypes)
      for (const char* d : {"/dtw", "/worse_slot"}) p.push_back("analysis/adversity/" + t + d);
    return p;
  }
  std::vector<std::pair<std::string, int64_t>> state_attributes() const override {
    return {{"adversity/deploy_mismatches", mismatches_}};
  }
  void start(int done, const StoredState& s) override {
    const size_t n = static_cast<size_t>(E_) * R_ * NP_;
    for (int t = 0; t < 2; ++t) {
      dtw_[t].assign(2 * n, kNaN);
      worse_[t].assign(n, 0);
      if (done == 0) continue;
      const std::vector<double>& d = s.at("analysis/adversity/" + kTypes[t] + "/dtw");
      const std::vector<double>& w = s.at("analysis/adversity/" + kTypes[t] + "/worse_slot");
      std::copy(d.begin(), d.end(), dtw_[t].begin());
      for (size_t k = 0; k < n; ++k) worse_[t][k] = static_cast<uint8_t>(w[k]);
    }
    const auto m = s.find("adversity/deploy_mismatches");
    mismatches_ = m == s.end() ? 0 : static_cast<int64_t>(m->second[0]);
    behaviour_.assign(pop_, {});
  }
  // pass 1: every agent's alone behaviour, for the pairs' DTW
  std::string round_input(int step) override { return step % 2 == 1 ? pack(behaviour_) : std::string(); }
  void take_input(int step, const std::string& input) override {
    env_ = step / 2, pass_ = step % 2;
    if (step % 2 == 1) behaviour_ = unpack<std::vector<std::vector<double>>>(input);
  }
  std::vector<std::string> items(int step) override {
    std::vector<std::string> items;
    if (step % 2 == 0) {
      for (int32_t a = 0; a < pop_; ++a) items.push_back(pack(a));
      alone_.assign(pop_, {});
    } else {
      for (int t = 0; t < 2; ++t)
        for (int r = 0; r < R_; ++r)
          for (int q = 0; q < NP_; ++q) items.push_back(pack(PairTask{t, r, pairs_[t][q].first, pairs_[t][q].second}));
      done_.assign(items.size(), {});
    }
    return items;
  }
  std::string compute(const std::string& bytes) override { return pass_ == 0 ? alone(bytes) : pair(bytes); }
  void reduce(int step, int64_t i, const std::string& bytes) override {
    if (step % 2 == 0) alone_[i] = unpack<AloneDone>(bytes);
    else done_[i] = unpack<PairDone>(bytes);
  }
  Records end_round(int step) override {
    const int ei = step / 2;
    if (step % 2 == 0) {
      alone_bl_.assign(pop_, kNaN);
      round_mismatches_ = 0;
      for (int a = 0; a < pop_; ++a) {
        AloneDone& d = alone_[a];
        const size_t k = static_cast<size_t>(ei) * pop_ + a;
        if (!same_bits(d.travel_u, deployed_.alone[k]) || d.status != deployed_.alone_status[k]) ++round_mismatches_;
        alone_bl_[a] = d.status == 0 ? d.travel_bl : kNaN;
        behaviour_[a] = std::move(d.behaviour);
      }
      return {};
    }
    const hsize_t hE = E_, hR = R_, hN = NP_;
    const size_t at = static_cast<size_t>(ei) * R_ * NP_;
    Records out;
    sum_ = {}, cnt_ = {};
    for (int t = 0; t < 2; ++t) {
      std::vector<double> dtw;
      std::vector<uint8_t> worse;
      for (int r = 0; r < R_; ++r)
        for (int q = 0; q < NP_; ++q) {
          const PairDone& d = done_[(static_cast<size_t>(t) * R_ + r) * NP_ + q];
          const size_t k = ((static_cast<size_t>(ei) * T_ + type_index_[t]) * R_ + r) * NP_ + q;
          if (!same_bits(d.travel_u, deployed_.pairs[k]) || d.status != deployed_.pairs_status[k]) ++round_mismatches_;
          dtw.push_back(d.dtw[0]);
          dtw.push_back(d.dtw[1]);
          // the worse agent travelled less alone; a tie (clones) makes the posterior one the worse
          const uint8_t w = alone_bl_[pairs_[t][q].second] < alone_bl_[pairs_[t][q].first] ? 1 : 0;
          worse.push_back(w);
          for (int slot = 0; slot < 2; ++slot)
            if (std::isfinite(d.dtw[slot])) sum_[t][slot == w ? 0 : 1] += d.dtw[slot], cnt_[t][slot == w ? 0 : 1] += 1;
        }
      std::copy(dtw.begin(), dtw.end(), dtw_[t].begin() + 2 * at);
      std::copy(worse.begin(), worse.end(), worse_[t].begin() + at);
      const std::string g = "analysis/adversity/" + kTypes[t];
      out.push_back({g + "/dtw", {hE, hR, hN, 2}, {ei}, std::move(dtw)});
      out.push_back({g + "/worse_slot", {hE, hR, hN}, {ei}, std::move(worse)});
    }
    mismatches_ += round_mismatches_;
    return out;
  }
  std::string summary(int ei) const override {
    char b[256];
    std::snprintf(b, sizeof b, "%s: DTW per step worse/better:", envs_[ei].c_str());
    std::string s = b;
    for (int t = 0; t < 2; ++t) {
      std::snprintf(b, sizeof b, " %s %.4f/%.4f", kTypes[t].c_str(), sum_[t][0] / cnt_[t][0], sum_[t][1] / cnt_[t][1]);
      s += b;
    }
    s += " u";
    if (round_mismatches_ > 0)
      s += "; WARNING " + std::to_string(round_mismatches_) + " re-simulated episode(s) differ from deploy's travel";
    return s;
  }
  // the statistics (§8.3) over every environment's rows
  Records finish() override {
    std::array<std::array<std::vector<double>, 2>, 2> per_rep;  // [type][worse/better] over replicates
    for (int t = 0; t < 2; ++t)
      for (int w = 0; w < 2; ++w)
        for (int r = 0; r < R_; ++r) {
          double s = 0, n = 0;
          for (int e = 0; e < E_; ++e)
            for (int q = 0; q < NP_; ++q) {
              const size_t k = (static_cast<size_t>(e) * R_ + r) * NP_ + q;
              const double v = dtw_[t][2 * k + (w == 0 ? worse_[t][k] : 1 - worse_[t][k])];
              if (std::isfinite(v)) s += v, n += 1;
            }
          per_rep[t][w].push_back(n > 0 ? s / n : kNaN);
        }
    std::vector<double> rep_means, welch;
    summary_.clear();
    for (int t = 0; t < 2; ++t)
      for (int w = 0; w < 2; ++w) {
        rep_means.insert(rep_means.end(), per_rep[t][w].begin(), per_rep[t][w].end());
        const std::vector<double> x = finite(per_rep[t][w]);
        const analysis::Interval ci =
            analysis::bootstrap_ci(x, seed_for(def_.seed, kAnalysisStage + 3, 2 * t + w), A_.bootstrap_resamples);
        summary_.insert(summary_.end(), {analysis::mean(x), ci.lo, ci.hi});
      }
    for (int w = 0; w < 2; ++w) {
      const analysis::TestResult tr = analysis::welch_t_test(finite(per_rep[0][w]), finite(per_rep[1][w]));
      welch.insert(welch.end(), {tr.statistic, tr.df, tr.p});
    }
    welch_p_ = {welch[2], welch[5]};
    const hsize_t hR = R_;
    return {{"analysis/adversity/replicate_means", {2, 2, hR}, {0, 1}, rep_means},
            {"analysis/adversity/summary", {2, 2, 3}, {0, 1}, summary_},
            {"analysis/adversity/welch", {2, 3}, {0, 1}, welch}};
  }
  std::string finish_summary() const override {
    std::string s = "DTW per step (u), mean over replicates [95% CI]:";
    char b[256];
    for (int t = 0; t < 2; ++t) {
      const double* x = &summary_[6 * t];
      std::snprintf(b, sizeof b, " %s worse %.4f [%.4f, %.4f] better %.4f [%.4f, %.4f];", kTypes[t].c_str(), x[0], x[1],
                    x[2], x[3], x[4], x[5]);
      s += b;
    }
    std::snprintf(b, sizeof b, " Welch p worse %.3g, better %.3g", welch_p_[0], welch_p_[1]);
    return s + b;
  }

 private:
  std::string alone(const std::string& bytes) {
    const int a = unpack<int32_t>(bytes);
    const std::string& env = envs_[env_];
    sim::RunResult full;
    const double offset = collective::alone_feature_offset(def_.deploy, agents_[a]);
    const collective::PairOutcome o = collective::run_alone(sim_, agents_[a], env, physics_.contact, rec_, &full, offset);
    AloneDone d{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status), {}};
    if (o.status == sim::Status::ok)
      d.behaviour =
          analysis::agent_behaviour(collective::agent_scene(agents_[a], env, physics_.contact, {}, offset), full, 0, A_.dtw_every);
    return pack(d);
  }
  std::string pair(const std::string& bytes) {
    const PairTask t = unpack<PairTask>(bytes);
    const sim::Scene s =
        collective::pair_scene(agents_[t.a], agents_[t.b], weights_[t.type][t.replicate], tether_, envs_[env_], physics_.contact);
    const sim::RunResult r = sim_.run(s, rec_);
    PairDone d{r.travel, static_cast<uint8_t>(r.status), {kNaN, kNaN}};
    if (r.status == sim::Status::ok)
      for (int slot = 0; slot < 2; ++slot) {
        const std::vector<double>& ind = behaviour_[slot == 0 ? t.a : t.b];
        if (ind.empty()) continue;
        const std::vector<double> teth = analysis::agent_behaviour(s, r, slot, A_.dtw_every);
        const int n = static_cast<int>(teth.size() / analysis::kBehaviourFeatures);
        const int m = static_cast<int>(ind.size() / analysis::kBehaviourFeatures);
        const analysis::DtwResult x = analysis::dtw(teth.data(), n, ind.data(), m, analysis::kBehaviourFeatures, dopt_);
        d.dtw[slot] = x.distance / (A_.dtw_norm == "sum_lengths" ? n + m
                                    : A_.dtw_norm == "max_length" ? std::max(n, m)
                                                                  : x.path_length);
      }
    return pack(d);
  }

  const AnalysisDef def_;
  const sim::RunPhysics& physics_ = def_.physics;  // run.contact, run.precision
  const config::RunConfig::Analysis& A_ = def_.analysis;
  const std::vector<std::string>& envs_ = def_.deploy.environments;
  const std::vector<morph::Agent>& agents_;
  const std::array<std::vector<std::vector<double>>, 2> weights_;  // [type][replicate]
  const std::array<std::vector<std::pair<int, int>>, 2> pairs_;     // [type][pair]
  const std::array<int, 2> type_index_;                            // among deploy's types
  const std::vector<std::string> novel_;
  const Deployed deployed_;
  const int E_, NP_, R_, T_, pop_;
  const collective::Tether tether_;
  sim::RunOptions rec_;
  analysis::DtwOptions dopt_;
  sim::Simulator sim_;
  int env_ = 0, pass_ = 0;  // every rank: the step's environment and pass (0 alone, 1 pairs)
  std::vector<std::vector<double>> behaviour_;  // [agent] its alone behaviour in the current environment
  std::vector<AloneDone> alone_;
  std::vector<PairDone> done_;
  std::vector<double> alone_bl_;
  std::array<std::vector<double>, 2> dtw_;     // [type] E × R × NP × 2
  std::array<std::vector<uint8_t>, 2> worse_;  // [type] E × R × NP
  std::array<std::array<double, 2>, 2> sum_{}, cnt_{};
  int64_t mismatches_ = 0, round_mismatches_ = 0;
  std::vector<double> summary_;
  std::array<double, 2> welch_p_{};
};

// the familiarity analysis (§8.2) as a plan: one round per novel environment, one PaCMAP fit per type and
// replicate; Table S1 (finish()) over every environment's counts, restored after a resume
class FamiliarityPlan final : public Plan {
 public:
  // hidden: deploy's states of the two types (E × R × NP × K × dim: hidden states, dim 32, or with
  // analysis.familiarity_on = inputs the network inputs, dim 11; none when every round is done)
  FamiliarityPlan(const AnalysisDef& def, std::vector<std::string> novel, std::array<std::vector<float>, 2> hidden,
                  int K, int dim)
      : def_(def), novel_(std::move(novel)), K_(K), dim_(dim), hidden_(std::move(hidden)),
        EN_(static_cast<int>(novel_.size())), NP_(def_.deploy.pairs), R_(def_.connectors.replicates),
        e_flat_(static_cast<int>(std::find(envs_.begin(), envs_.end(), "flat") - envs_.begin())) {}
  Info info() const override {
    Info i{"analysis familiarity", "analysis", "familiarity_envs_done", "environment", "fits", 1};
    i.independent_rounds = true;  // an environment's fits read only their task and the hidden states
    return i;
  }
  int rounds() const override { return EN_; }
  std::vector<std::string> state_paths() const override {
    std::vector<std::string> p;
    for (const std::string& t : kTypes)
      for (const char* d : {"/counts", "/n_states"}) p.push_back("analysis/familiarity/" + t + d);
    return p;
  }
  void start(int done, const StoredState& s) override {
    const size_t n = static_cast<size_t>(EN_) * R_;
    for (int t = 0; t < 2; ++t) {
      counts_[t].assign(6 * n, 0);
      ns_[t].assign(2 * n, 0);
      if (done == 0) continue;
      const std::vector<double>& c = s.at("analysis/familiarity/" + kTypes[t] + "/counts");
      const std::vector<double>& m = s.at("analysis/familiarity/" + kTypes[t] + "/n_states");
      for (size_t k = 0; k < c.size(); ++k) counts_[t][k] = static_cast<int64_t>(c[k]);
      for (size_t k = 0; k < m.size(); ++k) ns_[t][k] = static_cast<int64_t>(m[k]);
    }
  }
  std::vector<std::string> items(int k) override {
    std::vector<std::string> items;
    for (int32_t t = 0; t < 2; ++t)
      for (int32_t r = 0; r < R_; ++r) items.push_back(pack(FitTask{k, t, r}));
    done_[k].assign(items.size(), {});
    return items;
  }
  std::string compute(const std::string& bytes) override {
    const FitTask task = unpack<FitTask>(bytes);
    const int k = task.novel, t = task.type, r = task.replicate;
    const int ei = static_cast<int>(std::find(envs_.begin(), envs_.end(), novel_[k]) - envs_.begin());
    const uint64_t item = (static_cast<uint64_t>(k) * 2 + t) * R_ + r;
    Rng srng = make_rng(def_.seed, kAnalysisStage + 1, item);
    std::vector<float> states = states_of(hidden_[t], dim_, e_flat_, r, R_, NP_, K_, A_.max_states, srng);
    const std::vector<float> nov = states_of(hidden_[t], dim_, ei, r, R_, NP_, K_, A_.max_states, srng);
    FitDone d;
    d.n_train = static_cast<int32_t>(states.size() / dim_);
    d.n_novel = static_cast<int32_t>(nov.size() / dim_);
    states.insert(states.end(), nov.begin(), nov.end());
    const int n = d.n_train + d.n_novel;
    d.counts.assign(6, 0);
    if (d.n_train < 1 || d.n_novel < 1 || n < 4) {
      d.embedding.assign(static_cast<size_t>(n) * 2, std::numeric_limits<float>::quiet_NaN());
      return pack(d);
    }
    std::vector<double> X(states.begin(), states.end());
    analysis::PacmapOptions po;
    po.seed = seed_for(def_.seed, kAnalysisStage + 2, item);
    const std::vector<double> y = analysis::pacmap_fit(X.data(), n, dim_, po);
    std::vector<uint8_t> label(n, 0);
    std::fill(label.begin() + d.n_train, label.end(), 1);
    const auto count = [&](double scale) {  // finer (or coarser) cells than the unit ones
      std::vector<double> cells = y;
      if (scale != 1.0)
        for (double& c : cells) c *= scale;
      const analysis::Occupancy o = analysis::classify_cells(cells, label);
      return std::vector<int64_t>{o.states_both, o.states_train_only, o.states_novel_only,
                                  o.cells_both,  o.cells_train_only,  o.cells_novel_only};
    };
    d.counts = count(A_.cell_scale);
    if (A_.calibrated_cell_scale > 0) d.counts_calibrated = count(A_.calibrated_cell_scale);
    d.embedding.assign(y.begin(), y.end());
    return pack(d);
  }
  void reduce(int k, int64_t i, const std::string& bytes) override {
    FitDone& d = done_[k][i];
    d = unpack<FitDone>(bytes);
    const size_t row = static_cast<size_t>(k) * R_ + i % R_;  // item i is type i / R, replicate i % R
    ns_[i / R_][2 * row] = d.n_train;
    ns_[i / R_][2 * row + 1] = d.n_novel;
  }
  Records end_round(int k) override {
    const hsize_t hEN = EN_, hR = R_, hS = 2 * static_cast<hsize_t>(A_.max_states);
    Records out;
    for (int t = 0; t < 2; ++t) {
      std::vector<int64_t> counts, calibrated;
      std::vector<float> emb;
      for (int r = 0; r < R_; ++r) {
        const FitDone& d = done_[k][static_cast<size_t>(t) * R_ + r];
        counts.insert(counts.end(), d.counts.begin(), d.counts.end());
        if (d.counts_calibrated.empty()) calibrated.insert(calibrated.end(), 6, 0);  // a fit with too few states
        else calibrated.insert(calibrated.end(), d.counts_calibrated.begin(), d.counts_calibrated.end());
        std::vector<float> padded(2 * hS, std::numeric_limits<float>::quiet_NaN());
        std::copy(d.embedding.begin(), d.embedding.end(), padded.begin());
        emb.insert(emb.end(), padded.begin(), padded.end());
      }
      const size_t at = static_cast<size_t>(k) * R_;
      std::copy(counts.begin(), counts.end(), counts_[t].begin() + 6 * at);
      const std::vector<int64_t> ns(ns_[t].begin() + 2 * at, ns_[t].begin() + 2 * (at + R_));
      const std::string g = "analysis/familiarity/" + kTypes[t];
      out.push_back({g + "/counts", {hEN, hR, 6}, {k}, std::move(counts)});
      if (A_.calibrated_cell_scale > 0)
        out.push_back({g + "/counts_calibrated", {hEN, hR, 6}, {k}, std::move(calibrated)});
      out.push_back({g + "/n_states", {hEN, hR, 2}, {k}, ns});
      out.push_back({g + "/embedding", {hEN, hR, hS, 2}, {k}, std::move(emb)});
    }
    done_.erase(k);
    return out;
  }
  std::string summary(int k) const override {
    std::string s = novel_[k] + ": states in shared cells:";
    char b[128];
    for (int t = 0; t < 2; ++t) {
      double both = 0, all = 0;
      for (int r = 0; r < R_; ++r) {
        const size_t row = static_cast<size_t>(k) * R_ + r;
        both += counts_[t][6 * row], all += ns_[t][2 * row] + ns_[t][2 * row + 1];
      }
      std::snprintf(b, sizeof b, " %s %.1f%%", kTypes[t].c_str(), all > 0 ? 100 * both / all : NAN);
      s += b;
    }
    return s;
  }
  // Table S1: per novel environment and count, the mean over replicates of each type and Welch's p
  Records finish() override {
    std::vector<double> table;
    for (int k = 0; k < EN_; ++k)
      for (int c = 0; c < 3; ++c) {
        std::array<std::vector<double>, 2> v;  // per type, over replicates with a fit
        for (int t = 0; t < 2; ++t)
          for (int r = 0; r < R_; ++r) {
            const size_t row = static_cast<size_t>(k) * R_ + r;
            const int64_t n = ns_[t][2 * row] + ns_[t][2 * row + 1];
            const std::vector<int64_t>& x = counts_[t];
            if (n > 0 && x[6 * row] + x[6 * row + 1] + x[6 * row + 2] == n)
              v[t].push_back(static_cast<double>(x[6 * row + c]));
          }
        table.insert(table.end(), {analysis::mean(v[1]), analysis::mean(v[0]), analysis::welch_t_test(v[1], v[0]).p});
      }
    Record r{"analysis/familiarity/table", {static_cast<hsize_t>(EN_), 3, 3}, {}, std::move(table)};
    for (int k = 0; k < EN_; ++k) r.rows.push_back(k);
    return {r};
  }

 private:
  const AnalysisDef def_;
  const config::RunConfig::Analysis& A_ = def_.analysis;
  const std::vector<std::string>& envs_ = def_.deploy.environments;
  const std::vector<std::string> novel_;
  const int K_;                                     // hidden states per episode
  const int dim_;                                   // values per state: 32 hidden, or 11 inputs
  const std::array<std::vector<float>, 2> hidden_;  // [type] deploy's hidden states
  const int EN_, NP_, R_, e_flat_;
  std::map<int, std::vector<FitDone>> done_;  // [environment] its fits (several rounds are farmed together)
  std::array<std::vector<int64_t>, 2> counts_, ns_;  // [type] novel E × R × 6, × 2
};

}  // namespace

AnalysisDef analysis_def(const config::RunConfig& cfg) {
  return {cfg.run.seed, cfg.analysis, cfg.deploy, cfg.connectors, config::run_physics(cfg)};
}

std::unique_ptr<Plan> make_adversity_plan(const AnalysisDef& def, const std::vector<morph::Agent>& agents,
                                          std::array<std::vector<std::vector<double>>, 2> weights,
                                          std::array<std::vector<std::pair<int, int>>, 2> pairs,
                                          std::array<int, 2> type_index, int deploy_types,
                                          std::vector<std::string> novel, Deployed deployed) {
  return std::make_unique<AdversityPlan>(def, agents, std::move(weights), std::move(pairs), type_index, deploy_types,
                                         std::move(novel), std::move(deployed));
}

std::unique_ptr<Plan> make_familiarity_plan(const AnalysisDef& def, std::vector<std::string> novel,
                                            std::array<std::vector<float>, 2> hidden, int K, int dim) {
  return std::make_unique<FamiliarityPlan>(def, std::move(novel), std::move(hidden), K, dim);
}

void run_analysis_stage(Driver& driver) {
  const AnalysisDef def = analysis_def(driver.config());
  io::h5::File& file = driver.file();
  const auto& D = def.deploy;
  const std::vector<std::string>& envs = D.environments;
  const int NP = D.pairs, R = def.connectors.replicates;
  DIVCOLL_THROW_UNLESS(complete(file, "deploy"), file.file() << ": the analysis stage needs a complete deploy stage");
  const std::vector<morph::Agent> agents = load_population(def.physics, file);

  // the two types among deploy's, their weights and pairs
  const std::vector<std::string> deploy_types = io::split(file.group("deploy").read_string("types"));
  std::array<int, 2> type_index{};
  std::array<std::vector<std::vector<double>>, 2> weights;
  for (int t = 0; t < 2; ++t) {
    const auto it = std::find(deploy_types.begin(), deploy_types.end(), kTypes[t]);
    DIVCOLL_THROW_UNLESS(it != deploy_types.end(), file.file() << ": deploy has no " << kTypes[t]
                                                               << " episodes; the analyses need connectors.kinds to"
                                                                  " include weak_uniform and weak_diverse");
    type_index[t] = static_cast<int>(it - deploy_types.begin());
    const std::string kind = kTypes[t].substr(0, kTypes[t].find('@'));
    weights[t] = io::read_weights(file, "connectors/" + kind, R);
  }
  std::array<std::vector<std::pair<int, int>>, 2> pairs;
  pairs[0] = collective::deploy_uniform_pairs(D, def.connectors);
  {
    const std::vector<int32_t> dp = io::read_checked<int32_t>(file, "deploy/diverse_pairs", "pair,slot",
                                                              Dims{static_cast<hsize_t>(NP), 2},
                                                              std::to_string(NP) + " pairs, as deploy.pairs says");
    for (int q = 0; q < NP; ++q) pairs[1].emplace_back(dp[2 * q], dp[2 * q + 1]);
  }
  const std::vector<std::string> novel = novel_environments(D);

  io::h5::Node stage = file.group("analysis");
  for (const char* g : {"analysis/adversity", "analysis/familiarity"})
    if (!file.has(g)) file.create_group(g);

  // adversity: deploy's results, to check the re-simulated episodes against (the master checks; every rank
  // reads, as with every read of the run file: a read made by one rank alone unbalances the ranks' HDF5
  // metadata caches, io/h5.hpp)
  const hsize_t hE = envs.size(), hT = deploy_types.size(), hR = R, hNP = NP;
  const Dims alone_dims{hE, static_cast<hsize_t>(agents.size())}, pairs_dims{hE, hT, hR, hNP};
  const std::string alone_why = std::to_string(hE) + " environments × " + std::to_string(agents.size()) +
                                " agents, as the config and the population say";
  const std::string pairs_why = std::to_string(hE) + " environments × " + std::to_string(hT) + " types × " +
                                std::to_string(R) + " replicates × " + std::to_string(NP) + " pairs, as the config says";
  Deployed deployed;
  deployed.alone = io::read_checked<double>(file, "deploy/agents/travel_u", "env,agent", alone_dims, alone_why);
  deployed.alone_status = io::read_checked<uint8_t>(file, "deploy/agents/status", "env,agent", alone_dims, alone_why);
  deployed.pairs =
      io::read_checked<double>(file, "deploy/collectives/travel_u", "env,type,replicate,pair", pairs_dims, pairs_why);
  deployed.pairs_status =
      io::read_checked<uint8_t>(file, "deploy/collectives/status", "env,type,replicate,pair", pairs_dims, pairs_why);
  AdversityPlan adversity(def, agents, weights, pairs, type_index, static_cast<int>(deploy_types.size()), novel,
                          std::move(deployed));
  driver.drive(adversity);

  // familiarity: flat's hidden states against each novel environment's (every rank reads them while
  // rounds are left: the rank that computes a fit samples its states)
  if (std::find(envs.begin(), envs.end(), "flat") != envs.end() && !novel.empty()) {
    std::array<std::vector<float>, 2> hidden;
    int K = 0;
    const int64_t fam_done = stage.has_attribute("familiarity_envs_done") ? stage.read_int("familiarity_envs_done") : 0;
    // analysis.familiarity_on: the hidden states (SPEC §8.2) or the network inputs at the same samples
    const bool on_inputs = def.analysis.familiarity_on == "inputs";
    const int dim = on_inputs ? sim::kConnectorInputs : sim::kHidden;
    const std::string what = on_inputs ? "/inputs" : "/states", axes = on_inputs ? "env,replicate,pair,sample,input"
                                                                                 : "env,replicate,pair,sample,neuron";
    if (fam_done < static_cast<int64_t>(novel.size()))
      for (int t = 0; t < 2; ++t) {
        const std::string p = "deploy/hidden/" + kTypes[t] + what;
        DIVCOLL_THROW_UNLESS(!on_inputs || file.has(p), file.file() << ": analysis.familiarity_on = inputs needs " << p
                                                                    << ", which the deploy stage stores only when it "
                                                                       "runs with analysis.familiarity_on = inputs");
        // the samples per episode (axis 3) as deploy stored them; the other axes as the config says
        const Dims d = io::run_file::layout(file, p, axes).dims;
        hidden[t] = io::read_checked<float>(file, p, axes, Dims{hE, hR, hNP, d[3], static_cast<hsize_t>(dim)},
                                            std::to_string(hE) + " environments × " + std::to_string(R) +
                                                " replicates × " + std::to_string(NP) + " pairs × samples × " +
                                                std::to_string(dim) + (on_inputs ? " inputs" : " neurons"));
        K = static_cast<int>(d[3]);
      }
    FamiliarityPlan familiarity(def, novel, std::move(hidden), K, dim);
    driver.drive(familiarity);
  }
}

}  // namespace divcoll::stages
