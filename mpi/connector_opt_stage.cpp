// connector training with the optimisation keys of issue 9.2 (collective::ConnectorOptimizer: decaying rate,
// keep-best on a validation batch, truncated backpropagation, gradient averaging, CMA-ES), over the task farm.
// train_connectors hands over here when any of those keys differs from its default, so the default path and
// its run files are unchanged. Same datasets as train_connectors, plus, with keep_best:
//   <group>/val_bl         ((I+1) × columns) mean validation travel of the weights before each step, then of
//                          the final weights, BL
//   <group>/best_iteration (columns)         the row of val_bl whose weights were kept
// and the optimizer state state/{params, adam_m, adam_v, best_params, best, es_fitness} at each checkpoint.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "evo/connector_opt.hpp"
#include "common/check.hpp"
#include "morph/body.hpp"
#include "mpi/connectors_stage.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

using io::h5::Dims;

// one pair episode of one weight vector
struct ProbeTask {
  int32_t weights = 0, slot = 0, a = 0, b = 0;
  uint8_t grad = 0;
};
struct ProbeDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;
  std::vector<double> grad;
};
template <class Ar>
void serialize(Ar& ar, ProbeTask& t, unsigned) {
  ar & t.weights & t.slot & t.a & t.b & t.grad;
}
template <class Ar>
void serialize(Ar& ar, ProbeDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status & d.grad;
}

collective::PairOutcome outcome(const ProbeDone& d) {
  collective::PairOutcome o;
  o.travel_u = d.travel_u, o.travel_bl = d.travel_bl, o.status = static_cast<sim::Status>(d.status), o.grad = d.grad;
  return o;
}

}  // namespace

