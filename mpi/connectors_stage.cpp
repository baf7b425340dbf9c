#include "mpi/connectors_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "evo/connector_opt.hpp"
#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "morph/body.hpp"
#include "evo/optim.hpp"
#include "io/run_read.hpp"
#include "mpi/agents_stage.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

using io::h5::Dims;

// one pair episode of one connector
struct PairTask {
  int32_t connector = 0, a = 0, b = 0;
};
struct PairDone {
  double travel_u = 0, travel_bl = 0;
  uint8_t status = 0;
  std::vector<double> grad;
};

template <class Ar>
void serialize(Ar& ar, PairTask& t, unsigned) {
  ar & t.connector & t.a & t.b;
}
template <class Ar>
void serialize(Ar& ar, PairDone& d, unsigned) {
  ar & d.travel_u & d.travel_bl & d.status & d.grad;
}

void bcast_doubles(MPI_Comm comm, std::vector<double>& v) {
  int64_t n = static_cast<int64_t>(v.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, comm);
  v.resize(n);
  MPI_Bcast(v.data(), static_cast<int>(n), MPI_DOUBLE, 0, comm);
}

}  // namespace

std::vector<collective::Agent> load_population(MPI_Comm comm, const io::h5::Node& file, const std::string& group) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  // the main population's anchors are stored once, by the connectors stage; read back they are the numbers
  // compute_anchors gives (tests/mpi/run_determinism_test.sh compares every dataset across runs)
  const bool stored = group == "agents" && file.has(kAnchors);
  std::vector<collective::Agent> agents;
  if (rank == 0) {
    for (const evo::Individual& x : io::read_final_population(file, group)) agents.push_back(x.agent);
    if (stored) io::read_anchors(file, kAnchors, agents);
  }
  agents = broadcast(comm, agents);
  // otherwise anchors from each agent's own 1000-step run on flat: the same on every rank
  if (!stored)
    for (auto& a : agents) a.anchors = collective::compute_anchors(a);
  return agents;
}

SlotGroups slot_groups(const std::vector<ConnectorSlot>& slots) {
  SlotGroups g;
  for (const ConnectorSlot& s : slots) {
    const auto at = std::find(g.groups.begin(), g.groups.end(), s.group);
    if (at == g.groups.end()) g.groups.push_back(s.group), g.columns.push_back(s.column + 1);
    else g.columns[at - g.groups.begin()] = std::max(g.columns[at - g.groups.begin()], s.column + 1);
  }
  return g;
}

void write_slot_row(io::h5::File& file, bool master, const SlotGroups& g, const std::vector<ConnectorSlot>& slots,
                    const std::string& name, int rows, int row, const std::vector<double>& per_slot) {
  for (size_t gi = 0; gi < g.groups.size(); ++gi) {
    std::vector<int64_t> which;
    std::vector<double> u;
    if (master) {
      which.push_back(row);
      u.assign(g.columns[gi], NAN);
      for (size_t c = 0; c < slots.size(); ++c)
        if (slots[c].group == g.groups[gi]) u[slots[c].column] = per_slot[c];
    }
    file.write_rows<double>(g.groups[gi] + "/" + name, {static_cast<hsize_t>(rows), static_cast<hsize_t>(g.columns[gi])},
                            which, u);
  }
}

void write_trained_params(MPI_Comm comm, io::h5::File& file, const SlotGroups& g,
                          const std::vector<ConnectorSlot>& slots, std::vector<std::vector<double>>& params) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const int Pc = sim::connector_param_count();
  for (size_t gi = 0; gi < g.groups.size(); ++gi) {
    std::vector<int64_t> rows;
    std::vector<double> w;
    if (rank == 0)
      for (size_t c = 0; c < slots.size(); ++c)
        if (slots[c].group == g.groups[gi]) rows.push_back(slots[c].column), w.insert(w.end(), params[c].begin(), params[c].end());
    file.write_rows<double>(g.groups[gi] + "/params", {static_cast<hsize_t>(g.columns[gi]), static_cast<hsize_t>(Pc)},
                            rows, w);
  }
  // every rank gets the trained weights
  for (auto& p : params) {
    p.resize(Pc);
    MPI_Bcast(p.data(), Pc, MPI_DOUBLE, 0, comm);
  }
}

