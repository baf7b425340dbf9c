#include "mpi/connectors_stage.hpp"

#include <numeric>

#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "mpi/driver.hpp"
#include "mpi/protocol.hpp"

namespace divcoll::mpi {

std::vector<collective::Agent> load_population(MPI_Comm, const io::RunConfig& cfg, const io::h5::Node& file,
                                               const std::string& group) {
  // the main population's anchors are stored once, by the connectors stage; read back they are the numbers
  // compute_anchors gives (tests/mpi/run_determinism_test.sh compares every dataset across runs)
  const std::string at = io::anchors_path(group);
  const bool stored = file.has(at);
  // every rank reads (a read made by one rank alone unbalances the ranks' HDF5 metadata caches: io/h5.hpp)
  std::vector<collective::Agent> agents;
  for (const evo::Individual& x : io::read_final_population(file, group)) agents.push_back(x.agent);
  if (stored) io::read_anchors(file, at, agents);
  // otherwise anchors from each agent's own 1000-step run on flat: the same on every rank
  if (!stored)
    for (auto& a : agents) a.anchors = collective::compute_anchors(a, io::run_physics(cfg));
  return agents;
}

void store_anchors(MPI_Comm comm, const io::h5::File& file, const std::string& group,
                   const std::vector<collective::Agent>& agents) {
  const std::string at = io::anchors_path(group);
  if (file.has(at)) return;
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::vector<int64_t> rows(agents.size());
  std::iota(rows.begin(), rows.end(), 0);
  if (rank != 0) rows.clear();
  file.write_rows<int32_t>(at, {static_cast<hsize_t>(agents.size()), 4}, rows,
                           rank == 0 ? io::anchors_rows(agents) : std::vector<int32_t>{});
}

void run_connectors_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                          const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const auto& C = cfg.connectors;
  const std::vector<std::string>& kinds = C.kinds;
  const int K = static_cast<int>(kinds.size()), R = C.replicates;
  const std::vector<collective::Agent> agents = load_population(comm, cfg, file);

  io::h5::Node stage = file.group("connectors");
  stage.write_string("kinds", join(kinds));
  stage.write_int("replicates", R);
  store_anchors(comm, file, "agents", agents);
  // connector c = kind·R + replicate, trained on flat
  std::vector<ConnectorSlot> slots;
  for (int k = 0; k < K; ++k)
    for (int r = 0; r < R; ++r)
      slots.push_back({collective::tether(cfg, kinds[k]), io::connector_kind(kinds[k]).diverse, "flat", kConnectorsStage + k * R + r,
                       "connectors/" + kinds[k], r});
  TrainSpec spec{"connectors", "connectors", C.iterations, C.batch_pairs, C.episode_steps};
  train_connectors(comm, cfg, file, agents, slots, spec, checkpoint);
}

}  // namespace divcoll::mpi
