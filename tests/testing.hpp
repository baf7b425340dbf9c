// helpers shared by the tests: paths to shared test data and to the built binary, test agents
#pragma once

#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "collective/builders.hpp"
#include "collective/deploy_variants.hpp"
#include "config/config.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"

namespace divcoll::testing {
// the spec's physics, Coulomb contact and the networks in double: what the tests build and run unless they say
// otherwise (nothing in the process holds a run's physics: every scene and episode is given it)
inline constexpr sim::RunPhysics kSpec{};
inline constexpr sim::ContactLaw kCoulomb = sim::ContactLaw::coulomb;
// the weak and the strong connector of the default config (connectors.weak_stiffness, strong_stiffness,
// amplitude, damping: the schema is their one home)
inline collective::Tether weak_connector() { return collective::strength_tether(config::default_config().connectors, "weak"); }
inline collective::Tether strong_connector() { return collective::strength_tether(config::default_config().connectors, "strong"); }

// the project's shared folder (SPEC, parity scenes): the environment variable DIVCOLL_SHARED_DIR when set,
// else the CMake cache variable of the same name (default: ../shared beside the checkout)
inline std::string shared_dir() {
  const char* e = std::getenv("DIVCOLL_SHARED_DIR");
  return e && *e ? std::string(e) : std::string(DIVCOLL_SHARED_DIR);
}
inline std::string parity_dir() { return shared_dir() + "/testdata/parity"; }
inline std::string source_dir() { return DIVCOLL_SOURCE_DIR; }
inline std::string divcoll_binary() { return DIVCOLL_BINARY; }
// runs the divcoll binary with args (a shell word list); its exit code and its stdout and stderr together
struct Exec {
  int code;
  std::string out;  // stdout and stderr
};
inline Exec run_divcoll(const std::string& args) {
  const std::string cmd = divcoll_binary() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// the text of a document of the checkout, path relative to its root ("" if it cannot be read); readme(): README.md
inline std::string doc(const std::string& path) {
  std::ifstream in(source_dir() + "/" + path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
inline std::string readme() { return doc("README.md"); }
// a random agent from stream (seed, `stream`) with anchors from a short (300-step) run on flat
inline morph::Agent agent_with_anchors(uint64_t seed, uint64_t stream) {
  Rng rng = make_rng(seed, stream, 0);
  morph::Agent a = collective::random_agent(rng);
  a.anchors = collective::compute_anchors(a, kSpec, {}, 300);
  return a;
}

// the engine's gradient tests' pair (tests/sim/gradient_test.cpp, float_networks_test.cpp): two random agents with
// anchors and connector weights with nonzero biases (so that every term matters), from stream (11, 1)
struct GradientPair {
  morph::Agent p, a;
  std::vector<double> conn;
};
inline const GradientPair& gradient_pair() {
  static const GradientPair f = [] {
    GradientPair f;
    Rng rng = make_rng(11, 1, 0);
    f.p = collective::random_agent(rng);
    f.a = collective::random_agent(rng);
    f.p.anchors = collective::compute_anchors(f.p, kSpec, {}, 300);
    f.a.anchors = collective::compute_anchors(f.a, kSpec, {}, 300);
    f.conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
    for (double& w : f.conn) w += 0.05 * normal(rng);
    return f;
  }();
  return f;
}
inline double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double r = 0;
  for (size_t i = 0; i < a.size(); ++i) r += a[i] * b[i];
  return r;
}
// a unit vector of n normal draws from stream (seed, stream, n): a direction for directional derivatives
inline std::vector<double> unit_direction(size_t n, uint64_t seed, uint64_t stream) {
  Rng rng = make_rng(seed, stream, n);
  std::vector<double> d(n);
  for (double& x : d) x = normal(rng);
  const double norm = std::sqrt(dot(d, d));
  for (double& x : d) x /= norm;
  return d;
}
}  // namespace divcoll::testing
