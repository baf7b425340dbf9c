#include "mpi/deploy_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

using io::h5::Dims;

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
  std::vector<float> hidden;          // K × 32
  std::vector<int32_t> hidden_index;  // K: step · 5 + connector spring
  double early_bl = 0;                // travel at deploy.early_step, BL (when it is recorded)
};
template <class Ar>
void serialize(Ar& ar, DeployDone& d, unsigned) {
  ar & d.done & d.hidden & d.hidden_index & d.early_bl;
}

}  // namespace

void run_deploy_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                      const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& D = cfg.deploy;
  const std::vector<std::string>& envs = D.environments;
  const int E = static_cast<int>(envs.size()), NP = D.pairs;
  const std::vector<collective::Agent> agents = load_population(comm, file);
  const int pop = static_cast<int>(agents.size());
  const int R = cfg.connectors.replicates;

  // the collective types: every trained kind on uniform and on diverse pairs
  std::vector<std::string> types;
  std::vector<std::vector<std::vector<double>>> weights;  // [type][replicate] → params
  std::vector<double> stiffness;
  std::vector<bool> diverse;
  for (const std::string& kind : cfg.connectors.kinds) {
    DIVCOLL_THROW_UNLESS(file.has("connectors/" + kind + "/params"),
                         file.file() << " has no trained " << kind << " connectors: run the connectors stage first");
    const std::vector<std::vector<double>> reps = io::read_weights(file, "connectors/" + kind, R);
    for (const char* dep : {"uniform", "diverse"}) {
      types.push_back(kind + "@" + dep);
      weights.push_back(reps);
      stiffness.push_back(io::stiffness(cfg, kind));
      diverse.push_back(std::string(dep) == "diverse");
    }
  }
  const int T = static_cast<int>(types.size());
  // hidden states (SPEC §8.2) of the weak connectors deployed as trained, at most deploy.hidden_subsample
  // per (type, replicate, environment): K per episode, drawn from the episode's own stream
  std::vector<int> hidden_types;
  for (int t = 0; t < T; ++t)
    if (types[t] == "weak_uniform@uniform" || types[t] == "weak_diverse@diverse") hidden_types.push_back(t);
  const int per_episode = D.episode_steps * 5;
  const int K = D.hidden_subsample == 0 ? per_episode
                                        : std::min(per_episode, (D.hidden_subsample + NP - 1) / NP);
  Rng prng = make_rng(cfg.run.seed, kDeployStage, 0);
  const auto diverse_pairs = collective::random_pairs(prng, pop, NP);
  const auto uniform_pairs = collective::deploy_uniform_pairs(cfg);
  const bool early = D.early_step > 0;  // deploy.early_step: travel at that step too (from the recorded run)

  if (!file.has("deploy")) file.create_group("deploy");
  io::h5::Node stage = file.group("deploy");
  stage.write_string("status", "running");
  stage.write_string("environments", join(envs));
  stage.write_string("types", join(types));
  {
    std::vector<int64_t> rows;
    std::vector<int32_t> p;
    if (rank == 0)
      for (int q = 0; q < NP; ++q) rows.push_back(q), p.push_back(diverse_pairs[q].first), p.push_back(diverse_pairs[q].second);
    file.write_rows<int32_t>("deploy/diverse_pairs", {static_cast<hsize_t>(NP), 2}, rows, p);
  }
  const int done = stage.has_attribute("envs_done") ? static_cast<int>(stage.read_int("envs_done")) : 0;
  if (rank == 0 && done > 0) std::printf("deploy: resuming after %d environment(s)\n", done);

  sim::Simulator sim;
  std::string env_now;
  int env_index = 0;
  auto compute = [&](const std::string& bytes) {
    const Episode e = unpack<Episode>(bytes);
    DeployDone d;
    const bool hidden = e.type >= 0 && std::find(hidden_types.begin(), hidden_types.end(), e.type) != hidden_types.end();
    collective::PairOutcome o;
    sim::RunOptions opt;
    opt.steps = D.episode_steps;
    opt.record = early;
    sim::RunResult full;
    if (e.type < 0) {
      o = collective::run_alone(sim, agents[e.a], env_now, opt, &full, collective::alone_feature_offset(cfg, agents[e.a]));
      if (early) d.early_bl = collective::travel_at(full, sim::kAgentMasses, D.early_step) / collective::body_length(agents[e.a]);
    } else {
      opt.record_hidden = hidden;
      o = collective::run_pair(sim, agents[e.a], agents[e.b], weights[e.type][e.replicate], stiffness[e.type], env_now,
                               opt, &full);
      if (early)
        d.early_bl = collective::travel_at(full, 2 * sim::kAgentMasses, D.early_step) /
                     (0.5 * (collective::body_length(agents[e.a]) + collective::body_length(agents[e.b])));
      if (hidden) {
        // the episode's stream: (seed, deploy + 1, the episode's index in every environment's list)
        const uint64_t item = ((static_cast<uint64_t>(env_index) * T + e.type) * R + e.replicate) * NP + e.pair;
        Rng rng = make_rng(cfg.run.seed, kDeployStage + 1, item);
        const std::vector<int64_t> picked = sorted_sample(rng, per_episode, K);
        d.hidden_index.assign(picked.begin(), picked.end());
        d.hidden.assign(d.hidden_index.size() * 32, std::numeric_limits<float>::quiet_NaN());
        if (o.status == sim::Status::ok)
          for (size_t k = 0; k < d.hidden_index.size(); ++k)
            for (int q = 0; q < 32; ++q) d.hidden[k * 32 + q] = static_cast<float>(full.hidden[d.hidden_index[k] * 32 + q]);
      }
    }
    d.done = EpisodeDone{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status)};
    return pack(d);
  };

  const auto t_stage = std::chrono::steady_clock::now();
  for (int ei = done; ei < E; ++ei) {
    env_now = envs[ei];
    env_index = ei;
    std::vector<std::string> items;
    if (rank == 0) {
      for (int i = 0; i < pop; ++i) items.push_back(pack(Episode{-1, 0, i, i}));
      for (int t = 0; t < T; ++t)
        for (int r = 0; r < R; ++r)
          for (int q = 0; q < NP; ++q) {
            const auto& pr = diverse[t] ? diverse_pairs[q] : uniform_pairs[q];
            items.push_back(pack(Episode{t, r, pr.first, pr.second, q}));
          }
    }
    const FarmResult fr = farm(comm, items, compute);
    // row ei of every dataset, written by the master
    std::vector<int64_t> rows;
    std::vector<double> au, ab, cu, cb, ae, ce;
    std::vector<uint8_t> as, cs;
    std::vector<double> type_mean(T, 0.0);
    std::vector<int> type_ok(T, 0), type_bad(T, 0);
    std::vector<std::vector<float>> hid(hidden_types.size());
    std::vector<std::vector<int32_t>> hid_index(hidden_types.size());
    if (rank == 0) {
      rows.push_back(ei);
      for (size_t q = 0; q < fr.results.size(); ++q) {
        const DeployDone dd = unpack<DeployDone>(fr.results[q]);
        const EpisodeDone& d = dd.done;
        if (!dd.hidden_index.empty()) {
          const int t = static_cast<int>((q - pop) / (static_cast<size_t>(R) * NP));
          const int h = static_cast<int>(std::find(hidden_types.begin(), hidden_types.end(), t) - hidden_types.begin());
          hid[h].insert(hid[h].end(), dd.hidden.begin(), dd.hidden.end());
          hid_index[h].insert(hid_index[h].end(), dd.hidden_index.begin(), dd.hidden_index.end());
        }
        const bool alone = q < static_cast<size_t>(pop);
        (alone ? au : cu).push_back(d.travel_u);
        (alone ? ab : cb).push_back(d.travel_bl);
        (alone ? as : cs).push_back(d.status);
        (alone ? ae : ce).push_back(dd.early_bl);
        if (!alone) {
          const int t = static_cast<int>((q - pop) / (static_cast<size_t>(R) * NP));
          if (d.status == 0 && std::isfinite(d.travel_bl)) type_mean[t] += d.travel_bl, ++type_ok[t];
          else ++type_bad[t];
        }
      }
    }
    const hsize_t hE = E, hP = pop, hT = T, hR = R, hN = NP;
    file.write_rows<double>("deploy/agents/travel_u", {hE, hP}, rows, au);
    file.write_rows<double>("deploy/agents/travel_bl", {hE, hP}, rows, ab);
    file.write_rows<uint8_t>("deploy/agents/status", {hE, hP}, rows, as);
    file.write_rows<double>("deploy/collectives/travel_u", {hE, hT, hR, hN}, rows, cu);
    file.write_rows<double>("deploy/collectives/travel_bl", {hE, hT, hR, hN}, rows, cb);
    file.write_rows<uint8_t>("deploy/collectives/status", {hE, hT, hR, hN}, rows, cs);
    if (early) {
      file.write_rows<double>("deploy/agents/travel_bl_early", {hE, hP}, rows, ae);
      file.write_rows<double>("deploy/collectives/travel_bl_early", {hE, hT, hR, hN}, rows, ce);
    }
    for (size_t h = 0; h < hidden_types.size(); ++h) {
      const hsize_t hK = static_cast<hsize_t>(K);
      file.write_rows<float>("deploy/hidden/" + types[hidden_types[h]] + "/states", {hE, hR, hN, hK, 32}, rows, hid[h]);
      file.write_rows<int32_t>("deploy/hidden/" + types[hidden_types[h]] + "/index", {hE, hR, hN, hK}, rows,
                               hid_index[h]);
    }
    stage.write_int("envs_done", ei + 1);
    checkpoint();
    if (rank == 0) {
      double am = 0;
      int an = 0;
      for (size_t i = 0; i < ab.size(); ++i)
        if (as[i] == 0 && std::isfinite(ab[i])) am += ab[i], ++an;
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count();
      std::printf("deploy: %-11s (%d/%d) agents alone %.3f BL |", envs[ei].c_str(), ei + 1, E, an ? am / an : NAN);
      for (int t = 0; t < T; ++t)
        std::printf(" %s %.3f%s", types[t].c_str(), type_ok[t] ? type_mean[t] / type_ok[t] : NAN,
                    type_bad[t] ? (" (" + std::to_string(type_bad[t]) + " not ok)").c_str() : "");
      std::printf(" | %.0f s, ETA %.0f s\n", el, el / (ei + 1 - done) * (E - ei - 1));
      std::fflush(stdout);
    }
  }
  stage.write_string("status", "complete");
  checkpoint();
}

}  // namespace divcoll::mpi
