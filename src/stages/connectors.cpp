// connector training as a plan (stages/plan.hpp): every slot (a connector being trained) in lock-step, one round
// per iteration, one item per pair episode. Two plans: the plain one (Adam or a normalized step on the
// summed gradient) and, when any of the optimisation keys differs from its default, the extended
// one (evo::ConnectorOptimizer: decaying rate, keep-best on a validation batch, truncated
// backpropagation, gradient averaging, CMA-ES). They share the slots, batches, curves and weights rows.
//
// Rows (through the run-file schema; <group> = each slot's group, columns its slots):
//   <group>/curve_u, curve_bl, nan_pairs  (I × columns)   each iteration's batch (before its step)
//   <group>/params                        (columns × P_c) the trained weights (finish)
//   state/params, adam_m, adam_v          (N × P_c)       the committed optimizer state
// extended, with keep_best: <group>/val_bl ((I+1) × columns), <group>/best_iteration (columns), and in the
// state best_params (N × P_c), best (N × 2), es_fitness (N × I·popsize, cmaes)
#include "stages/connectors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "collective/references.hpp"
#include "common/check.hpp"
#include "evo/connector_opt.hpp"
#include "evo/optim.hpp"
#include "io/run_read.hpp"
#include "morph/body.hpp"
#include "stages/payload.hpp"
#include "config/pipeline.hpp"
#include "stages/population.hpp"

namespace divcoll::stages {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// one pair episode of one weight vector (the plain plan: weight vector = slot), `steps` long
struct PairTask {
  int32_t weights = 0, slot = 0, a = 0, b = 0;
  uint8_t grad = 1;
  int32_t steps = 0;
};
struct PairDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;
  std::vector<double> grad;
  uint8_t redone_in_double = 0;
};
template <class Ar>
void serialize(Ar& ar, PairTask& t, unsigned) {
  ar & t.weights & t.slot & t.a & t.b & t.grad & t.steps;
}
template <class Ar>
void serialize(Ar& ar, PairDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status & d.grad & d.redone_in_double;
}
// a finished pair as evo::ProbeSum takes it (by value: a caller done with `d` moves its gradient in)
collective::PairOutcome outcome(PairDone d) {
  collective::PairOutcome o;
  o.travel_u = d.travel_u, o.travel_bl = d.travel_bl, o.status = static_cast<sim::Status>(d.status);
  o.grad = std::move(d.grad);
  o.redone_in_double = d.redone_in_double != 0;
  return o;
}

Records& operator+=(Records& a, Records b) {
  for (Record& r : b) a.push_back(std::move(r));
  return a;
}

// what both plans share
class LockstepPlan : public ConnectorsPlan {
 public:
  LockstepPlan(const ConnectorsDef& def, const std::vector<morph::Agent>& agents,
               const std::vector<ConnectorSlot>& slots, const TrainSpec& spec)
      : def_(def), agents_(agents), slots_(slots), spec_(spec), groups_(slot_groups(slots)),
        slot_count_(static_cast<int>(slots.size())), batch_pairs_(spec.batch_pairs), iterations_(spec.iterations),
        population_(static_cast<int>(agents.size())), params_per_connector_(sim::connector_param_count(def.connectors.network == "joint")),
        state_prefix_(spec.state_group + "/state/") {}

  Info info() const override { return {spec_.label, spec_.state_group, "iterations_done", "iteration", "pair-episodes"}; }
  int rounds() const override { return iterations_; }
  void take_input(int, const std::string& input) override { weights_ = unpack<std::vector<double>>(input); }

