#include "collective/references.hpp"

#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "morph/body.hpp"
#include "nn/mlp.hpp"
#include "sim/scene.hpp"

namespace divcoll::collective {

std::vector<double> follower_connector_params(double amplitude) {
  DIVCOLL_THROW_UNLESS(amplitude > 0, "the follower connector needs connectors.amplitude > 0, got " << amplitude);
  const nn::Layout L = nn::connector_layout();
  const int in = L.sizes[0], h1 = L.sizes[1];
  std::vector<double> p(L.param_count(), 0.0);
  p[L.weight_offset(0) + 0 * in + (in - 1)] = 1.0;  // W1[0][ℓ/L]: the last input is the spring's ℓ/L
  p[L.bias_offset(0) + 0] = -1.0;                   // b1[0]: h1₀ = tanh(ℓ/L − 1)
  p[L.weight_offset(1) + 0 * h1 + 0] = 1.0;         // W2[0][0]: h2₀ = tanh(h1₀)
  p[L.weight_offset(2) + 0] = 1.0 / amplitude;      // W3[0][0]: net = h2₀ / a
  return p;
}

std::vector<double> initial_connector_params(const config::RunConfig::Connectors& connectors, double amplitude, Rng& rng) {
  if (connectors.init != "follower") return morph::init_connector_params(rng, connectors.init_out_gain);
  std::vector<double> w = follower_connector_params(amplitude);
  for (double& x : w) x += connectors.init_noise * normal(rng);
  return w;
}

ReferenceConnector reference_connector(const config::RunConfig::Connectors& connectors, std::string_view name) {
  ReferenceConnector r{std::string(name), tether(connectors, "weak_uniform"),
                       std::vector<double>(sim::connector_param_count(), 0.0)};
  if (name == "free") {
    r.tether = Tether{0.0, connectors.amplitude, 0.0};
  } else if (name == "follower") {
    r.weights = follower_connector_params(connectors.amplitude);
  } else {
    DIVCOLL_THROW_UNLESS(name == "passive", "no reference connector " << name << " (free, passive, follower)");
  }
  return r;
}

}  // namespace divcoll::collective
