#include "stages/population.hpp"

#include <cstdint>
#include <numeric>

#include "collective/builders.hpp"
#include "io/run_read.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

std::vector<morph::Agent> load_population(const sim::RunPhysics& physics, const io::h5::Node& file,
                                          const std::string& group) {
  // the main population's anchors are stored once, by the connectors stage; read back they are the numbers
  // compute_anchors gives (tests/mpi/run_determinism_test.sh compares every dataset across runs)
  const std::string at = io::anchors_path(group);
  const bool stored = file.has(at);
  // every rank reads (a read made by one rank alone unbalances the ranks' HDF5 metadata caches: io/h5.hpp)
  std::vector<morph::Agent> agents;
  for (const evo::Individual& x : io::read_final_population(file, group)) agents.push_back(x.agent);
  if (stored) io::read_anchors(file, at, agents);
  // otherwise anchors from each agent's own 1000-step run on flat: the same on every rank
  if (!stored)
    for (auto& a : agents) a.anchors = collective::compute_anchors(a, physics);
  return agents;
}

void store_anchors(Driver& driver, const std::string& group, const std::vector<morph::Agent>& agents) {
  const std::string at = io::anchors_path(group);
  if (driver.file().has(at)) return;
  Records records;
  if (driver.master()) {
    Record r{at, {static_cast<uint64_t>(agents.size()), 4}, std::vector<int64_t>(agents.size()), io::anchors_rows(agents)};
    std::iota(r.rows.begin(), r.rows.end(), int64_t{0});
    records.push_back(std::move(r));
  }
  driver.write(records);
}

}  // namespace divcoll::stages