 protected:
  // slot c's batch of iteration it: uniform slots pair agent i with its clone, diverse ones draw fresh pairs
  std::vector<std::pair<int, int>> batch(int c, int it) const {
    if (!slots_[c].diverse) return collective::uniform_pairs(batch_pairs_);
    Rng rng = make_rng(def_.seed, slots_[c].stream, it);
    return collective::random_pairs(rng, population_, batch_pairs_);
  }
  std::vector<double> initial_weights(int c) const {
    Rng rng = make_rng(def_.seed, slots_[c].stream, config::kItemInitialWeights);
    return collective::initial_connector_params(def_.connectors, slots_[c].tether.amplitude, rng);
  }
  // one pair episode of weight vector t.weights of the round's weights_
  PairDone episode(const PairTask& t, const sim::RunOptions& ro) {
    const ConnectorSlot& s = slots_[t.slot];
    const std::vector<double> w(weights_.begin() + static_cast<size_t>(t.weights) * params_per_connector_,
                                weights_.begin() + static_cast<size_t>(t.weights + 1) * params_per_connector_);
    const collective::PairOutcome o = collective::run_pair(sim_, agents_[t.a], agents_[t.b], w, s.tether, s.env, def_.physics.contact, ro, nullptr);
    return PairDone{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status), o.grad, static_cast<uint8_t>(o.redone_in_double)};
  }
  // row `row` of each group's (rows × columns) dataset <group>/<name>, from per-slot values
  Records slot_row(const std::string& name, int rows, int row, const std::vector<double>& per_slot) const {
    Records out;
    for (size_t gi = 0; gi < groups_.groups.size(); ++gi) {
      std::vector<double> u(groups_.columns[gi], kNaN);
      for (int c = 0; c < slot_count_; ++c)
        if (slots_[c].group == groups_.groups[gi]) u[slots_[c].column] = per_slot[c];
      out.push_back({groups_.groups[gi] + "/" + name, {static_cast<uint64_t>(rows), static_cast<uint64_t>(groups_.columns[gi])},
                     {row}, std::move(u)});
    }
    return out;
  }
  // <group>/<name> (columns × width) from per-slot rows
  Records slot_rows(const std::string& name, const std::vector<std::vector<double>>& per_slot, size_t width) const {
    Records out;
    for (size_t gi = 0; gi < groups_.groups.size(); ++gi) {
      Record r{groups_.groups[gi] + "/" + name, {static_cast<uint64_t>(groups_.columns[gi])}, {}, std::vector<double>{}};
      if (width > 0) r.dims.push_back(width);
      auto& v = std::get<std::vector<double>>(r.values);
      for (int c = 0; c < slot_count_; ++c)
        if (slots_[c].group == groups_.groups[gi])
          r.rows.push_back(slots_[c].column), v.insert(v.end(), per_slot[c].begin(), per_slot[c].end());
      out.push_back(std::move(r));
    }
    return out;
  }
  // state/<name> (N × width): one row per slot
  Record state_rows(const std::string& name, const std::vector<std::vector<double>>& per_slot, size_t width) const {
    Record r{state_prefix_ + name, {static_cast<uint64_t>(slot_count_), width}, {}, io::join_weights(per_slot)};
    for (int c = 0; c < slot_count_; ++c) r.rows.push_back(c);
    return r;
  }
  // numerical trouble, reported with where: pairs whose episode ran (status ok) but whose gradient was not
  // finite are left out of the step (they count in nan_pairs; one of them would have made the slot's weights
  // NaN); with run.precision = "float_networks", pairs whose float gradient overflowed were run again in double
  // (said by the driver: take_warnings)
  void report_bad_gradients(int it, int c, int n, int redone) {
    const std::string at = slots_[c].group + " column " + std::to_string(slots_[c].column) + ", iteration " +
                           std::to_string(it + 1) + ": ";
    if (n > 0)
      warnings_.push_back(at + std::to_string(n) + " pair(s) ran but their gradient was not finite; left out of the "
                          "step (counted in nan_pairs)");
    if (redone > 0)
      warnings_.push_back(at + std::to_string(redone) + " pair(s) had a float gradient beyond float's range; run "
                          "again with the networks in double");
  }
  std::vector<std::string> take_warnings() override { return std::exchange(warnings_, {}); }
  Records curves(int it, const std::vector<double>& travel_u, const std::vector<double>& travel_bl,
                 const std::vector<double>& nan_pairs) const {
    Records out = slot_row("curve_u", iterations_, it, travel_u);
    out += slot_row("curve_bl", iterations_, it, travel_bl);
    out += slot_row("nan_pairs", iterations_, it, nan_pairs);
    return out;
  }

  const ConnectorsDef def_;
  const std::vector<morph::Agent>& agents_;
  const std::vector<ConnectorSlot>& slots_;
  const TrainSpec spec_;
  const SlotGroups groups_;
  const int slot_count_, batch_pairs_, iterations_, population_, params_per_connector_;
  const std::string state_prefix_;
  sim::Simulator sim_;
  std::vector<double> weights_;  // the round's weight vectors, params_per_connector_ each (every rank)
  std::vector<std::string> warnings_;  // of the last end_round
};

