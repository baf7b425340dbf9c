#include "mpi/analysis_stage.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "analysis/behaviour.hpp"
#include "analysis/dtw.hpp"
#include "analysis/pacmap.hpp"
#include "analysis/stats.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/deploy_stage.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

using io::h5::Dims;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kHidden = 32;  // hidden units per connector spring state (SPEC §6.3)

// the two types the analyses compare: weak connectors deployed as trained
const std::array<std::string, 2> kTypes = {"weak_uniform@uniform", "weak_diverse@diverse"};

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

// familiarity: one PaCMAP fit of a replicate's training and novel hidden states
struct FitTask {
  uint64_t seed = 0;
  int32_t n_train = 0, n_novel = 0;
  std::vector<float> states;  // (n_train + n_novel) × 32, training first
};
template <class Ar>
void serialize(Ar& ar, FitTask& t, unsigned) {
  ar & t.seed & t.n_train & t.n_novel & t.states;
}
struct FitDone {
  std::vector<int64_t> counts;  // 6
  std::vector<float> embedding;  // (n_train + n_novel) × 2
};
template <class Ar>
void serialize(Ar& ar, FitDone& d, unsigned) {
  ar & d.counts & d.embedding;
}

bool same_bits(double x, double y) { return (std::isnan(x) && std::isnan(y)) || x == y; }

// the finite hidden states of replicate r in environment e (ok episodes only), at most max_states of them
std::vector<float> states_of(const std::vector<float>& all, int e, int r, int R, int NP, int K, int max_states,
                             Rng& rng) {
  std::vector<int64_t> rows;
  for (int q = 0; q < NP; ++q)
    for (int k = 0; k < K; ++k) {
      const int64_t row = ((static_cast<int64_t>(e) * R + r) * NP + q) * K + k;
      const float* s = &all[row * kHidden];
      if (std::all_of(s, s + kHidden, [](float v) { return std::isfinite(v); })) rows.push_back(row);
    }
  std::vector<float> out;
  for (int64_t i : sorted_sample(rng, static_cast<int64_t>(rows.size()), max_states))
    out.insert(out.end(), &all[rows[i] * kHidden], &all[rows[i] * kHidden] + kHidden);
  return out;
}

std::vector<double> finite(const std::vector<double>& v) {
  std::vector<double> out;
  for (double x : v)
    if (std::isfinite(x)) out.push_back(x);
  return out;
}

}  // namespace

