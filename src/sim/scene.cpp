// scene model: parameter counts, the invariant checks of validate(), the stability rule and body lengths.
#include "sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "common/check.hpp"

namespace divcoll::sim {

namespace {

// output sizes of the two controllers (SPEC §4.3, §6.3)
constexpr int kAgentOutputs = kAgentSprings;
constexpr int kConnectorOutputs = 1;

// W (out × in) plus b per layer of in → 32 → 32 → out
int mlp_param_count(int in, int out) {
  return kHidden * in + kHidden + kHidden * kHidden + kHidden + out * kHidden + out;
}

// "springs/rest_length[3]" style names of array elements
std::string at(const char* dataset, size_t index) { return msg() << dataset << "[" << index << "]"; }

// every value of an array finite
void check_finite(const std::vector<double>& v, const char* dataset) {
  for (size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k]))
      throw InputError(msg() << at(dataset, k) << " is " << (std::isnan(v[k]) ? "NaN" : "infinite"));
  }
}

// the number of values an array must have
void check_size(size_t found, size_t expected, const char* dataset, const std::string& why) {
  DIVCOLL_THROW_UNLESS(found == expected,
                       dataset << " has " << found << " values, expected " << expected << " (" << why << ")");
}

// every index in [0, n), and distinct within each row of `row` entries when `row` > 0
void check_indices(const std::vector<int32_t>& idx, int n, const char* dataset, const char* what, int row) {
  for (size_t k = 0; k < idx.size(); ++k) {
    DIVCOLL_THROW_UNLESS(idx[k] >= 0 && idx[k] < n, at(dataset, k) << " = " << idx[k] << " is not a " << what
                                                                   << " index (the scene has " << n << " "
                                                                   << what << "s)");
  }
  if (row <= 0) return;
  for (size_t r = 0; r * row < idx.size(); ++r) {
    std::set<int32_t> seen;
    for (int c = 0; c < row; ++c) {
      const size_t k = r * row + c;
      DIVCOLL_THROW_UNLESS(seen.insert(idx[k]).second, at(dataset, k)
                                                           << " = " << idx[k] << " repeats a " << what
                                                           << " already listed in row " << r);
    }
  }
}

// a scalar in [lo, hi] (or (lo, hi] when lo_open)
void check_range(double v, const char* name, double lo, double hi, bool lo_open) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  DIVCOLL_THROW_UNLESS(
      ok, name << " = " << v << " is out of range " << (lo_open ? "(" : "[") << lo << ", " << hi << "]");
}

void validate_constants(const Constants& c) {
  DIVCOLL_THROW_UNLESS(std::isfinite(c.dt) && c.dt > 0, "dt = " << c.dt << " s must be positive and finite");
  DIVCOLL_THROW_UNLESS(std::isfinite(c.omega), "omega = " << c.omega << " must be finite");
  DIVCOLL_THROW_UNLESS(c.n_sines >= 0 && c.n_sines <= 10000,
                       "n_sines = " << c.n_sines << " must lie in [0, 10000]");
  DIVCOLL_THROW_UNLESS(c.substeps >= 0, "substeps = " << c.substeps << " must be >= 0 (0 = automatic)");
  check_range(c.agent_alpha, "agent_alpha", 0, 1, true);
  check_range(c.conn_alpha, "conn_alpha", 0, 1, true);
  DIVCOLL_THROW_UNLESS(std::isfinite(c.agent_kappa) && c.agent_kappa >= 0,
                       "agent_kappa = " << c.agent_kappa << " must be finite and >= 0");
  DIVCOLL_THROW_UNLESS(std::isfinite(c.conn_kappa_x) && c.conn_kappa_x >= 0,
                       "conn_kappa_x = " << c.conn_kappa_x << " must be finite and >= 0");
  DIVCOLL_THROW_UNLESS(std::isfinite(c.conn_kappa_v) && c.conn_kappa_v >= 0,
                       "conn_kappa_v = " << c.conn_kappa_v << " must be finite and >= 0");
  DIVCOLL_THROW_UNLESS(std::isfinite(c.eps_len) && c.eps_len > 0,
                       "eps_len = " << c.eps_len << " u must be positive and finite");
}