// the plain method: each slot's gradients summed in pair order, then one Adam (or normalized) step
class PlainConnectorsPlan final : public LockstepPlan {
 public:
  using LockstepPlan::LockstepPlan;
  std::vector<std::string> state_paths() const override { return {state_prefix_ + "params", state_prefix_ + "adam_m", state_prefix_ + "adam_v"}; }
  void start(int done, const StoredState& s) override {
    params_.resize(slot_count_);
    adam_.resize(slot_count_);
    if (done > 0) {
      params_ = io::split_weights(s.at(state_prefix_ + "params"), slot_count_);
      const auto m = io::split_weights(s.at(state_prefix_ + "adam_m"), slot_count_), v = io::split_weights(s.at(state_prefix_ + "adam_v"), slot_count_);
      for (int c = 0; c < slot_count_; ++c) adam_[c].m = m[c], adam_[c].v = v[c];
      return;
    }
    for (int c = 0; c < slot_count_; ++c) {
      params_[c] = initial_weights(c);
      adam_[c].m.assign(params_per_connector_, 0.0);
      adam_[c].v.assign(params_per_connector_, 0.0);
    }
  }
  Records state() const override {
    std::vector<std::vector<double>> m, v;
    for (const evo::Adam& a : adam_) m.push_back(a.m), v.push_back(a.v);
    return {state_rows("params", params_, params_per_connector_), state_rows("adam_m", m, params_per_connector_), state_rows("adam_v", v, params_per_connector_)};
  }
  std::string round_input(int) override { return pack(io::join_weights(params_)); }
  std::vector<std::string> items(int it) override {
    std::vector<std::string> items;
    for (int c = 0; c < slot_count_; ++c)
      for (const auto& [a, b] : batch(c, it)) items.push_back(pack(PairTask{c, c, a, b, 1, spec_.episode_steps}));
    curve_u_.assign(slot_count_, kNaN), curve_bl_.assign(slot_count_, kNaN), nan_pairs_.assign(slot_count_, 0);
    evo::ProbeSum empty;
    empty.pair_clip = evo::pair_clip(evo::opt_settings(def_.connectors));  // connectors.clip
    sums_.assign(slot_count_, empty);
    return items;
  }
  std::string compute(const std::string& item) override {
    const PairTask t = unpack<PairTask>(item);
    sim::RunOptions ro = def_.physics.options();
    ro.steps = t.steps;
    ro.grad = true;
    ro.agent_param_grad = false;  // the agents stay frozen
    return pack(episode(t, ro));
  }
  void reduce(int, int64_t i, const std::string& bytes) override {
    // in pair order; a pair not ok or with a non-finite gradient is counted
    sums_[static_cast<size_t>(i / batch_pairs_)].add(outcome(unpack<PairDone>(bytes)));
  }
  Records end_round(int it) override {
    const auto& C = def_.connectors;
    for (int c = 0; c < slot_count_; ++c) {
      evo::ProbeResult r = sums_[c].mean();
      nan_pairs_[c] = r.not_ok;
      report_bad_gradients(it, c, r.bad_grad, r.redone);
      if (r.ok == 0) continue;
      curve_u_[c] = r.travel_u;
      curve_bl_[c] = r.travel_bl;
      for (double& x : r.grad) x = -x;  // loss = −mean travel
      if (C.optimizer == "adam")
        adam_[c].step(params_[c], r.grad, C.lr, C.clip_norm, it + 1);
      else
        evo::normalized_step(params_[c], r.grad, C.lr);
    }
    return curves(it, curve_u_, curve_bl_, nan_pairs_);
  }
  std::string summary(int) const override {
    std::string s;
    const auto& groups = groups_.groups;
    for (size_t gi = 0; gi < groups.size() && gi < 6; ++gi) {
      double m = 0;
      int k = 0;
      for (int c = 0; c < slot_count_; ++c)
        if (slots_[c].group == groups[gi] && std::isfinite(curve_bl_[c])) m += curve_bl_[c], ++k;
      char b[128];
      std::snprintf(b, sizeof b, "%s%s %.3f", s.empty() ? "" : " ", groups[gi].substr(groups[gi].rfind('/') + 1).c_str(),
                    k ? m / k : NAN);
      s += b;
    }
    return s + (groups.size() > 6 ? " ... BL" : " BL");
  }
  Records finish() override { return slot_rows("params", params_, params_per_connector_); }
  std::vector<std::vector<double>> weights() const override { return params_; }

