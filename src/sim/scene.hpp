// scene model: plain data, exactly the content of a scene file (SPEC §9).
//
// A scene is built in code (src/collective/builders) or read from a scene file (src/io/scene_file)
// and is never changed by the simulator. All arrays are flat and row-major; every field says its
// shape and unit. Several scenes of the same shape form a batch (sim/batch.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace divcoll::sim {

// masses and springs per agent, and springs per connector (SPEC §1, §4.1, §6.2)
inline constexpr int kAgentMasses = 11;
inline constexpr int kAgentSprings = 21;
inline constexpr int kConnectorSprings = 5;
inline constexpr int kHidden = 32;  // width of both hidden layers of both controllers

// constants of the step and of the controllers (SPEC §2, §4.3, §6.3); written into every scene file
struct Constants {
  double dt = 0.004;            // s, one step
  double omega = 10.0;          // rad/s, agent sine frequency
  int n_sines = 10;             // agent sine inputs
  double agent_alpha = 0.15;    // agent actuation smoothing
  double agent_kappa = 0.05;    // agent sensor scale
  double conn_alpha = 0.1;      // connector actuation smoothing
  double conn_kappa_x = 10.0;   // connector position sensor scale
  double conn_kappa_v = 1.0;    // connector velocity sensor scale
  double eps_len = 1e-6;        // u, spring length regulariser
  int substeps = 0;             // physics substeps per step; 0 = choose from the stability rule
};

// one terrain segment: the line y = y_start + slope * (x - x_start) for x_start <= x < next x_start
struct Segment {
  double x_start = 0;  // u (the first segment's is ignored: it extends to -inf)
  double y_start = 0;  // u
  double slope = 0;    // dimensionless
};

// the contact law of SPEC §2.4: coulomb is the spec's (Coulomb friction, κ_t, time of impact); no_slip is
// DiffTaichi's mass_spring.py advance_toi (the velocity after contact is the surface's, plus κ_ns of the
// tangential relative velocity; same contact detection and time of impact). src/MODEL.md, "Contact laws"
enum class ContactLaw : uint8_t { coulomb = 0, no_slip = 1 };
// "coulomb" / "no_slip"
const char* contact_law_name(ContactLaw law);
// the law of that name; false (and *law untouched) for any other name
bool contact_law_from_name(const std::string& name, ContactLaw* law);

// every scalar field of an environment, the one table that the struct below, its validation (scene.cpp), the
// environments file (config/environments.cpp), the scene file (io/scene_file.cpp) and `divcoll envs` read:
//   X(name, default, lowest, highest, lowest excluded, optional in a scene file (read as the default when absent))
// A new field is one row here (and its meaning in configs/environments.toml and src/MODEL.md).
#define DIVCOLL_ENVIRONMENT_FIELDS(X)                                                                             \
  X(gravity, -4.8, -100, 0, false, false)      /* u/s^2 (negative: down) */                                    \
  X(damping, 15.0, 0, 1000, false, false)      /* 1/s, velocity decay gamma */                                 \
  X(friction, 1.0, 0, 100, false, false)       /* Coulomb mu */                                                \
  X(tangent_keep, 1.0, 0, 1, false, false)     /* kappa_t, extra tangential retention on contact */            \
  X(belt_speed, 0.0, 0, 10, false, false)      /* u/s, floor moves backward at this speed */                   \
  X(wind_amp, 0.0, -100, 100, false, false)    /* u/s^2, horizontal wind acceleration amplitude */             \
  X(wind_period, 4.0, 0, 1e6, true, false)     /* s */                                                         \
  X(adhesion, 0.0, 0, 100, false, false)       /* u/s^2, downward pull on masses near the surface */           \
  X(adhesion_band, 0.01, 0, 1, false, false)   /* u, height above the surface where adhesion acts */           \
  X(no_slip_keep, 0.0, 0, 1, false, true)      /* kappa_ns, tangential relative velocity kept under no_slip */

