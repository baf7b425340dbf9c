#include "collective/references.hpp"

#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "morph/body.hpp"
#include "nn/mlp.hpp"
#include "sim/scene.hpp"

namespace divcoll::collective {

std::vector<double> follower_connector_params(double amplitude, bool joint) {
  DIVCOLL_THROW_UNLESS(amplitude > 0, "the follower connector needs connectors.amplitude > 0, got " << amplitude);
  const nn::Layout L = joint ? nn::joint_connector_layout() : nn::connector_layout();
  const int in = L.sizes[0], h1 = L.sizes[1], h2 = L.sizes[2];
  std::vector<double> p(L.param_count(), 0.0);
  for (int r = 0; r < L.out(); ++r) {  // output r: spring r (one output, spring 0, per spring)
    const int l = sim::kConnectorInputs * r + sim::kConnectorInputs - 1;  // the spring's ℓ/L, last of its inputs
    p[L.weight_offset(0) + r * in + l] = 1.0;       // W1[r][ℓ/L]
    p[L.bias_offset(0) + r] = -1.0;                 // b1[r]: h1ᵣ = tanh(ℓ/L − 1)
    p[L.weight_offset(1) + r * h1 + r] = 1.0;       // W2[r][r]: h2ᵣ = tanh(h1ᵣ)
    p[L.weight_offset(2) + r * h2 + r] = 1.0 / amplitude;  // W3[r][r]: net = h2ᵣ / a
  }
  return p;
}

std::vector<double> initial_connector_params(const config::RunConfig::Connectors& connectors, double amplitude, Rng& rng) {
  const bool joint = connectors.network == "joint";
  if (connectors.init != "follower") return morph::init_connector_params(rng, connectors.init_out_gain, joint);
  std::vector<double> w = follower_connector_params(amplitude, joint);
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