 private:
  std::vector<std::vector<double>> params_;
  std::vector<evo::Adam> adam_;
  std::vector<double> curve_u_, curve_bl_, nan_pairs_;
  std::vector<evo::ProbeSum> sums_;  // each slot's batch, summed in pair order
};

// the connector optimisation keys: ask/tell optimizers, each probe a weight vector on a batch; with
// keep_best each slot's current weights also run its fixed validation batch, and a closing round scores
// the final weights
class ExtendedConnectorsPlan final : public LockstepPlan {
 public:
  ExtendedConnectorsPlan(const ConnectorsDef& def, const std::vector<morph::Agent>& agents,
                         const std::vector<ConnectorSlot>& slots, const TrainSpec& spec)
      : LockstepPlan(def, agents, slots, spec), os_(evo::opt_settings(def.connectors)),
        es_(os_.optimizer == "cmaes"), E_(static_cast<size_t>(spec.iterations) * os_.es_popsize) {}

  bool closing_round() const override { return os_.keep_best; }
  std::vector<std::string> state_paths() const override {
    std::vector<std::string> p;
    for (const char* n : {"params", "adam_m", "adam_v", "best_params", "best"}) p.push_back(state_prefix_ + n);
    if (es_) p.push_back(state_prefix_ + "es_fitness");
    return p;
  }
  void start(int done, const StoredState& s) override {
    for (int c = 0; c < slot_count_; ++c) opt_.emplace_back(os_, initial_weights(c), iterations_, def_.seed, slots_[c].stream);
    if (os_.keep_best)
      for (int c = 0; c < slot_count_; ++c)
        val_.push_back(evo::validation_pairs(slots_[c].diverse, def_.connectors.validation_pairs, batch_pairs_, population_,
                                                    def_.seed, slots_[c].stream));
    if (done == 0) return;
    auto row = [&](const std::string& name, int c, size_t w) {
      const std::vector<double>& x = s.at(state_prefix_ + name);
      return std::vector<double>(x.begin() + c * w, x.begin() + (c + 1) * w);
    };
    for (int c = 0; c < slot_count_; ++c) {
      evo::ConnectorOptimizer::State st;
      st.params = row("params", c, params_per_connector_), st.m = row("adam_m", c, params_per_connector_), st.v = row("adam_v", c, params_per_connector_);
      st.best_params = row("best_params", c, params_per_connector_);
      const std::vector<double> b = row("best", c, 2);
      st.best_score = b[0], st.best_it = static_cast<int>(b[1]);
      if (es_) st.es_fitness = row("es_fitness", c, E_);
      opt_[c].restore(st, done);
    }
  }
  Records state() const override {
    std::vector<std::vector<double>> p, m, v, bp, b, ef;
    for (int c = 0; c < slot_count_; ++c) {
      const auto st = opt_[c].state();
      p.push_back(st.params), m.push_back(st.m), v.push_back(st.v), bp.push_back(st.best_params);
      b.push_back({st.best_score, static_cast<double>(st.best_it)});
      ef.push_back(st.es_fitness);
      ef.back().resize(E_, kNaN);
    }
    Records r = {state_rows("params", p, params_per_connector_), state_rows("adam_m", m, params_per_connector_), state_rows("adam_v", v, params_per_connector_),
                 state_rows("best_params", bp, params_per_connector_), state_rows("best", b, 2)};
    if (es_) r.push_back(state_rows("es_fitness", ef, E_));
    return r;
  }
  // the round's weight vectors and items: each slot's probes on its batch, then (keep_best) its current
  // weights on its validation batch; the closing round (it = I) has the validation alone
  std::string round_input(int it) override {
    const bool closing = it >= iterations_;
    const int steps = evo::training_steps(os_, spec_.episode_steps, it);  // the probes' (connectors.horizon_start)
    std::vector<double> w;
    items_.clear();
    counts_.assign(slot_count_, {});
    int nw = 0;
    for (int c = 0; c < slot_count_; ++c) {
      if (!closing) {
        const auto pairs = batch(c, it);
        for (const evo::Probe& p : opt_[c].ask(it)) {
          w.insert(w.end(), p.weights.begin(), p.weights.end());
          for (const auto& [a, b] : pairs) items_.push_back(pack(PairTask{nw, c, a, b, p.grad, steps}));
          counts_[c].push_back(static_cast<int>(pairs.size()));
          ++nw;
        }
      }
      if (os_.keep_best) {
        w.insert(w.end(), opt_[c].current().begin(), opt_[c].current().end());
        for (const auto& [a, b] : val_[c]) items_.push_back(pack(PairTask{nw, c, a, b, 0, spec_.episode_steps}));
        counts_[c].push_back(static_cast<int>(val_[c].size()));
        ++nw;
      }
    }
    done_.assign(items_.size(), {});
    return pack(w);
  }
  std::vector<std::string> items(int) override { return items_; }
  std::string compute(const std::string& item) override {
    const PairTask t = unpack<PairTask>(item);
    sim::RunOptions ro = def_.physics.options();
    ro.steps = t.steps;
    ro.grad = t.grad != 0;
    ro.agent_param_grad = false;  // the agents stay frozen
    ro.grad_window = os_.bptt_window;
    return pack(episode(t, ro));
  }
  void reduce(int, int64_t i, const std::string& bytes) override { done_[i] = unpack<PairDone>(bytes); }
  Records end_round(int it) override {
    // per slot: the probes' mean results and the validation score
    std::vector<std::vector<evo::ProbeResult>> results(slot_count_);
    vscore_.assign(slot_count_, kNaN);
    size_t q = 0;
    for (int c = 0; c < slot_count_; ++c) {
      int bad_grad = 0, redone = 0;
      for (size_t w = 0; w < counts_[c].size(); ++w) {
        evo::ProbeSum sum;
        sum.pair_clip = evo::pair_clip(os_);  // connectors.clip
        for (int p = 0; p < counts_[c][w]; ++p, ++q) sum.add(outcome(done_[q]));
        bad_grad += sum.bad_grad, redone += sum.redone;
        if (os_.keep_best && w + 1 == counts_[c].size()) vscore_[c] = sum.mean().travel_bl;
        else results[c].push_back(sum.mean());
      }
      report_bad_gradients(it, c, bad_grad, redone);
    }
    Records out;
    if (it < iterations_) {
      curve_u_.assign(slot_count_, kNaN), curve_bl_.assign(slot_count_, kNaN);
      std::vector<double> nan_pairs(slot_count_, 0);
      for (int c = 0; c < slot_count_; ++c) {
        opt_[c].tell(it, results[c], vscore_[c]);
        curve_u_[c] = opt_[c].curve_u, curve_bl_[c] = opt_[c].curve_bl, nan_pairs[c] = opt_[c].curve_not_ok;
      }
      out = curves(it, curve_u_, curve_bl_, nan_pairs);
    } else {  // the final weights' validation, and the kept weights' rows
      for (int c = 0; c < slot_count_; ++c) opt_[c].finish(vscore_[c]);
    }
    if (os_.keep_best) out += slot_row("val_bl", iterations_ + 1, it, vscore_);
    if (it >= iterations_) {
      std::vector<std::vector<double>> bi;
      for (int c = 0; c < slot_count_; ++c) bi.push_back({static_cast<double>(opt_[c].best_iteration())});
      out += slot_rows("best_iteration", bi, 0);
    }
    return out;
  }
  std::string summary(int) const override {
    double m = 0, v = 0;
    int k = 0, kv = 0;
    for (int c = 0; c < slot_count_; ++c) {
      if (std::isfinite(curve_bl_[c])) m += curve_bl_[c], ++k;
      if (std::isfinite(vscore_[c])) v += vscore_[c], ++kv;
    }
    char b[160];
    std::snprintf(b, sizeof b, "batch %.3f BL", k ? m / k : NAN);
    std::string s = b;
    if (kv) std::snprintf(b, sizeof b, ", validation %.3f BL", v / kv), s += b;
    std::snprintf(b, sizeof b, " (mean over %d connectors)", slot_count_);
    return s + b;
  }
  Records finish() override { return slot_rows("params", weights(), params_per_connector_); }
  std::vector<std::vector<double>> weights() const override {
    std::vector<std::vector<double>> w;
    for (const auto& o : opt_) w.push_back(o.result());
    return w;
  }

