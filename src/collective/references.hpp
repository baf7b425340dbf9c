// the reference connectors: three connectors that need no training, deployed beside the trained ones so that a
// trained connector's travel reads as a share of what is reachable (deploy.references)
//
//   free      no tether: the five springs have stiffness 0 and no dashpot, so each agent of a pair moves exactly as
//             it does alone from the same start; the pair's travel is its agents' travel side by side
//   passive   a weak connector whose network outputs 0 (every weight 0): the springs keep their rest lengths, a
//             fixed-length tether between the posterior's front and the anterior's back
//   follower  a weak connector run by a hand-written network with four non-zero weights that sets each spring's
//             target length to the length it has: out ≈ (ℓ/L − 1)/a (follower_connector_params), so the springs
//             pull little; the controller's 0.1 output smoothing (SPEC §6.3) makes it lag a fast stretch
//
// Each is a weak connector (connectors.weak_stiffness, amplitude and, for passive and follower, damping), one weight
// set per reference, no replicate.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "collective/builders.hpp"
#include "common/rng.hpp"
#include "config/config.hpp"

namespace divcoll::collective {

// the references in the order deploy stores them
inline constexpr std::array<std::string_view, 3> kReferenceConnectors = {"free", "passive", "follower"};

// the follower policy in the connector network's layout (11 → 32 → 32 → 1, SPEC §6.3; nn::connector_layout):
// h1₀ = tanh(ℓ/L − 1), h2₀ = tanh(h1₀), net = h2₀ / amplitude, every other weight and bias 0. Its four non-zero
// values are W1[0][10] = 1 (input 10 is ℓ/L), b1[0] = −1, W2[0][0] = 1 and W3[0][0] = 1/amplitude, so near rest
// length out = tanh(net) ≈ (ℓ/L − 1)/a and the spring's target L·(1 + a·out) ≈ ℓ. amplitude must be > 0.
// joint: the same policy in the joint network (55 → 32 → 32 → 5, nn::joint_connector_layout): spring r's output reads
// input 11r + 10 through hidden units r of both layers, 20 non-zero values; it drives every spring as the per-spring
// follower does, bit for bit (tests/collective/references_test.cpp)
std::vector<double> follower_connector_params(double amplitude, bool joint = false);

// the weights a connector's training starts from (connectors.init), in the network of connectors.network: random =
// morph::init_connector_params with connectors.init_out_gain; follower = follower_connector_params(amplitude) plus
// N(0, init_noise²) per weight, drawn in storage order from `rng`
std::vector<double> initial_connector_params(const config::RunConfig::Connectors& connectors, double amplitude, Rng& rng);

// reference `name` (one of kReferenceConnectors) built from the [connectors] section
struct ReferenceConnector {
  std::string name;
  Tether tether;
  std::vector<double> weights;  // sim::connector_param_count() values
};
ReferenceConnector reference_connector(const config::RunConfig::Connectors& connectors, std::string_view name);

}  // namespace divcoll::collective