std::vector<std::vector<double>> train_connectors_extended(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                                                           const std::vector<collective::Agent>& agents,
                                                           const std::vector<ConnectorSlot>& slots,
                                                           const TrainSpec& spec,
                                                           const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& C = cfg.connectors;
  const collective::OptSettings os = collective::opt_settings(C);
  const int N = static_cast<int>(slots.size()), B = spec.batch_pairs, I = spec.iterations;
  const int pop = static_cast<int>(agents.size());
  const int Pc = sim::connector_param_count();
  const bool es = os.optimizer == "cmaes";
  const SlotGroups sgroups = slot_groups(slots);
  io::h5::Node stage = file.group(spec.state_group);
  const std::string sg = spec.state_group + "/state/";
  int done = stage.has_attribute("iterations_done") ? static_cast<int>(stage.read_int("iterations_done")) : 0;

  // the optimizers live on the master
  std::vector<collective::ConnectorOptimizer> opt;
  if (rank == 0) {
    for (int c = 0; c < N; ++c) {
      Rng rng = make_rng(cfg.run.seed, slots[c].stream, 1000000);
      opt.emplace_back(os, morph::init_connector_params(rng, C.init_out_gain), I, cfg.run.seed, slots[c].stream);
    }
    if (done > 0) {
      const auto p = file.read<double>(sg + "params"), m = file.read<double>(sg + "adam_m"),
                 v = file.read<double>(sg + "adam_v"), bp = file.read<double>(sg + "best_params"),
                 b = file.read<double>(sg + "best");
      std::vector<double> ef;
      if (es) ef = file.read<double>(sg + "es_fitness");
      const size_t E = static_cast<size_t>(I) * os.es_popsize;
      for (int c = 0; c < N; ++c) {
        collective::ConnectorOptimizer::State st;
        auto row = [&](const std::vector<double>& x) {
          return std::vector<double>(x.begin() + static_cast<size_t>(c) * Pc, x.begin() + static_cast<size_t>(c + 1) * Pc);
        };
        st.params = row(p), st.m = row(m), st.v = row(v), st.best_params = row(bp);
        st.best_score = b[2 * c], st.best_it = static_cast<int>(b[2 * c + 1]);
        if (es) st.es_fitness.assign(ef.begin() + c * E, ef.begin() + (c + 1) * E);
        opt[c].restore(st, done);
      }
      std::printf("%s: resuming after iteration %d\n", spec.label.c_str(), done);
    }
  }
  auto write_state = [&] {
    std::vector<int64_t> rows;
    std::vector<double> p, m, v, bp, b, ef;
    const size_t E = static_cast<size_t>(I) * os.es_popsize;
    if (rank == 0)
      for (int c = 0; c < N; ++c) {
        const auto st = opt[c].state();
        rows.push_back(c);
        p.insert(p.end(), st.params.begin(), st.params.end());
        m.insert(m.end(), st.m.begin(), st.m.end());
        v.insert(v.end(), st.v.begin(), st.v.end());
        bp.insert(bp.end(), st.best_params.begin(), st.best_params.end());
        b.insert(b.end(), {st.best_score, static_cast<double>(st.best_it)});
        std::vector<double> e = st.es_fitness;
        e.resize(E, std::numeric_limits<double>::quiet_NaN());
        ef.insert(ef.end(), e.begin(), e.end());
      }
    const Dims d = {static_cast<hsize_t>(N), static_cast<hsize_t>(Pc)};
    file.write_rows<double>(sg + "params", d, rows, p);
    file.write_rows<double>(sg + "adam_m", d, rows, m);
    file.write_rows<double>(sg + "adam_v", d, rows, v);
    file.write_rows<double>(sg + "best_params", d, rows, bp);
    file.write_rows<double>(sg + "best", {static_cast<hsize_t>(N), 2}, rows, b);
    if (es) file.write_rows<double>(sg + "es_fitness", {static_cast<hsize_t>(N), static_cast<hsize_t>(E)}, rows, ef);
  };

  // every slot's fixed validation batch
  std::vector<std::vector<std::pair<int, int>>> val(N);
  if (os.keep_best)
    for (int c = 0; c < N; ++c)
      val[c] = collective::validation_pairs(slots[c].diverse, C.validation_pairs, B, pop, cfg.run.seed, slots[c].stream);

  sim::Simulator sim;
  std::vector<double> weights;  // every weight vector of the round, Pc each
  auto compute = [&](const std::string& bytes) {
    const ProbeTask t = unpack<ProbeTask>(bytes);
    const ConnectorSlot& s = slots[t.slot];
    const std::vector<double> w(weights.begin() + static_cast<size_t>(t.weights) * Pc,
                                weights.begin() + static_cast<size_t>(t.weights + 1) * Pc);
    sim::RunOptions ro;
    ro.steps = spec.episode_steps;
    ro.grad = t.grad != 0;
    ro.agent_param_grad = false;  // the agents stay frozen
    ro.grad_window = os.bptt_window;
    const collective::PairOutcome o = collective::run_pair(sim, agents[t.a], agents[t.b], w, s.stiffness, s.env, ro, nullptr);
    return pack(ProbeDone{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status), o.grad});
  };
  // one farm round: each slot's probes on its batch, then (keep_best) its current weights on its validation
  // batch; returns per slot the probes' results and the validation score
  auto round = [&](int it, bool final_validation, std::vector<std::vector<collective::ProbeResult>>& results,
                   std::vector<double>& vscore) {
    weights.clear();
    std::vector<std::string> items;
    std::vector<std::vector<int>> counts(N);  // pairs per weight vector, in item order
    int nw = 0;
    for (int c = 0; c < N; ++c) {
      std::vector<std::pair<int, int>> batch;
      if (!final_validation) {
        if (slots[c].diverse) {
          Rng rng = make_rng(cfg.run.seed, slots[c].stream, it);
          batch = collective::random_pairs(rng, pop, B);
        } else {
          batch = collective::uniform_pairs(B);
        }
      }
      if (rank != 0) continue;
      if (!final_validation)
        for (const collective::Probe& p : opt[c].ask(it)) {
          weights.insert(weights.end(), p.weights.begin(), p.weights.end());
          for (const auto& [a, b] : batch) items.push_back(pack(ProbeTask{nw, c, a, b, p.grad}));
          counts[c].push_back(static_cast<int>(batch.size()));
          ++nw;
        }
      if (os.keep_best) {
        weights.insert(weights.end(), opt[c].current().begin(), opt[c].current().end());
        for (const auto& [a, b] : val[c]) items.push_back(pack(ProbeTask{nw, c, a, b, 0}));
        counts[c].push_back(static_cast<int>(val[c].size()));
        ++nw;
      }
    }
    int64_t n = static_cast<int64_t>(weights.size());
    MPI_Bcast(&n, 1, MPI_INT64_T, 0, comm);
    weights.resize(n);
    MPI_Bcast(weights.data(), static_cast<int>(n), MPI_DOUBLE, 0, comm);
    const FarmResult fr = farm(comm, items, compute);
    results.assign(N, {});
    vscore.assign(N, std::numeric_limits<double>::quiet_NaN());
    if (rank != 0) return;
    size_t q = 0;
    for (int c = 0; c < N; ++c)
      for (size_t w = 0; w < counts[c].size(); ++w) {
        collective::ProbeSum sum;
        for (int p = 0; p < counts[c][w]; ++p) sum.add(outcome(unpack<ProbeDone>(fr.results[q++])));
        const bool is_val = os.keep_best && w + 1 == counts[c].size();
        if (is_val) vscore[c] = sum.mean().travel_bl;
        else results[c].push_back(sum.mean());
      }
  };
  auto write_val = [&](int row, const std::vector<double>& vscore) {
    if (os.keep_best) write_slot_row(file, rank == 0, sgroups, slots, "val_bl", I + 1, row, vscore);
  };

  const auto t_stage = std::chrono::steady_clock::now();
  std::vector<std::vector<collective::ProbeResult>> results;
  std::vector<double> vscore;
  for (int it = done; it < I; ++it) {
    const auto t0 = std::chrono::steady_clock::now();
    round(it, false, results, vscore);
    std::vector<double> cu(N, NAN), cb(N, NAN), nn(N, 0);
    if (rank == 0)
      for (int c = 0; c < N; ++c) {
        opt[c].tell(it, results[c], vscore[c]);
        cu[c] = opt[c].curve_u, cb[c] = opt[c].curve_bl, nn[c] = opt[c].curve_not_ok;
      }
    write_slot_row(file, rank == 0, sgroups, slots, "curve_u", I, it, cu);
    write_slot_row(file, rank == 0, sgroups, slots, "curve_bl", I, it, cb);
    write_slot_row(file, rank == 0, sgroups, slots, "nan_pairs", I, it, nn);
    write_val(it, vscore);
    if ((it + 1) % cfg.output.checkpoint_every == 0 || it + 1 == I) {
      write_state();
      stage.write_int("iterations_done", it + 1);
      checkpoint();
    }
    if (rank == 0) {
      const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count();
      double m = 0, v = 0;
      int k = 0, kv = 0;
      for (int c = 0; c < N; ++c) {
        if (std::isfinite(cb[c])) m += cb[c], ++k;
        if (std::isfinite(vscore[c])) v += vscore[c], ++kv;
      }
      std::printf("%s: iteration %d/%d: batch %.3f BL", spec.label.c_str(), it + 1, I, k ? m / k : NAN);
      if (kv) std::printf(", validation %.3f BL", v / kv);
      std::printf(" (mean over %d connectors); %.0f s, ETA %.0f s\n", N, el, (I - it - 1) * dt);
      std::fflush(stdout);
    }
  }
  // the final weights' validation (keep_best): row I of val_bl; the kept weights and their rows
  // (a resumed run repeats it: the final weights, hence their score, are the same)
  if (os.keep_best) {
    round(I, true, results, vscore);
    if (rank == 0)
      for (int c = 0; c < N; ++c) opt[c].finish(vscore[c]);
    write_val(I, vscore);
    std::vector<double> bi(N, NAN);
    if (rank == 0)
      for (int c = 0; c < N; ++c) bi[c] = opt[c].best_iteration();
    for (size_t gi = 0; gi < sgroups.groups.size(); ++gi) {
      std::vector<int64_t> rows;
      std::vector<double> b;
      if (rank == 0)
        for (int c = 0; c < N; ++c)
          if (slots[c].group == sgroups.groups[gi]) rows.push_back(slots[c].column), b.push_back(bi[c]);
      file.write_rows<double>(sgroups.groups[gi] + "/best_iteration", {static_cast<hsize_t>(sgroups.columns[gi])}, rows, b);
    }
  }
  std::vector<std::vector<double>> params(N);
  if (rank == 0)
    for (int c = 0; c < N; ++c) params[c] = opt[c].result();
  write_trained_params(comm, file, sgroups, slots, params);
  return params;
}

}  // namespace divcoll::mpi
