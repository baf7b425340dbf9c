// what a run's stages need before any work, for the run's checks before it starts (divcoll run agrees on every rank
// what these refuse): the results of the stages each reads, sound where they are stored, and the memory of the
// longest episode with gradients. The stages that run: the config's run.stages, or with `agents_only` the agents
// stage alone (divcoll evolve)
#pragma once

#include <cstdint>
#include <string>

#include "config/config.hpp"

namespace divcoll::stages {

// refuses (InputError naming the stage, the stage it reads and where it looked) a stage that would run without the
// results it reads, and stored results it reads that hold a NaN or Inf. `existing`: the run file being continued
// ("" for a new one); with `from`, the stages of `base` before `from` count as present (--from STAGE --base OLD.h5)
void check_inputs(const config::RunConfig& cfg, bool agents_only, const std::string& existing, const std::string& from,
                  const std::string& base);

// the simulator tape of the longest episode with gradients the stages make (every rank's simulator holds one)
struct Tape {
  std::uint64_t bytes = 0;
  std::string what;  // what sets it: "connectors.episode_steps = 1000, 2 substep(s) per step"
};
Tape largest_tape(const config::RunConfig& cfg, bool agents_only);

}  // namespace divcoll::stages
