// a scene compiled for the step: flattened topology, derived constants and the flags that let a scene
// skip what it does not need (walls, wind, adhesion, belt, spring dashpots, connectors).
// internal to src/sim.
#pragma once

#include <cstdint>
#include <vector>

#include "common/aligned.hpp"
#include "nn/mlp.hpp"
#include "sim/scene.hpp"

namespace divcoll::sim {

struct Model {
  const Scene* scene = nullptr;
  int N = 0, S = 0, A = 0, C = 0, K = 0;
  int substeps = 1;
  double dt = 0;          // s, control step
  double h = 0;           // s, physics substep dt / substeps
  double decay = 1;       // exp(−γ h)

  // what the scene needs
  bool has_walls = false;       // terrain with more than one segment (also: slopes change)
  bool has_wind = false;
  bool has_adhesion = false;
  bool has_belt = false;
  bool has_dashpots = false;    // any spring damping > 0
  bool has_connectors = false;

  // terrain as separate arrays (K)
  LineVector<double> seg_x, seg_y, seg_s;

  LineVector<double> inv_mass;  // (N)
  // the springs stages' per-spring values between their two loops (4 × S); scratch, hence mutable
  mutable LineVector<double> spring_scratch;

  // controllers
  nn::Layout agent_layout, conn_layout;
  int agent_params = 0, conn_params = 0;
  // the connector network (sim::connector_param_count): per spring (conn_layout 11 → 32 → 32 → 1 on conn_cols =
  // 5·C columns, one per spring) or joint (55 → 32 → 32 → 5 on conn_cols = C columns, one per connector). Both
  // read the same input block (11 values per spring, springs in order, connectors in order) and write the same
  // outputs (one per spring, in that order): only the network's columns differ
  int conn_cols = 0;
  // the controllers' weights packed for the MLP kernels (nn::pack): A × nn::packed_count(agent_layout), and
  // nn::packed_count(conn_layout) for the connectors' shared weights
  int agent_packed_count = 0;
  LineVector<double> agent_packed, conn_packed;
  // the same weights rounded to float, packed for the float kernels (RunOptions::float_networks only; pack_float())
  int agent_packed_count_f = 0;
  LineVector<float> agent_packed_f, conn_packed_f;
  // the packed weights for the kernels' scalar T
  template <class T>
  const T* agent_packed_for() const {
    if constexpr (sizeof(T) == sizeof(double)) return agent_packed.data();
    else return agent_packed_f.data();
  }
  template <class T>
  const T* conn_packed_for() const {
    if constexpr (sizeof(T) == sizeof(double)) return conn_packed.data();
    else return conn_packed_f.data();
  }
  template <class T>
  int agent_packed_count_for() const {
    return sizeof(T) == sizeof(double) ? agent_packed_count : agent_packed_count_f;
  }
  // distinct anchor masses per connector: conn_anchor[conn_anchor_start[c] .. conn_anchor_start[c+1])
  std::vector<int32_t> conn_anchor_start, conn_anchor;

  // the agents' sine inputs sin(ω t Δt + 2π j / n_sines) of steps t < sine_steps (sine_steps × n_sines): the
  // same for every scene with the same constants, so kept across compiles and computed once per batch
  LineVector<double> sines;
  int sine_steps = 0;

  // compiles `s` (validated by the caller); reuses this model's buffers (the sine table too, if it still fits)
  void compile(const Scene& s, int substeps);
  // makes the sine table cover steps [0, steps) for the compiled scene's constants
  void prepare_sines(int steps);
  // packs the compiled scene's controller weights for the float kernels
  void pack_float();
  double sine_omega_ = 0, sine_dt_ = 0;  // the constants the table was made for
  int sine_n_ = 0;
};

}  // namespace divcoll::sim
