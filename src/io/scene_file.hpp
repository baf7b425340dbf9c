// scene files (SPEC §9): one sim::Scene per HDF5 file, written by the builders, read by `simulate`.
//
// Layout: root attributes format = "divcoll-scene", version = 1, the sim::Constants (dt, omega, n_sines,
// agent_alpha, agent_kappa, conn_alpha, conn_kappa_x, conn_kappa_v, eps_len, and substeps, which is
// optional on read and 0 when absent); datasets masses/{x0, m}, springs/{i, j, rest_length, stiffness,
// amplitude, damping}, agents/{mass_index, spring_index, params}, connectors/spring_index (also when
// C = 0, as C × 5 = 0 × 5), connector_params (only when C > 0); group env with the environment's
// constants as attributes (with the string contact, "coulomb" or "no_slip", and the double no_slip_keep, both
// optional on read: coulomb and 0 when absent) and dataset env/terrain (K × 3; the first x_start is written
// as -1e9).
#pragma once

#include <string>

#include "sim/scene.hpp"

namespace divcoll::io {

inline constexpr const char* kSceneFormat = "divcoll-scene";
inline constexpr int kSceneVersion = 1;

// reads and validates a scene file; throws InputError naming the file and the missing, misshapen or
// invalid attribute or dataset
sim::Scene read_scene(const std::string& path);

// validates `s` and writes it; an existing file is refused unless overwrite is set. Every array is
// written as is, so write → read gives back the same bits.
void write_scene(const std::string& path, const sim::Scene& s, bool overwrite = false);

}  // namespace divcoll::io