// the ranges of configs/environments.toml (the same ones config/environments.cpp enforces on the tables)
void validate_environment(const Environment& e) {
  for (const EnvironmentField& f : kEnvironmentFields)
    check_range(e.*(f.field), (std::string("env/") + f.name).c_str(), f.lo, f.hi, f.lo_open);
  DIVCOLL_THROW_UNLESS(e.contact == ContactLaw::coulomb || e.contact == ContactLaw::no_slip,
                       "env/contact = " << static_cast<int>(e.contact) << " is not a contact law (coulomb, no_slip)");

  // terrain: finite, bounded heights and slopes, sorted, every segment but the first >= 0.01 u wide
  const auto& t = e.terrain;
  DIVCOLL_THROW_UNLESS(!t.empty(), "env/terrain is empty (it needs at least one segment)");
  for (size_t k = 0; k < t.size(); ++k) {
    const double row[3] = {t[k].x_start, t[k].y_start, t[k].slope};
    const char* col[3] = {"x_start", "y_start", "slope"};
    for (int c = 0; c < 3; ++c) {
      DIVCOLL_THROW_UNLESS(std::isfinite(row[c]), "env/terrain["
                                                      << k << "] " << col[c] << " is "
                                                      << (std::isnan(row[c]) ? "NaN" : "infinite"));
    }
    DIVCOLL_THROW_UNLESS(std::abs(t[k].y_start) <= 100, "env/terrain: segment "
                                                            << k << " has y_start = " << t[k].y_start
                                                            << " u, outside [-100, 100]");
    DIVCOLL_THROW_UNLESS(std::abs(t[k].slope) <= 10, "env/terrain: segment " << k << " has slope "
                                                                             << t[k].slope
                                                                             << ", outside [-10, 10]");
  }
  // the first segment extends to -inf, so its line must not depend on its (ignored) x_start
  DIVCOLL_THROW_UNLESS(t[0].slope == 0, "env/terrain: segment 0 has slope " << t[0].slope
                                            << "; the first segment extends to -inf and must be flat (slope 0)");
  // segment 1's left neighbour extends to -inf, so the width rule starts at segment 2; the tolerance
  // absorbs the rounding of x_f + dx when tables are placed
  constexpr double kMinWidth = 0.01, kTol = 1e-12;
  for (size_t k = 2; k < t.size(); ++k) {
    const double w = t[k].x_start - t[k - 1].x_start;
    DIVCOLL_THROW_UNLESS(w >= 0, "env/terrain: segment " << k << " starts at " << t[k].x_start
                                                         << " u, before segment " << k - 1 << " (at "
                                                         << t[k - 1].x_start
                                                         << " u); segments must be sorted by x_start");
    DIVCOLL_THROW_UNLESS(w >= kMinWidth - kTol, "env/terrain: segment "
                                                    << k << " starts at " << t[k].x_start << " u, only " << w
                                                    << " u after segment " << k - 1
                                                    << " (the minimum width is " << kMinWidth << " u)");
  }
}

}  // namespace

const char* contact_law_name(ContactLaw law) { return law == ContactLaw::no_slip ? "no_slip" : "coulomb"; }

bool contact_law_from_name(const std::string& name, ContactLaw* law) {
  if (name == "coulomb") *law = ContactLaw::coulomb;
  else if (name == "no_slip") *law = ContactLaw::no_slip;
  else return false;
  return true;
}

int agent_input_size(const Constants& c) { return c.n_sines + 4 * kAgentMasses; }

int agent_param_count(const Constants& c) { return mlp_param_count(agent_input_size(c), kAgentOutputs); }

int connector_param_count(bool joint) {
  return joint ? mlp_param_count(kConnectorSprings * kConnectorInputs, kConnectorSprings)
               : mlp_param_count(kConnectorInputs, kConnectorOutputs);
}
bool joint_connector_params(size_t count) { return count == static_cast<size_t>(connector_param_count(true)); }

void validate(const Scene& s) { validate(s, ValidateOptions{}); }