std::vector<std::vector<double>> train_connectors(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                                                  const std::vector<collective::Agent>& agents,
                                                  const std::vector<ConnectorSlot>& slots, const TrainSpec& spec,
                                                  const std::function<void()>& checkpoint) {
  if (collective::extended(collective::opt_settings(cfg.connectors)))  // issue 9.2's optimisation keys
    return train_connectors_extended(comm, cfg, file, agents, slots, spec, checkpoint);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& C = cfg.connectors;
  const int N = static_cast<int>(slots.size()), B = spec.batch_pairs, I = spec.iterations;
  const int pop = static_cast<int>(agents.size());
  const int Pc = sim::connector_param_count();
  const SlotGroups sgroups = slot_groups(slots);
  const std::vector<std::string>& groups = sgroups.groups;
  io::h5::Node stage = file.group(spec.state_group);

  // state: weights and Adam moments of every slot
  int done = stage.has_attribute("iterations_done") ? static_cast<int>(stage.read_int("iterations_done")) : 0;
  std::vector<std::vector<double>> params(N);
  std::vector<evo::Adam> adam(N);
  const std::string sg = spec.state_group + "/state/";
  if (rank == 0) {
    if (done > 0) {
      params = io::split_weights(file.read<double>(sg + "params"), N);
      const auto m = io::split_weights(file.read<double>(sg + "adam_m"), N);
      const auto v = io::split_weights(file.read<double>(sg + "adam_v"), N);
      for (int c = 0; c < N; ++c) adam[c].m = m[c], adam[c].v = v[c];
      std::printf("%s: resuming after iteration %d\n", spec.label.c_str(), done);
    } else {
      for (int c = 0; c < N; ++c) {
        Rng rng = make_rng(cfg.run.seed, slots[c].stream, 1000000);
        params[c] = morph::init_connector_params(rng, C.init_out_gain);
        adam[c].m.assign(Pc, 0.0);
        adam[c].v.assign(Pc, 0.0);
      }
    }
  }

  auto write_state = [&] {
    std::vector<int64_t> rows;
    std::vector<double> p, m, v;
    if (rank == 0) {
      std::vector<std::vector<double>> ms, vs;
      for (int c = 0; c < N; ++c) rows.push_back(c), ms.push_back(adam[c].m), vs.push_back(adam[c].v);
      p = io::join_weights(params), m = io::join_weights(ms), v = io::join_weights(vs);
    }
    const Dims d = {static_cast<hsize_t>(N), static_cast<hsize_t>(Pc)};
    file.write_rows<double>(sg + "params", d, rows, p);
    file.write_rows<double>(sg + "adam_m", d, rows, m);
    file.write_rows<double>(sg + "adam_v", d, rows, v);
  };

  sim::Simulator sim;
  std::vector<double> flat_params;  // all slots' weights, broadcast each iteration
  auto compute = [&](const std::string& bytes) {
    const PairTask t = unpack<PairTask>(bytes);
    const ConnectorSlot& s = slots[t.connector];
    const std::vector<double> w(flat_params.begin() + static_cast<size_t>(t.connector) * Pc,
                                flat_params.begin() + static_cast<size_t>(t.connector + 1) * Pc);
    const collective::PairOutcome o =
        collective::run_pair(sim, agents[t.a], agents[t.b], w, s.stiffness, s.env, spec.episode_steps, true);
    PairDone d{o.travel_u, o.travel_bl, static_cast<uint8_t>(o.status), o.grad};
    return pack(d);
  };

  const auto t_stage = std::chrono::steady_clock::now();
  for (int it = done; it < I; ++it) {
    const auto t0 = std::chrono::steady_clock::now();
    flat_params.clear();
    if (rank == 0) flat_params = io::join_weights(params);
    bcast_doubles(comm, flat_params);
    // this iteration's batches: uniform slots use agent i with its clone, diverse ones fresh random pairs
    std::vector<std::string> items;
    for (int c = 0; c < N; ++c) {
      std::vector<std::pair<int, int>> batch;
      if (slots[c].diverse) {
        Rng rng = make_rng(cfg.run.seed, slots[c].stream, it);
        batch = collective::random_pairs(rng, pop, B);
      } else {
        batch = collective::uniform_pairs(B);
      }
      if (rank == 0)
        for (const auto& [a, b] : batch) items.push_back(pack(PairTask{c, a, b}));
    }
    // the master sums each slot's gradients in pair order as the results come in (in item order, so the
    // sums are the same whatever the rank count), while the round runs
    std::vector<double> curve_u(N, std::numeric_limits<double>::quiet_NaN()), curve_bl = curve_u, nan_pairs(N, 0);
    std::vector<std::vector<double>> g(rank == 0 ? N : 0, std::vector<double>(Pc, 0.0));
    std::vector<double> su(N, 0.0), sb(N, 0.0);
    std::vector<int> ok(N, 0);
    FarmOptions fo;
    fo.on_result = [&](int64_t i, const std::string& bytes) {
      const int c = static_cast<int>(i / B);
      const PairDone d = unpack<PairDone>(bytes);
      if (d.status != 0 || !std::isfinite(d.travel_u)) {
        ++nan_pairs[c];
        return;
      }
      ++ok[c];
      su[c] += d.travel_u;
      sb[c] += d.travel_bl;
      for (int q = 0; q < Pc; ++q) g[c][q] += d.grad[q];
    };
    farm(comm, items, compute, fo);

    // and steps
    if (rank == 0) {
      for (int c = 0; c < N; ++c) {
        if (ok[c] == 0) continue;
        curve_u[c] = su[c] / ok[c];
        curve_bl[c] = sb[c] / ok[c];
        // loss = −mean travel
        for (double& x : g[c]) x = -x / ok[c];
        if (C.optimizer == "adam")
          adam[c].step(params[c], g[c], C.lr, C.clip_norm, it + 1);
        else
          evo::normalized_step(params[c], g[c], C.lr);
      }
    }
    // curves: row `it` of each group's (I × columns) datasets
    write_slot_row(file, rank == 0, sgroups, slots, "curve_u", I, it, curve_u);
    write_slot_row(file, rank == 0, sgroups, slots, "curve_bl", I, it, curve_bl);
    write_slot_row(file, rank == 0, sgroups, slots, "nan_pairs", I, it, nan_pairs);
    if ((it + 1) % cfg.output.checkpoint_every == 0 || it + 1 == I) {
      write_state();
      stage.write_int("iterations_done", it + 1);
      checkpoint();
    }
    if (rank == 0) {
      const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count();
      std::printf("%s: iteration %d/%d:", spec.label.c_str(), it + 1, I);
      for (size_t gi = 0; gi < groups.size() && gi < 6; ++gi) {
        double m = 0;
        int k = 0;
        for (int c = 0; c < N; ++c)
          if (slots[c].group == groups[gi] && std::isfinite(curve_bl[c])) m += curve_bl[c], ++k;
        std::printf(" %s %.3f", groups[gi].substr(groups[gi].rfind('/') + 1).c_str(), k ? m / k : NAN);
      }
      if (groups.size() > 6) std::printf(" ...");
      std::printf(" BL; %.0f pair-episodes/s, %.0f s, ETA %.0f s\n", N * B / dt, el, (I - it - 1) * dt);
      std::fflush(stdout);
    }
  }
  if (rank == 0 && done >= I) std::printf("%s: all %d iterations were already done\n", spec.label.c_str(), I);

  write_trained_params(comm, file, sgroups, slots, params);
  return params;
}

