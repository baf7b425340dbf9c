// A/B driver for the engine (jobs/BENCHMARKS.md, "Engine A/B: two builds measured together"): the same fixed work
// through one build's engine, timed by the thread's CPU time, so that two builds can be compared on a busy machine;
// jobs/engine_ab.py runs two such drivers in turn. Not built by CMake: it is compiled once against each tree's
// libraries, the tree under test and the base (e.g. a `git worktree` of the base commit built with jobs/build.sh).
//   a tree of today's layout (one library per layer), TREE its checkout with TREE/build built:
//   g++ -std=c++20 -O3 -march=native -ffp-contract=off -DHAS_AGRAD -DHAS_PHYSICS -DHAS_FLOAT -I TREE/src -I TREE \
//       jobs/engine_ab_driver.cpp TREE/build/libdivcoll_science.a TREE/build/libdivcoll_config.a \
//       TREE/build/libdivcoll_engine.a -ltomlplusplus -lpagmo -o ab
//   a base tree older than a feature leaves out its macro: -DHAS_AGRAD needs RunOptions::agent_param_grad (without
//   it every gradient block is computed, as such a tree must), -DHAS_PHYSICS builders that take the contact law and
//   a compute_anchors that takes the run's physics (sim::RunPhysics), -DHAS_FLOAT RunOptions::float_networks (with
//   it, DIVCOLL_AB_FLOAT=1 in the environment runs the networks in float: a two-line script
//   `DIVCOLL_AB_FLOAT=1 exec ./ab "$@"` is then the float side of engine_ab.py's pair). A tree from before the
//   libraries were split by layer (e.g. dea5a14) links its one TREE/build/libdivcoll_core.a -ltomlplusplus
//   -lboost_serialization instead.
//   ./ab KIND BATCH STEPS GRAD AGENT_PARAM_GRAD REPS   (KIND: agent, pair, chain20) prints scene-steps per CPU
//   second, CPU seconds and a checksum (equal checksums: the same bits)
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <string>
#include <vector>
#include "collective/builders.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"
using namespace divcoll;
#ifdef HAS_PHYSICS
#define AB_LAW sim::ContactLaw::coulomb,
#define AB_PHYSICS sim::RunPhysics{},
#else
#define AB_LAW
#define AB_PHYSICS
#endif
int main(int argc, char** argv) {
  const std::string kind = argv[1];
  const int batch = atoi(argv[2]), steps = atoi(argv[3]), grad = atoi(argv[4]), agrad = atoi(argv[5]), reps = atoi(argv[6]);
  std::vector<morph::Agent> agents;
  Rng rng(seed_for(7, 99, 0));
  for (int q = 0; q < 24; ++q) {
    agents.push_back(collective::random_agent(rng));
    agents.back().anchors = collective::compute_anchors(agents.back(), AB_PHYSICS {}, 300);
  }
  auto conn = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);  // what `divcoll bench` uses
  const collective::Tether weak{5e3, 0.6};  // the default config's weak connector
  std::vector<sim::Scene> scenes;
  for (int b = 0; b < batch; ++b) {
    if (kind == "agent") scenes.push_back(collective::agent_scene(agents[b % 24], "flat", AB_LAW {}));
    else if (kind == "pair") scenes.push_back(collective::pair_scene(agents[b % 24], agents[(b + 1) % 24], conn, weak, "flat", AB_LAW {}));
    else { std::vector<const morph::Agent*> ch; for (int q = 0; q < 20; ++q) ch.push_back(&agents[(b + q) % 24]);
      scenes.push_back(collective::chain_scene(ch, conn, weak, "flat", AB_LAW {})); }
  }
  sim::Simulator sim;
  sim::RunOptions opt; opt.steps = steps; opt.grad = grad;
#ifdef HAS_AGRAD
  opt.agent_param_grad = agrad;
#else
  (void)agrad;
#endif
#ifdef HAS_FLOAT
  opt.float_networks = std::getenv("DIVCOLL_AB_FLOAT") != nullptr;  // the networks in float
#endif
  double s = 0;
  sim.run_batch({scenes.front()}, opt);
  timespec t0, t1;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
  for (int r = 0; r < reps; ++r) for (auto& res : sim.run_batch(scenes, opt)) s += res.travel + (grad && !res.grad_connector_params.empty() ? res.grad_connector_params[0] : 0);
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
  const double cpu = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  std::printf("%.0f %.4f %.17g\n", double(reps) * batch * steps / cpu, cpu, s);
}