 private:
  const evo::OptSettings os_;
  const bool es_;
  const size_t E_;
  std::vector<evo::ConnectorOptimizer> opt_;
  std::vector<std::vector<std::pair<int, int>>> val_;
  std::vector<std::string> items_;
  std::vector<std::vector<int>> counts_;
  std::vector<PairDone> done_;
  std::vector<double> curve_u_, curve_bl_, vscore_;
};

}  // namespace

SlotGroups slot_groups(const std::vector<ConnectorSlot>& slots) {
  SlotGroups g;
  for (const ConnectorSlot& s : slots) {
    const auto at = std::find(g.groups.begin(), g.groups.end(), s.group);
    if (at == g.groups.end()) g.groups.push_back(s.group), g.columns.push_back(s.column + 1);
    else g.columns[at - g.groups.begin()] = std::max(g.columns[at - g.groups.begin()], s.column + 1);
  }
  return g;
}

ConnectorsDef connectors_def(const config::RunConfig& cfg) { return {cfg.run.seed, cfg.connectors, config::run_physics(cfg)}; }

std::unique_ptr<ConnectorsPlan> make_connectors_plan(const ConnectorsDef& def,
                                                     const std::vector<morph::Agent>& agents,
                                                     const std::vector<ConnectorSlot>& slots, const TrainSpec& spec) {
  if (evo::extended(evo::opt_settings(def.connectors)))
    return std::make_unique<ExtendedConnectorsPlan>(def, agents, slots, spec);
  return std::make_unique<PlainConnectorsPlan>(def, agents, slots, spec);
}

