// divcoll tether RUN.h5 --out DIR: what a run's tethers do to each agent of a deployed pair, in every environment of
// its deployment. Per pair: the free tether (no springs: each agent as it walks alone from the same start), the
// passive and follower references and the run's trained weak connector of the deployment's kind, each with the
// impulse and work its springs gave each agent (collective::tether_effect). Writes tether.csv (one row per episode)
// and tether.md (means per environment, deployment and connector).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
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

// the means of tether.md for one (environment, deployment, connector) against the free tether of the same pairs; the
// slower agent of a pair is the one that travels less under the free tether
void write_summary(std::ostream& md, const std::vector<TetherRow>& rows, const std::vector<std::string>& connectors) {
  md << "| environment | pairs | connector | pair (BL) | pair − free (BL) | slower agent − free (BL) | faster agent − free "
        "(BL) | impulse on the slower agent (mass·u/s) | work on the pair (mass·u²/s²) | ∫\\|f\\|dt (mass·u/s) |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  const size_t k = connectors.size();
  for (size_t at = 0; at + k <= rows.size();) {
    const std::string env = rows[at].env, dep = rows[at].deployment;
    size_t end = at;
    while (end < rows.size() && rows[end].env == env && rows[end].deployment == dep) end += k;
    for (size_t c = 1; c < k; ++c) {
      double n = 0, pair = 0, dpair = 0, dslow = 0, dfast = 0, jslow = 0, work = 0, ft = 0;
      for (size_t r = at; r < end; r += k) {
        const auto& f = rows[r].effect;  // the free tether's episode of this pair
        const auto& e = rows[r + c].effect;
        if (f.status != sim::Status::ok || e.status != sim::Status::ok) continue;
        const int slow = f.travel_bl[0] <= f.travel_bl[1] ? 0 : 1;
        n += 1, pair += e.pair_travel_bl, dpair += e.pair_travel_bl - f.pair_travel_bl;
        dslow += e.travel_bl[slow] - f.travel_bl[slow], dfast += e.travel_bl[1 - slow] - f.travel_bl[1 - slow];
        jslow += e.impulse_x[slow], work += e.work[0] + e.work[1], ft += e.force_time;
      }
      char line[512];
      std::snprintf(line, sizeof line, "| %s | %s, %d | %s | %.2f | %+.2f | %+.2f | %+.2f | %+.3f | %+.3f | %.2f |\n",
                    env.c_str(), dep.c_str(), static_cast<int>(n), connectors[c].c_str(), pair / n, dpair / n,
                    dslow / n, dfast / n, jslow / n, work / n, ft / n);
      md << line;
    }
    at = end;
  }
}

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
  const std::string csv_path = (fs::path(a.out) / "tether.csv").string(), md_path = (fs::path(a.out) / "tether.md").string();
  check_output_path(csv_path, a.force, {a.run});
  check_output_path(md_path, a.force, {a.run});

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
  std::vector<std::string> names;
  for (const auto& t : tethers["uniform"]) names.push_back(t.name);

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
  std::ofstream md(md_path);
  md << "# What the tether does to each agent of a pair\n\n"
     << "Run file `" << a.run << "` (commit " << f.read_string("git_commit") << "); command `divcoll tether " << a.run
     << " --pairs " << a.pairs << " --replicate " << a.replicate << "`, divcoll " << DIVCOLL_VERSION << " ("
     << git_commit() << ") on " << host() << ", one core of " << std::thread::hardware_concurrency() << ".\n\n"
     << "The first " << a.pairs << " deployed pairs of each deployment (uniform: clones; diverse: the deploy stage's "
     << "pairs), " << steps << " steps, the weak connector kind of the deployment (replicate " << a.replicate
     << ") beside the passive and follower references. Differences are against the free tether (stiffness 0: each "
     << "agent as it walks alone from the same start). The slower agent of a pair is the one that travels less under "
     << "the free tether; the impulse is the tether's horizontal push on it (the faster agent gets its negative). "
     << "Work is what the tether's springs did on both agents (positive: energy the actuated springs put in).\n\n";
  write_summary(md, rows, names);
  std::printf("tether: wrote %s and %s\n", md_path.c_str(), csv_path.c_str());
  return 0;
}

}  // namespace divcoll::cli