void run_connectors_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                          const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& C = cfg.connectors;
  const std::vector<std::string>& kinds = C.kinds;
  const int K = static_cast<int>(kinds.size()), R = C.replicates;
  const std::vector<collective::Agent> agents = load_population(comm, file);
  const int pop = static_cast<int>(agents.size());

  if (!file.has("connectors")) file.create_group("connectors");
  io::h5::Node stage = file.group("connectors");
  stage.write_string("status", "running");
  stage.write_string("kinds", join(kinds));
  stage.write_int("replicates", R);
  if (!file.has(kAnchors)) {
    std::vector<int64_t> rows(pop);
    std::iota(rows.begin(), rows.end(), 0);
    if (rank != 0) rows.clear();
    file.write_rows<int32_t>(kAnchors, {static_cast<hsize_t>(pop), 4}, rows,
                             rank == 0 ? io::anchors_rows(agents) : std::vector<int32_t>{});
  }
  // connector c = kind·R + replicate, trained on flat
  std::vector<ConnectorSlot> slots;
  for (int k = 0; k < K; ++k)
    for (int r = 0; r < R; ++r)
      slots.push_back({io::stiffness(cfg, kinds[k]), io::connector_kind(kinds[k]).diverse, "flat", kConnectorsStage + k * R + r,
                       "connectors/" + kinds[k], r});
  TrainSpec spec{"connectors", "connectors", C.iterations, C.batch_pairs, C.episode_steps};
  train_connectors(comm, cfg, file, agents, slots, spec, checkpoint);
  stage.write_string("status", "complete");
  checkpoint();
}

}  // namespace divcoll::mpi
