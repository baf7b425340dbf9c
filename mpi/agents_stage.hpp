// the agents stage (SPEC §4): a population co-designed by evolution (on the master) and gradient
// descent (on every rank), written generation by generation into the run file.
//
// Run file layout of the stage (group /agents):
//   attributes  status ("running" | "complete"), generations_done (groups gen_000 .. complete), population
//   gen_NNN/    every candidate of generation NNN (gen_000: the P random agents after training; later
//               generations: the P parents, then their P offspring), one row each:
//     id, parent (int64; parent −1 in generation 0), cells, springs (int64 genotypes),
//     rest_pos (M×11×2, u), spring_i, spring_j (M×21 int32), rest_length (M×21, u), amplitude (M×21),
//     params (M×P_a), fitness (M, travel in body lengths), travel_u (M, u), status (M uint8: 0 ok,
//     1 nan, 2 unstable), descriptor (M×9), uniqueness (M, in the whole pool), survived (M uint8),
//     curve_u (M×(epochs+1): travel at each evaluation of this generation's training; NaN for parents)
//   final/      the surviving population after the last generation (same datasets, P rows), which the
//               later stages read
// Rows are written by the rank that trained them; the master writes the rest (parallel HDF5).
// A generation is a checkpoint: --resume continues after the last complete one, bit-identically.
#pragma once

#include <mpi.h>

#include <functional>
#include <string>
#include <vector>

#include "evo/evolution.hpp"
#include "config/config.hpp"
#include "io/h5.hpp"
#include "config/pipeline.hpp"

namespace divcoll::mpi {

// random-number stage id of generation g of the agents stage (SPEC §10: seeds are (run, stage, item))
inline constexpr uint64_t kAgentsStage = io::stage_stream("agents");

// where and how a population is evolved: the main one (defaults) or a graded-diversity one (SPEC §7.5)
struct AgentsSpec {
  std::string group = "agents";        // run-file group of the generations and the final population
  std::string label = "agents";        // progress lines
  uint64_t stream = kAgentsStage;      // random stream of generation g: stream + g
  uint32_t fixed_cells = 0;            // generation 0 takes this body (0: random bodies)
  uint32_t fixed_springs = 0;          // ... and these springs (0: random springs)
  bool spring_descriptor = false;      // uniqueness on the spring-dependent descriptor entries
};
void run_agents_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                      const std::function<void()>& checkpoint, const AgentsSpec& spec);

// runs (or resumes) the stage on `comm`; rank 0 prints progress. Every rank calls it. `checkpoint` is
// called (collectively) after every output.checkpoint_every generations and at the end of the stage.

}  // namespace divcoll::mpi
