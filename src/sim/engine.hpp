// the simulator: runs scenes forward (SPEC §2) and, on request, backward for the gradient of travel.
//
// Design
// - A Scene is compiled once into a Model (flags for what the scene needs, flattened topology,
//   connector anchor sets, substep count). A scene without walls, wind, adhesion, belt or connectors
//   skips those stages entirely.
// - The step is a short fixed list of stages (sim/stages.hpp): control → [springs → free velocity →
//   contact] × substeps. Each stage has its adjoint beside it, with the same arguments.
// - With gradients on, each stage writes what its adjoint needs to the tape; the backward pass replays
//   the stages' adjoints in exact reverse order and never recomputes the forward state. Without
//   gradients no tape is kept (two state buffers only).
// - A batch is a list of same-shaped scenes (same N, S, A, C). It is simulated scene by scene with one
//   workspace: one episode's tape (≈ 6 MB for a 1000-step pair) stays in cache, where stepping all
//   scenes in lock-step would need B tapes and stream them from memory. Connector weights are shared
//   across the 5·C connector springs of a scene and evaluated as one GEMM.
// - Workspace and tape are sized once per shape and reused: the step loop allocates nothing.
// - A NaN/Inf or a runaway state ends only its own episode, with a status and the step and mass where
//   it happened; the other scenes of a batch are unaffected.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/scene.hpp"

namespace divcoll::sim {

enum class Status : uint8_t { ok = 0, nan = 1, unstable = 2 };
const char* status_name(Status s);

// what to compute for an episode
struct RunOptions {
  int steps = 1000;              // control steps T
  bool grad = false;             // reverse-mode gradient of travel (keeps a tape)
  int grad_window = 0;           // truncated backpropagation: > 0 cuts the adjoint of the state every this many
                                 // steps (the gradient of travel's per-window displacements, each window's start
                                 // state held fixed); 0 = the full gradient
  bool agent_param_grad = true;  // with grad: also w.r.t. the agents' controller weights (a third of the
                                 // MLP backward; connector training leaves them frozen and sets false)
  bool record = false;           // keep x, v, touch at every step for output
  bool record_hidden = false;    // keep the connectors' second hidden layer (32 per connector spring)
  int hidden_every = 1;          // record hidden states every this many steps
  bool record_tether = false;    // sum, over the episode, each connector spring's impulse and work on its two masses
                                 // (RunResult::tether): what a tether does to each agent of a collective
  bool record_inputs = false;    // keep the connectors' network inputs (11 per connector spring, SPEC §6.3) at the
                                 // steps where hidden states are recorded (every hidden_every steps)
  double speed_limit = 100.0;    // u/s; a mass faster than this marks the episode unstable
  bool float_networks = false;   // the controllers' networks in float (inputs, weights, activations and their
                                 // gradients; nn/mlp.hpp's float kernels), the physics in double: faster, and not
                                 // the spec's double precision (SPEC §10); false = the spec's step (run.precision)
};

// a run's two choices of how every episode is computed (run.contact, run.precision; config::run_physics reads them
// from a config). Nothing holds them for the process: whatever builds a run's scenes and episodes is given them
// and passes them on, the contact law into every environment it places (Environment::contact, so the scene
// carries it), the precision into every episode's options (RunOptions::float_networks)
struct RunPhysics {
  ContactLaw contact = ContactLaw::coulomb;
  bool float_networks = false;

  // options for an episode in this precision (every other field at its default)
  RunOptions options() const {
    RunOptions o;
    o.float_networks = float_networks;
    return o;
  }
  bool operator==(const RunPhysics&) const = default;
};

// what an episode produced
struct RunResult {
  double travel = 0;              // u, mean x at T minus mean x at 0 (NaN unless status ok)
  Status status = Status::ok;
  int bad_step = -1;              // the step at which a non-finite or runaway state appeared
  int bad_mass = -1;              // the first offending mass
  std::string message;            // human-readable account of a non-ok status
  int substeps = 1;               // physics substeps per step that were used
  bool redone_in_double = false;  // float_networks with grad: float's gradient was not finite (its range ends at
                                  // 3.4e38), so the episode was run again with the networks in double

  // contact events over the episode, counted per mass and substep (with grad only: read off the tape)
  struct ContactCounts {
    long floor = 0;     // floor contacts
    long wall = 0;      // wall contacts
    long sliding = 0;   // contacts where the friction projection is active (v'' ≠ b)
    long toi = 0;       // contacts whose time of impact is differentiable (0 ≤ t* ≤ h)
    long belt = 0;      // floor contacts on a moving belt
  } contacts;

  // with grad (zero when status is not ok)
  std::vector<double> grad_agent_params;      // (A x P_a), empty unless agent_param_grad
  std::vector<double> grad_connector_params;  // (P_c), empty when C = 0
  std::vector<double> grad_x0;                // (N x 2)
  std::vector<double> grad_rest_length;       // (S)

  // with record
  std::vector<double> x, v;        // ((T+1) x N x 2)
  std::vector<uint8_t> touch;      // ((T+1) x N)
  // with record_hidden: (n_records x C*5 x 32), n_records = ceil(T / hidden_every)
  std::vector<double> hidden;
  // with record_inputs: (n_records x C*5 x 11), the networks' inputs at those steps
  std::vector<double> inputs;
  // with record_tether: (C*5 x kTetherColumns) per connector spring s = (i, j), in connector then spring order,
  // summed over every physics substep of the episode (h = Δt / substeps; f the spring's force on i from SPEC §2
  // step 2 with the substep's starting x, v and o; −f acts on j; p a mass's path over the substep, the mean of
  // h·v at its start and its displacement Δx, so that a passive spring's work is its stored energy's loss to O(h²)):
  //   impulse_x_i, impulse_y_i   Σ f h               (mass·u/s; on j it is the negative)
  //   work_i, work_j             Σ f·p_i, Σ −f·p_j    (mass·u²/s², the work the spring did on each mass)
  //   force_time                 Σ |f| h             (mass·u/s, the spring's force magnitude integrated over time)
  std::vector<double> tether;
};

// the columns of RunResult::tether, in order
inline constexpr int kTetherColumns = 5;
inline constexpr const char* kTetherColumnNames[kTetherColumns] = {"impulse_x_i", "impulse_y_i", "work_i", "work_j",
                                                                   "force_time"};

class Simulator {
 public:
  Simulator();
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // one episode; throws InputError if the scene is invalid or needs more substeps than its file allows
  RunResult run(const Scene& scene, const RunOptions& opt);
  // a batch of same-shaped scenes (refused with InputError otherwise); results in scene order
  std::vector<RunResult> run_batch(const std::vector<Scene>& scenes, const RunOptions& opt);

  // bytes held by the workspace and tape (for the benchmark and for memory planning)
  size_t workspace_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// convenience: one episode with a fresh simulator
RunResult simulate(const Scene& scene, const RunOptions& opt);

}  // namespace divcoll::sim
