// divcoll tether RUN.h5 --out DIR: what a run's tethers do to each agent of a deployed pair, in every environment of
// its deployment. Per pair: the free tether (no springs: each agent as it walks alone from the same start), the
// passive and follower references and the run's trained weak connector of the deployment's kind, each with the
// impulse and work its springs gave each agent (collective::tether_effect). Writes tether.csv (one row per episode),
// then runs divcoll_post.tether on it for tether.md and tether.png (the means per environment, deployment and
// connector; the same module draws the page over several populations' tables).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <unistd.h>

#include "cli/commands.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/references.hpp"
#include "collective/tether_effect.hpp"
#include "common/check.hpp"
#include "common/version.hpp"
#include "config/pipeline.hpp"
#include "io/h5.hpp"
#include "io/run_read.hpp"

namespace divcoll::cli {
namespace {

// one episode's row: which pair and connector, and the tether's account
struct TetherRow {
  std::string env, deployment, connector;
  int pair = 0, posterior = 0, anterior = 0;
  collective::TetherEffect effect;
};

std::string host() {
  char name[256] = {0};
  return gethostname(name, sizeof name - 1) == 0 ? std::string(name) : std::string("an unnamed host");
}

}  // namespace

int tether(const TetherArgs& a) {
  namespace fs = std::filesystem;
  io::h5::quiet_errors();
  const io::h5::File f = io::h5::File::open(a.run);
  DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run",
                       a.run << " is not a divcoll run file");
  DIVCOLL_THROW_UNLESS(f.has("deploy/diverse_pairs"), a.run << " has no deployment: run the deploy stage first");
  const config::RunConfig cfg = config::parse_config(f.read_string("config"), a.run + " (stored config)");
  const sim::RunPhysics physics = config::run_physics(cfg);
  DIVCOLL_THROW_UNLESS(a.pairs >= 1 && a.pairs <= cfg.deploy.pairs, "--pairs must be in [1, " << cfg.deploy.pairs << "]");
  DIVCOLL_THROW_UNLESS(a.replicate >= 0 && a.replicate < cfg.connectors.replicates,
                       "--replicate must be in [0, " << cfg.connectors.replicates - 1 << "]");
  fs::create_directories(a.out);
  const std::string csv_path = (fs::path(a.out) / "tether.csv").string();
  for (const char* name : {"tether.csv", "tether.md", "tether.png"})
    check_output_path((fs::path(a.out) / name).string(), a.force, {a.run});

  std::vector<morph::Agent> agents;
  for (const auto& x : io::read_final_population(f)) agents.push_back(x.agent);
  io::read_anchors(f, io::anchors_path("agents"), agents);
  const std::vector<int32_t> dp = f.read<int32_t>("deploy/diverse_pairs");
  const auto up = collective::deploy_uniform_pairs(cfg.deploy, cfg.connectors);
  const std::vector<std::string> envs = io::split(f.group("deploy").read_string("environments"));
  const int steps = a.steps > 0 ? a.steps : cfg.deploy.episode_steps;
  // each deployment's tethers, built once: the references (free first, the baseline of every difference), then the
  // trained weak kind of the deployment
  std::map<std::string, std::vector<collective::ReferenceConnector>> tethers;
  for (const std::string dep : {"uniform", "diverse"}) {
    for (std::string_view name : collective::kReferenceConnectors)
      tethers[dep].push_back(collective::reference_connector(cfg.connectors, name));
    const std::string kind = "weak_" + dep;
    tethers[dep].push_back({"trained", collective::tether(cfg.connectors, kind),
                            io::read_weights_row(f, "connectors/" + kind, a.replicate)});
  }

  sim::Simulator sim;
  std::vector<TetherRow> rows;
  const auto t0 = std::chrono::steady_clock::now();
  for (const std::string& env : envs) {
    for (const std::string dep : {"uniform", "diverse"}) {
      for (int q = 0; q < a.pairs; ++q) {
        const int p = dep == "diverse" ? dp[2 * q] : up[q].first, r = dep == "diverse" ? dp[2 * q + 1] : up[q].second;
        for (const auto& t : tethers[dep])
          rows.push_back({env, dep, t.name, q, p, r,
                          collective::tether_effect(sim, agents[p], agents[r], t.weights, t.tether, env, physics, steps)});
      }
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const size_t done = &env - &envs[0] + 1;
    std::printf("tether: %s done (%zu/%zu environments), %.0f s, ETA %.0f s\n", env.c_str(), done, envs.size(), s,
                s * (envs.size() - done) / done);
    std::fflush(stdout);
  }

  std::ofstream csv(csv_path);
  csv << "environment,deployment,connector,pair,posterior,anterior,status,pair_travel_bl,posterior_travel_bl,"
         "anterior_travel_bl,posterior_impulse_x,anterior_impulse_x,posterior_work,anterior_work,force_time\n";
  csv.precision(10);
  for (const auto& r : rows) {
    const auto& e = r.effect;
    csv << r.env << ',' << r.deployment << ',' << r.connector << ',' << r.pair << ',' << r.posterior << ','
        << r.anterior << ',' << sim::status_name(e.status) << ',' << e.pair_travel_bl << ',' << e.travel_bl[0] << ','
        << e.travel_bl[1] << ',' << e.impulse_x[0] << ',' << e.impulse_x[1] << ',' << e.work[0] << ',' << e.work[1]
        << ',' << e.force_time << '\n';
  }
  csv.close();
  DIVCOLL_THROW_UNLESS(csv, "cannot write " << csv_path);
  std::ostringstream prov;
  prov << "Run file `" << a.run << "` (commit " << f.read_string("git_commit") << "); command `divcoll tether " << a.run
       << " --pairs " << a.pairs << " --replicate " << a.replicate
       << (a.steps > 0 ? " --steps " + std::to_string(steps) : std::string()) << "`, divcoll " << DIVCOLL_VERSION
       << " (" << git_commit() << ") on " << host() << ", one core of "
       << std::thread::hardware_concurrency() << ". The first " << a.pairs << " deployed pairs of each deployment "
       << "(uniform: clones; diverse: the deploy stage's pairs), " << steps << " steps, the weak connector kind of the "
       << "deployment (replicate " << a.replicate << ") beside the passive and follower references.";
  std::printf("tether: wrote %s\n", csv_path.c_str());
  std::fflush(stdout);
  const int rc = run_python("divcoll_post.tether", {csv_path, "--out", a.out, "--provenance", prov.str()});
  DIVCOLL_THROW_UNLESS(rc == 0, "the page of " << csv_path << " failed (divcoll_post.tether exit " << rc << ")");
  return 0;
}

}  // namespace divcoll::cli
