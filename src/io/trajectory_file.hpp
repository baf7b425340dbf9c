// trajectory files (SPEC §9): what `simulate --steps T [--grad]` writes, and what the parity tests read.
//
// Layout: datasets x, v ((T+1) × N × 2, float64), touch ((T+1) × N, uint8); root attributes travel (u),
// steps (T), status ("ok" | "nan" | "unstable"); with gradients, group grad with datasets agent_params
// (A × P_a), connector_params (P_c, only when non-empty), x0 (N × 2) and rest_length (S).
// On read, touch and status are optional (the parity files in testdata/parity have neither).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace divcoll::io {

struct Trajectory {
  int steps = 0;               // T
  int n_masses = 0;            // N
  std::vector<double> x, v;    // ((T+1) × N × 2) u, u/s
  std::vector<uint8_t> touch;  // ((T+1) × N) 0/1; empty if the file had none
  double travel = 0;           // u, mean x at step T minus mean x at step 0
  std::string status = "ok";   // "ok" | "nan" | "unstable"; "ok" when the file does not record it

  // gradient of travel (SPEC §9), present when has_grad
  bool has_grad = false;
  int n_agents = 0;                           // A (rows of grad/agent_params)
  std::vector<double> grad_agent_params;      // (A × P_a)
  std::vector<double> grad_connector_params;  // (P_c), empty when the scene has no connectors
  std::vector<double> grad_x0;                // (N × 2)
  std::vector<double> grad_rest_length;       // (S)
};

// true for "ok", "nan" and "unstable"
bool is_trajectory_status(const std::string& s);

// checks the shapes, then writes; an existing file is refused unless overwrite is set
void write_trajectory(const std::string& path, const Trajectory& t, bool overwrite = false);

// reads a trajectory file; throws InputError naming the file and the missing or misshapen dataset
Trajectory read_trajectory(const std::string& path);

}  // namespace divcoll::io