void run_analysis_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                        const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& A = cfg.analysis;
  const auto& D = cfg.deploy;
  const std::vector<std::string>& envs = D.environments;
  const int E = static_cast<int>(envs.size()), NP = D.pairs, R = cfg.connectors.replicates;
  DIVCOLL_THROW_UNLESS(file.has("deploy") && file.group("deploy").has_attribute("status") &&
                           file.group("deploy").read_string("status") == "complete",
                       file.file() << ": the analysis stage needs a complete deploy stage");
  const std::vector<collective::Agent> agents = load_population(comm, file);
  const int pop = static_cast<int>(agents.size());

  // the two types among deploy's, their weights and pairs
  const std::vector<std::string> deploy_types = split(file.group("deploy").read_string("types"));
  const int T = static_cast<int>(deploy_types.size());
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
  const double stiffness = io::strength_stiffness(cfg, "weak");
  std::vector<std::pair<int, int>> pairs[2];
  pairs[0] = collective::deploy_uniform_pairs(cfg);
  {
    std::vector<int32_t> dp = file.read<int32_t>("deploy/diverse_pairs", Dims{static_cast<hsize_t>(NP), 2});
    for (int q = 0; q < NP; ++q) pairs[1].emplace_back(dp[2 * q], dp[2 * q + 1]);
  }
  std::vector<std::string> novel;
  const auto flat_it = std::find(envs.begin(), envs.end(), "flat");
  for (const auto& e : envs)
    if (e != "flat") novel.push_back(e);
  const int EN = static_cast<int>(novel.size());

  if (!file.has("analysis")) file.create_group("analysis");
  io::h5::Node stage = file.group("analysis");
  stage.write_string("status", "running");
  stage.write_string("types", kTypes[0] + "," + kTypes[1]);
  stage.write_string("environments", join(envs));
  stage.write_string("novel_environments", join(novel));
  if (!file.has("analysis/adversity")) file.create_group("analysis/adversity");
  if (!file.has("analysis/familiarity")) file.create_group("analysis/familiarity");
  io::h5::Node adv = file.group("analysis/adversity");
  if (!adv.has_attribute("deploy_mismatches")) adv.write_int("deploy_mismatches", 0);

  // deploy's results, to check the re-simulated episodes against (the master checks; every rank reads, as
  // with every read of the run file: a read made by one rank alone unbalances the ranks' HDF5 metadata
  // caches, io/h5.hpp)
  const std::vector<double> deploy_alone = file.read<double>("deploy/agents/travel_u");
  const std::vector<uint8_t> deploy_alone_status = file.read<uint8_t>("deploy/agents/status");
  const std::vector<double> deploy_pairs = file.read<double>("deploy/collectives/travel_u");
  const std::vector<uint8_t> deploy_pairs_status = file.read<uint8_t>("deploy/collectives/status");

  const auto t_stage = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count(); };
  sim::Simulator sim;
  sim::RunOptions rec;
  rec.steps = D.episode_steps;
  rec.record = true;
  const int frames = D.episode_steps / A.dtw_every + 1;
  analysis::DtwOptions dopt;
  dopt.band = static_cast<int>(std::ceil(A.dtw_band * frames));
  dopt.cost = A.dtw_cost == "squared_sqrt" ? analysis::DtwCost::squared_sqrt : analysis::DtwCost::euclidean;
  dopt.step = A.dtw_step == "symmetric2" ? analysis::DtwStep::symmetric2 : analysis::DtwStep::symmetric1;

  // ---- adversity (§8.1): per environment, agents alone, then the pairs --------------------------------
  const int dtw_done = stage.has_attribute("dtw_envs_done") ? static_cast<int>(stage.read_int("dtw_envs_done")) : 0;
  if (rank == 0 && dtw_done > 0) std::printf("analysis: resuming adversity after %d environment(s)\n", dtw_done);
  std::string env_now;
  std::vector<std::vector<double>> behaviour(pop);
  auto alone = [&](const std::string& bytes) {
    const int a = unpack<int32_t>(bytes);
    sim::RunResult full;
    const double offset = collective::alone_feature_offset(cfg, agents[a]);
    const collective::PairOutcome o = collective::run_alone(sim, agents[a], env_now, rec, &full, offset);
    AloneDone d{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status), {}};
    if (o.status == sim::Status::ok)
      d.behaviour = analysis::agent_behaviour(collective::agent_scene(agents[a], env_now, {}, offset), full, 0, A.dtw_every);
    return pack(d);
  };
  auto pair = [&](const std::string& bytes) {
    const PairTask t = unpack<PairTask>(bytes);
    const sim::Scene s =
        collective::pair_scene(agents[t.a], agents[t.b], weights[t.type][t.replicate], stiffness, env_now);
    const sim::RunResult r = sim.run(s, rec);
    PairDone d{r.travel, static_cast<uint8_t>(r.status), {kNaN, kNaN}};
    if (r.status == sim::Status::ok)
      for (int slot = 0; slot < 2; ++slot) {
        const std::vector<double>& ind = behaviour[slot == 0 ? t.a : t.b];
        if (ind.empty()) continue;
        const std::vector<double> teth = analysis::agent_behaviour(s, r, slot, A.dtw_every);
        const int n = static_cast<int>(teth.size() / analysis::kBehaviourFeatures);
        const int m = static_cast<int>(ind.size() / analysis::kBehaviourFeatures);
        const analysis::DtwResult x =
            analysis::dtw(teth.data(), n, ind.data(), m, analysis::kBehaviourFeatures, dopt);
        d.dtw[slot] = x.distance / (A.dtw_norm == "sum_lengths" ? n + m
                                     : A.dtw_norm == "max_length" ? std::max(n, m)
                                                                  : x.path_length);
      }
    return pack(d);
  };
  const hsize_t hE = E, hR = R, hN = NP;
  for (int ei = dtw_done; ei < E; ++ei) {
    env_now = envs[ei];
    std::vector<std::string> items;
    if (rank == 0)
      for (int32_t a = 0; a < pop; ++a) items.push_back(pack(a));
    const FarmResult fa = farm(comm, items, alone);
    long mismatches = adv.read_int("deploy_mismatches");  // every rank reads
    std::vector<double> alone_bl(pop, kNaN);
    if (rank == 0) {
      for (int a = 0; a < pop; ++a) {
        AloneDone d = unpack<AloneDone>(fa.results[a]);
        const size_t k = static_cast<size_t>(ei) * pop + a;
        if (!same_bits(d.travel_u, deploy_alone[k]) || d.status != deploy_alone_status[k]) ++mismatches;
        alone_bl[a] = d.status == 0 ? d.travel_bl : kNaN;
        behaviour[a] = std::move(d.behaviour);
      }
    }
    // every rank needs every agent's independent behaviour
    behaviour = broadcast(comm, behaviour);

    items.clear();
    if (rank == 0)
      for (int t = 0; t < 2; ++t)
        for (int r = 0; r < R; ++r)
          for (int q = 0; q < NP; ++q) items.push_back(pack(PairTask{t, r, pairs[t][q].first, pairs[t][q].second}));
    const FarmResult fp = farm(comm, items, pair);
    std::vector<int64_t> rows;
    std::array<std::vector<double>, 2> dtw;
    std::array<std::vector<uint8_t>, 2> worse;
    std::array<std::array<double, 2>, 2> sum{}, cnt{};
    if (rank == 0) {
      rows.push_back(ei);
      for (int t = 0; t < 2; ++t)
        for (int r = 0; r < R; ++r)
          for (int q = 0; q < NP; ++q) {
            const PairDone d = unpack<PairDone>(fp.results[(static_cast<size_t>(t) * R + r) * NP + q]);
            const size_t k = ((static_cast<size_t>(ei) * T + type_index[t]) * R + r) * NP + q;
            if (!same_bits(d.travel_u, deploy_pairs[k]) || d.status != deploy_pairs_status[k]) ++mismatches;
            dtw[t].push_back(d.dtw[0]);
            dtw[t].push_back(d.dtw[1]);
            // the worse agent travelled less alone; a tie (clones) makes the posterior one the worse
            const uint8_t w = alone_bl[pairs[t][q].second] < alone_bl[pairs[t][q].first] ? 1 : 0;
            worse[t].push_back(w);
            for (int slot = 0; slot < 2; ++slot)
              if (std::isfinite(d.dtw[slot])) sum[t][slot == w ? 0 : 1] += d.dtw[slot], cnt[t][slot == w ? 0 : 1] += 1;
          }
    }
    for (int t = 0; t < 2; ++t) {
      file.write_rows<double>("analysis/adversity/" + kTypes[t] + "/dtw", {hE, hR, hN, 2}, rows, dtw[t]);
      file.write_rows<uint8_t>("analysis/adversity/" + kTypes[t] + "/worse_slot", {hE, hR, hN}, rows, worse[t]);
    }
    MPI_Bcast(&mismatches, 1, MPI_LONG, 0, comm);
    adv.write_int("deploy_mismatches", mismatches);
    stage.write_int("dtw_envs_done", ei + 1);
    checkpoint();
    if (rank == 0) {
      const double el = elapsed();
      std::printf("analysis: adversity %-11s (%d/%d) DTW per step worse/better:", envs[ei].c_str(), ei + 1, E);
      for (int t = 0; t < 2; ++t)
        std::printf(" %s %.4f/%.4f", kTypes[t].c_str(), sum[t][0] / cnt[t][0], sum[t][1] / cnt[t][1]);
      std::printf(" u | %.0f s, ETA %.0f s\n", el, el / (ei + 1 - dtw_done) * (E - ei - 1));
      if (mismatches > 0)
        std::printf("analysis: WARNING %ld re-simulated episode(s) differ from deploy's travel\n", mismatches);
      std::fflush(stdout);
    }
  }

  // ---- familiarity (§8.2): per novel environment, one PaCMAP fit per type and replicate ----------------
  const int fam_done =
      stage.has_attribute("familiarity_envs_done") ? static_cast<int>(stage.read_int("familiarity_envs_done")) : 0;
  const int ms = A.max_states;
  const hsize_t hEN = EN, hS = 2 * static_cast<hsize_t>(ms);
  if (flat_it != envs.end() && EN > 0) {
    const int e_flat = static_cast<int>(flat_it - envs.begin());
    if (rank == 0 && fam_done > 0) std::printf("analysis: resuming familiarity after %d environment(s)\n", fam_done);
    std::array<std::vector<float>, 2> hidden;
    int K = 0;
    if (fam_done < EN)  // every rank reads
      for (int t = 0; t < 2; ++t) {
        Dims d;
        hidden[t] = file.read<float>("deploy/hidden/" + kTypes[t] + "/states", &d);
        DIVCOLL_THROW_UNLESS(d.size() == 5 && d[0] == hE && d[1] == hR && d[2] == hN && d[4] == kHidden,
                             file.file() << ": deploy/hidden/" << kTypes[t] << "/states has an unexpected shape");
        K = static_cast<int>(d[3]);
      }
    auto fit = [&](const std::string& bytes) {
      const FitTask task = unpack<FitTask>(bytes);
      const int n = task.n_train + task.n_novel;
      FitDone d;
      d.counts.assign(6, 0);
      if (task.n_train < 1 || task.n_novel < 1 || n < 4) {
        d.embedding.assign(static_cast<size_t>(n) * 2, std::numeric_limits<float>::quiet_NaN());
        return pack(d);
      }
      std::vector<double> X(task.states.begin(), task.states.end());
      analysis::PacmapOptions po;
      po.seed = task.seed;
      const std::vector<double> y = analysis::pacmap_fit(X.data(), n, kHidden, po);
      std::vector<uint8_t> label(n, 0);
      std::fill(label.begin() + task.n_train, label.end(), 1);
      std::vector<double> cells = y;  // analysis.cell_scale: finer (or coarser) cells than the unit ones
      if (A.cell_scale != 1.0)
        for (double& c : cells) c *= A.cell_scale;
      const analysis::Occupancy o = analysis::classify_cells(cells, label);
      d.counts = {o.states_both, o.states_train_only, o.states_novel_only, o.cells_both, o.cells_train_only,
                  o.cells_novel_only};
      d.embedding.assign(y.begin(), y.end());
      return pack(d);
    };
    for (int k = fam_done; k < EN; ++k) {
      const int ei = static_cast<int>(std::find(envs.begin(), envs.end(), novel[k]) - envs.begin());
      std::vector<std::string> items;
      std::array<std::vector<int64_t>, 2> ns;
      if (rank == 0)
        for (int t = 0; t < 2; ++t)
          for (int r = 0; r < R; ++r) {
            const uint64_t item = (static_cast<uint64_t>(k) * 2 + t) * R + r;
            Rng srng = make_rng(cfg.run.seed, kAnalysisStage + 1, item);
            FitTask task;
            task.seed = seed_for(cfg.run.seed, kAnalysisStage + 2, item);
            task.states = states_of(hidden[t], e_flat, r, R, NP, K, ms, srng);
            const std::vector<float> nov = states_of(hidden[t], ei, r, R, NP, K, ms, srng);
            task.n_train = static_cast<int32_t>(task.states.size() / kHidden);
            task.n_novel = static_cast<int32_t>(nov.size() / kHidden);
            task.states.insert(task.states.end(), nov.begin(), nov.end());
            ns[t].push_back(task.n_train);
            ns[t].push_back(task.n_novel);
            items.push_back(pack(task));
          }
      const FarmResult ff = farm(comm, items, fit);
      std::vector<int64_t> rows;
      std::array<std::vector<int64_t>, 2> counts;
      std::array<std::vector<float>, 2> emb;
      if (rank == 0) {
        rows.push_back(k);
        for (int t = 0; t < 2; ++t)
          for (int r = 0; r < R; ++r) {
            const FitDone d = unpack<FitDone>(ff.results[static_cast<size_t>(t) * R + r]);
            counts[t].insert(counts[t].end(), d.counts.begin(), d.counts.end());
            std::vector<float> padded(2 * hS, std::numeric_limits<float>::quiet_NaN());
            std::copy(d.embedding.begin(), d.embedding.end(), padded.begin());
            emb[t].insert(emb[t].end(), padded.begin(), padded.end());
          }
      }
      for (int t = 0; t < 2; ++t) {
        const std::string g = "analysis/familiarity/" + kTypes[t];
        file.write_rows<int64_t>(g + "/counts", {hEN, hR, 6}, rows, counts[t]);
        file.write_rows<int64_t>(g + "/n_states", {hEN, hR, 2}, rows, ns[t]);
        file.write_rows<float>(g + "/embedding", {hEN, hR, hS, 2}, rows, emb[t]);
      }
      stage.write_int("familiarity_envs_done", k + 1);
      checkpoint();
      if (rank == 0) {
        const double el = elapsed();
        std::printf("analysis: familiarity %-11s (%d/%d) states in shared cells:", novel[k].c_str(), k + 1, EN);
        for (int t = 0; t < 2; ++t) {
          double both = 0, all = 0;
          for (int r = 0; r < R; ++r) both += counts[t][6 * r], all += ns[t][2 * r] + ns[t][2 * r + 1];
          std::printf(" %s %.1f%%", kTypes[t].c_str(), all > 0 ? 100 * both / all : NAN);
        }
        std::printf(" | %.0f s\n", el);
        std::fflush(stdout);
      }
    }
  }

  // ---- statistics (§8.3), from the datasets written above -----------------------------------------------
  std::vector<double> rep_means, summary, welch, table;
  // every rank reads; the master computes
  std::array<std::vector<double>, 2> dtw_all;
  std::array<std::vector<uint8_t>, 2> ws_all;
  std::array<std::vector<int64_t>, 2> counts, ns;
  for (int t = 0; t < 2; ++t) {
    dtw_all[t] = file.read<double>("analysis/adversity/" + kTypes[t] + "/dtw");
    ws_all[t] = file.read<uint8_t>("analysis/adversity/" + kTypes[t] + "/worse_slot");
    if (EN > 0 && flat_it != envs.end()) {
      counts[t] = file.read<int64_t>("analysis/familiarity/" + kTypes[t] + "/counts");
      ns[t] = file.read<int64_t>("analysis/familiarity/" + kTypes[t] + "/n_states");
    }
  }
  if (rank == 0) {
    std::array<std::array<std::vector<double>, 2>, 2> per_rep;  // [type][worse/better] over replicates
    for (int t = 0; t < 2; ++t) {
      const std::vector<double>& dtw = dtw_all[t];
      const std::vector<uint8_t>& ws = ws_all[t];
      for (int w = 0; w < 2; ++w)
        for (int r = 0; r < R; ++r) {
          double s = 0, n = 0;
          for (int e = 0; e < E; ++e)
            for (int q = 0; q < NP; ++q) {
              const size_t k = (static_cast<size_t>(e) * R + r) * NP + q;
              const double v = dtw[2 * k + (w == 0 ? ws[k] : 1 - ws[k])];
              if (std::isfinite(v)) s += v, n += 1;
            }
          per_rep[t][w].push_back(n > 0 ? s / n : kNaN);
        }
    }
    for (int t = 0; t < 2; ++t)
      for (int w = 0; w < 2; ++w) {
        rep_means.insert(rep_means.end(), per_rep[t][w].begin(), per_rep[t][w].end());
        const std::vector<double> x = finite(per_rep[t][w]);
        const analysis::Interval ci =
            analysis::bootstrap_ci(x, seed_for(cfg.run.seed, kAnalysisStage + 3, 2 * t + w), A.bootstrap_resamples);
        summary.insert(summary.end(), {analysis::mean(x), ci.lo, ci.hi});
      }
    for (int w = 0; w < 2; ++w) {
      const analysis::TestResult tr = analysis::welch_t_test(finite(per_rep[0][w]), finite(per_rep[1][w]));
      welch.insert(welch.end(), {tr.statistic, tr.df, tr.p});
    }
    if (EN > 0 && flat_it != envs.end()) {
      for (int k = 0; k < EN; ++k)
        for (int c = 0; c < 3; ++c) {
          std::array<std::vector<double>, 2> v;  // per type, over replicates with a fit
          for (int t = 0; t < 2; ++t)
            for (int r = 0; r < R; ++r) {
              const size_t row = static_cast<size_t>(k) * R + r;
              const int64_t n = ns[t][2 * row] + ns[t][2 * row + 1];
              if (n > 0 && counts[t][6 * row] + counts[t][6 * row + 1] + counts[t][6 * row + 2] == n)
                v[t].push_back(static_cast<double>(counts[t][6 * row + c]));
            }
          table.insert(table.end(), {analysis::mean(v[1]), analysis::mean(v[0]), analysis::welch_t_test(v[1], v[0]).p});
        }
    }
  }
  std::vector<int64_t> rows_t(rank == 0 ? 2 : 0);
  for (size_t i = 0; i < rows_t.size(); ++i) rows_t[i] = static_cast<int64_t>(i);
  file.write_rows<double>("analysis/adversity/replicate_means", {2, 2, hR}, rows_t, rep_means);
  file.write_rows<double>("analysis/adversity/summary", {2, 2, 3}, rows_t, summary);
  file.write_rows<double>("analysis/adversity/welch", {2, 3}, rows_t, welch);
  if (EN > 0 && flat_it != envs.end()) {
    std::vector<int64_t> rows_en;
    if (rank == 0)
      for (int k = 0; k < EN; ++k) rows_en.push_back(k);
    file.write_rows<double>("analysis/familiarity/table", {hEN, 3, 3}, rows_en, table);
  }
  if (rank == 0) {
    std::printf("analysis: DTW per step (u), mean over replicates [95%% CI]:");
    for (int t = 0; t < 2; ++t)
      std::printf(" %s worse %.4f [%.4f, %.4f] better %.4f [%.4f, %.4f];", kTypes[t].c_str(), summary[6 * t],
                  summary[6 * t + 1], summary[6 * t + 2], summary[6 * t + 3], summary[6 * t + 4], summary[6 * t + 5]);
    std::printf(" Welch p worse %.3g, better %.3g\n", welch[2], welch[5]);
    std::fflush(stdout);
  }
  stage.write_string("status", "complete");
  checkpoint();
}

}  // namespace divcoll::mpi