std::vector<std::vector<double>> train_connectors(Driver& driver, const std::vector<morph::Agent>& agents,
                                                  const std::vector<ConnectorSlot>& slots, const TrainSpec& spec) {
  const std::unique_ptr<ConnectorsPlan> plan = make_connectors_plan(connectors_def(driver.config()), agents, slots, spec);
  driver.drive(*plan);
  // every rank gets the trained weights
  return broadcast(driver, driver.master() ? plan->weights() : std::vector<std::vector<double>>{});
}

void run_connectors_stage(Driver& driver) {
  const ConnectorsDef def = connectors_def(driver.config());
  io::h5::File& file = driver.file();
  const auto& C = def.connectors;
  const std::vector<std::string>& kinds = C.kinds;
  const int K = static_cast<int>(kinds.size()), R = C.replicates;
  const std::vector<morph::Agent> agents = load_population(def.physics, file);

  io::h5::Node stage = file.group("connectors");
  stage.write_string("kinds", io::join(kinds));
  stage.write_int("replicates", R);
  store_anchors(driver, "agents", agents);
  // connector c = kind·R + replicate, trained on flat
  std::vector<ConnectorSlot> slots;
  for (int k = 0; k < K; ++k)
    for (int r = 0; r < R; ++r)
      slots.push_back({collective::tether(C, kinds[k]), config::connector_kind(kinds[k]).diverse, "flat", kConnectorsStage + k * R + r,
                       "connectors/" + kinds[k], r});
  TrainSpec spec{"connectors", "connectors", C.iterations, C.batch_pairs, C.episode_steps};
  train_connectors(driver, agents, slots, spec);
}

}  // namespace divcoll::stages
