#include "io/memory.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <cmath>

namespace divcoll {

uint64_t mem_available_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  uint64_t kb = 0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ls(line);
    if (ls >> key >> kb >> unit && key == "MemAvailable:") return kb * 1024;
  }
  return 0;
}

uint64_t memory_limit_bytes(double gb) {
  if (gb > 0) return static_cast<uint64_t>(gb * 1e9);
  return mem_available_bytes() / 5 * 4;
}

uint64_t episode_bytes(const sim::Scene& scene, const sim::RunOptions& opt) {
  const int needed = sim::substeps_needed(scene);  // refuses more than 1e6 per step
  const int n = std::max(needed, scene.constants.substeps);
  auto probe = [&](int steps, int substeps) {
    sim::Scene s = scene;
    s.constants.dt = 1e-7;  // any substep count is stable: the probe measures buffers, not physics
    s.constants.substeps = substeps;
    sim::RunOptions o = opt;
    o.steps = steps;
    o.record = false;
    o.record_hidden = false;
    sim::Simulator sim;
    sim.run(s, o);
    return static_cast<double>(sim.workspace_bytes());
  };
  const double p11 = probe(1, 1), p21 = probe(2, 1), p12 = probe(1, 2);
  const double per_substep = p12 - p11, per_step = p21 - p11 - per_substep, fixed = p11 - per_step - per_substep;
  const double T = opt.steps;
  double bytes = fixed + per_step * T + per_substep * T * n;
  if (opt.record) bytes += (T + 1) * scene.n_masses() * (2 * 2 * sizeof(double) + 1);
  if (opt.record_hidden)
    bytes += std::ceil(T / std::max(opt.hidden_every, 1)) * sim::kConnectorSprings * scene.n_connectors() * 32 * sizeof(double);
  return static_cast<uint64_t>(std::max(bytes, 0.0));
}

std::string gb_text(uint64_t bytes) {
  char b[32];
  std::snprintf(b, sizeof b, bytes >= 100000000 ? "%.1f GB" : "%.3f GB", bytes / 1e9);
  return b;
}

}  // namespace divcoll