void validate(const Scene& s, const ValidateOptions& opt) {
  validate_constants(s.constants);
  validate_environment(s.env);

  // shapes
  const size_t N = s.mass.size();
  DIVCOLL_THROW_UNLESS(N >= 1, "masses/m is empty (a scene needs at least one mass)");
  check_size(s.x0.size(), 2 * N, "masses/x0", "N x 2 with N = masses/m's length");
  const size_t S = s.spring_i.size();
  const std::string per_spring = "one per spring, S = springs/i's length";
  check_size(s.spring_j.size(), S, "springs/j", per_spring);
  check_size(s.rest_length.size(), S, "springs/rest_length", per_spring);
  check_size(s.stiffness.size(), S, "springs/stiffness", per_spring);
  check_size(s.amplitude.size(), S, "springs/amplitude", per_spring);
  check_size(s.damping.size(), S, "springs/damping", per_spring);
  DIVCOLL_THROW_UNLESS(s.agent_mass_index.size() % kAgentMasses == 0,
                       "agents/mass_index has " << s.agent_mass_index.size() << " values, not a multiple of "
                                                << kAgentMasses << " (A x " << kAgentMasses << ")");
  const size_t A = s.agent_mass_index.size() / kAgentMasses;
  check_size(s.agent_spring_index.size(), A * kAgentSprings, "agents/spring_index",
             msg() << "A x " << kAgentSprings << " with A = " << A);
  const size_t Pa = static_cast<size_t>(agent_param_count(s.constants));
  check_size(
      s.agent_params.size(), A * Pa, "agents/params",
      msg() << "A x P_a with A = " << A << ", P_a = " << Pa << " for n_sines = " << s.constants.n_sines);
  DIVCOLL_THROW_UNLESS(s.connector_spring_index.size() % kConnectorSprings == 0,
                       "connectors/spring_index has " << s.connector_spring_index.size()
                                                      << " values, not a multiple of " << kConnectorSprings
                                                      << " (C x " << kConnectorSprings << ")");
  const size_t C = s.connector_spring_index.size() / kConnectorSprings;
  if (C > 0) {
    const bool joint = joint_connector_params(s.connector_params.size());
    check_size(s.connector_params.size(), static_cast<size_t>(connector_param_count(joint)), "connector_params",
               msg() << "P_c for the scene's " << C << " connectors (" << connector_param_count(true)
                     << " for the joint network)");
  } else {
    check_size(s.connector_params.size(), 0, "connector_params",
               "it must be empty when there are no connectors");
  }

  // indices
  const int n = static_cast<int>(N), ns = static_cast<int>(S);
  check_indices(s.spring_i, n, "springs/i", "mass", 0);
  check_indices(s.spring_j, n, "springs/j", "mass", 0);
  for (size_t k = 0; k < S; ++k) {
    DIVCOLL_THROW_UNLESS(s.spring_i[k] != s.spring_j[k], "spring " << k << " joins mass " << s.spring_i[k]
                                                                   << " to itself (springs/i[" << k
                                                                   << "] == springs/j[" << k << "])");
  }
  check_indices(s.agent_mass_index, n, "agents/mass_index", "mass", kAgentMasses);
  check_indices(s.agent_spring_index, ns, "agents/spring_index", "spring", kAgentSprings);
  check_indices(s.connector_spring_index, ns, "connectors/spring_index", "spring", kConnectorSprings);

  // values
  check_finite(s.x0, "masses/x0");
  check_finite(s.mass, "masses/m");
  check_finite(s.rest_length, "springs/rest_length");
  check_finite(s.stiffness, "springs/stiffness");
  check_finite(s.amplitude, "springs/amplitude");
  check_finite(s.damping, "springs/damping");
  if (opt.finite_params) {
    check_finite(s.agent_params, "agents/params");
    check_finite(s.connector_params, "connector_params");
  }
  for (size_t k = 0; k < N; ++k)
    DIVCOLL_THROW_UNLESS(s.mass[k] > 0, at("masses/m", k) << " = " << s.mass[k] << " must be positive");
  for (size_t k = 0; k < S; ++k) {
    DIVCOLL_THROW_UNLESS(s.rest_length[k] > 0, at("springs/rest_length", k)
                                                   << " = " << s.rest_length[k] << " u must be positive");
    DIVCOLL_THROW_UNLESS(s.stiffness[k] >= 0, at("springs/stiffness", k)
                                                  << " = " << s.stiffness[k] << " must be >= 0");
    DIVCOLL_THROW_UNLESS(s.damping[k] >= 0, at("springs/damping", k)
                                                << " = " << s.damping[k] << " must be >= 0");
  }
}

double stability_number(const Scene& s, double dt) {
  // Σ k over the springs at each mass
  std::vector<double> ksum(s.mass.size(), 0.0);
  for (size_t k = 0; k < s.spring_i.size(); ++k) {
    ksum[s.spring_i[k]] += s.stiffness[k];
    ksum[s.spring_j[k]] += s.stiffness[k];
  }
  double worst = 0;
  for (size_t i = 0; i < s.mass.size(); ++i) worst = std::max(worst, dt * std::sqrt(ksum[i] / s.mass[i]));
  return worst;
}

int substeps_needed(const Scene& s, double limit) {
  DIVCOLL_THROW_UNLESS(limit > 0, "the stability limit must be positive (got " << limit << ")");
  const double q = std::ceil(stability_number(s, s.constants.dt) / limit);
  DIVCOLL_THROW_UNLESS(std::isfinite(q) && q < 1e6, "the scene needs "
                                                        << q << " substeps per step (dt*sqrt(sum k/m) = "
                                                        << stability_number(s, s.constants.dt)
                                                        << "); stiffness or dt too large");
  return std::max(1, static_cast<int>(q));
}

double body_length(const Scene& s, int agent) {
  DIVCOLL_THROW_UNLESS(agent >= 0 && agent < s.n_agents(),
                       "agent " << agent << " does not exist (the scene has " << s.n_agents() << ")");
  double lo = INFINITY, hi = -INFINITY;
  for (int r = 0; r < kAgentMasses; ++r) {
    const double x = s.x0[2 * static_cast<size_t>(s.agent_mass_index[agent * kAgentMasses + r])];
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return hi - lo;
}

double mean_body_length(const Scene& s) {
  const int A = s.n_agents();
  if (A > 0) {
    double sum = 0;
    for (int a = 0; a < A; ++a) sum += body_length(s, a);
    return sum / A;
  }
  // no agents: the extent of all masses
  if (s.mass.empty()) return 0;
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < s.mass.size(); ++i) {
    lo = std::min(lo, s.x0[2 * i]);
    hi = std::max(hi, s.x0[2 * i]);
  }
  return hi - lo;
}

}  // namespace divcoll::sim
