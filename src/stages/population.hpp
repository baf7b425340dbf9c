// a run's agent population as the stages after the agents stage read it: the final agents of a population group
// with their anchors, and the anchors stored once with its first connector training. Every rank reads and writes
// alike (a read made by one rank alone unbalances the ranks' HDF5 metadata caches, io/h5.hpp)
#pragma once

#include <string>
#include <vector>

#include "io/h5.hpp"
#include "morph/agent.hpp"
#include "sim/engine.hpp"
#include "stages/driver.hpp"

namespace divcoll::stages {

// the final agent population of the run file on every rank, with its anchors: the stored ones
// (io::anchors_path: connectors/anchors, graded/<name>/connectors/anchors) once its connector training stored
// them, otherwise computed (deterministically, under the run's `physics`)
std::vector<morph::Agent> load_population(const sim::RunPhysics& physics, const io::h5::Node& file,
                                          const std::string& group = "agents");
// stores the anchors of `agents` (the population of `group`) once, at io::anchors_path(group), through the
// driver's write
void store_anchors(Driver& driver, const std::string& group, const std::vector<morph::Agent>& agents);

}  // namespace divcoll::stages