// an environment (SPEC §3): physical constants and terrain
struct Environment {
  std::string name = "flat";
#define DIVCOLL_ENVIRONMENT_FIELD(name, def, lo, hi, lo_open, optional) double name = def;
  DIVCOLL_ENVIRONMENT_FIELDS(DIVCOLL_ENVIRONMENT_FIELD)
#undef DIVCOLL_ENVIRONMENT_FIELD
  ContactLaw contact = ContactLaw::coulomb;  // the contact law (run.contact)
  std::vector<Segment> terrain{Segment{}};  // sorted by x_start, at least one
};

// the table as data: one row per scalar field of Environment
struct EnvironmentField {
  const char* name;
  double Environment::*field;
  double lo, hi;
  bool lo_open;   // the lowest value itself is refused
  bool optional;  // a scene file may leave it out (read as the default)
};
inline constexpr EnvironmentField kEnvironmentFields[] = {
#define DIVCOLL_ENVIRONMENT_FIELD(name, def, lo, hi, lo_open, optional) \
  {#name, &Environment::name, lo, hi, lo_open, optional},
    DIVCOLL_ENVIRONMENT_FIELDS(DIVCOLL_ENVIRONMENT_FIELD)
#undef DIVCOLL_ENVIRONMENT_FIELD
};

// a scene: N masses, S springs, A agents, C connectors
struct Scene {
  Constants constants;
  Environment env;

  std::vector<double> x0;    // (N x 2) u, initial positions
  std::vector<double> mass;  // (N) mass units

  std::vector<int32_t> spring_i, spring_j;  // (S) mass indices
  std::vector<double> rest_length;          // (S) u
  std::vector<double> stiffness;            // (S) force/u
  std::vector<double> amplitude;            // (S) relative actuation amplitude (0 = passive)
  std::vector<double> damping;              // (S) dashpot

  std::vector<int32_t> agent_mass_index;    // (A x 11) the agent's masses in its own order
  std::vector<int32_t> agent_spring_index;  // (A x 21) the spring each controller output drives
  std::vector<double> agent_params;         // (A x P_a) flat MLP parameters (SPEC §4.3)

  std::vector<int32_t> connector_spring_index;  // (C x 5)
  std::vector<double> connector_params;         // (P_c) shared connector MLP, empty when C = 0

  int n_masses() const { return static_cast<int>(mass.size()); }
  int n_springs() const { return static_cast<int>(spring_i.size()); }
  int n_agents() const { return static_cast<int>(agent_mass_index.size() / kAgentMasses); }
  int n_connectors() const { return static_cast<int>(connector_spring_index.size() / kConnectorSprings); }
};

// parameter counts of the two controllers (SPEC §4.3, §6.3)
int agent_input_size(const Constants& c);        // n_sines + 4 * 11
int agent_param_count(const Constants& c);       // 3509 with the defaults
inline constexpr int kConnectorInputs = 11;
// the connector network (connectors.network): per spring = SPEC §6.3's 11 → 32 → 32 → 1 applied to each of the five
// springs (1473 weights); joint = one 55 → 32 → 32 → 5 network per connector that reads the five springs' inputs in
// spring order and drives the five springs (3013 weights). A scene's connector_params say which: their count.
int connector_param_count(bool joint = false);   // 1473, or 3013 joint
// connector_params of a scene hold the joint network (their count is connector_param_count(true))
bool joint_connector_params(size_t count);

// checks every structural and numerical invariant of a scene (shapes, index ranges, finite values,
// sorted terrain with segments at least 0.01 u wide, positive masses and rest lengths ...).
// throws divcoll::InputError naming the first problem.
void validate(const Scene& s);
// the same with the finiteness of the controller parameters (agents/params, connector_params) optional:
// a simulator given weights that training turned NaN can then end the episode with a status instead
struct ValidateOptions {
  bool finite_params = true;  // refuse NaN/Inf in agent_params and connector_params
};
void validate(const Scene& s, const ValidateOptions& opt);

// Δt·sqrt(Σ k_s / m) at the worst mass (SPEC §2 stability rule; < 2 is stable)
double stability_number(const Scene& s, double dt);
// the substeps a scene needs so that the number per substep stays below `limit`
int substeps_needed(const Scene& s, double limit = 1.9);

// centre of mass x at t = 0 and body lengths (SPEC §1)
double body_length(const Scene& s, int agent);      // max x − min x of the agent's x0
double mean_body_length(const Scene& s);

}  // namespace divcoll::sim
