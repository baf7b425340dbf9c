// memory known before it is spent: what a simulator needs for an episode, measured from two
// tiny probe episodes and extrapolated, checked against a limit before anything large is allocated.
#pragma once

#include <cstdint>
#include <string>

#include "sim/engine.hpp"
#include "sim/scene.hpp"

namespace divcoll {

// MemAvailable of /proc/meminfo in bytes (0 if it cannot be read)
uint64_t mem_available_bytes();

// the default limit: 80% of MemAvailable; `gb` > 0 overrides it (bytes)
uint64_t memory_limit_bytes(double gb);

// bytes a sim::Simulator holds for `scene` run with `opt` (workspace and tape), plus the recorded
// trajectory (opt.record) and hidden states (opt.record_hidden) it returns. The engine sizes every buffer
// as a + b·steps + c·steps·substeps; a, b and c are read off Simulator::workspace_bytes() after probe
// episodes of one and two steps at one and two substeps (on a copy with a tiny dt), so the estimate
// follows any change of the tape's layout. Refuses (InputError) a scene that needs too many substeps.
uint64_t episode_bytes(const sim::Scene& scene, const sim::RunOptions& opt);

// "3.2 GB"
std::string gb_text(uint64_t bytes);

}  // namespace divcoll
