#include "stages/needs.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"
#include "config/pipeline.hpp"
#include "io/h5.hpp"
#include "io/memory.hpp"
#include "io/run_read.hpp"
#include "morph/body.hpp"
#include "stages/driver.hpp"

namespace divcoll::stages {
namespace {

// stored values that the stages to run read, where no NaN or Inf may be (a finished stage's weights and bodies; a
// running stage's checkpointed optimizer state)
void check_finite(const config::RunConfig& cfg, const std::set<std::string>& present, const std::string& source,
                  bool continued) {
  io::h5::File f = io::h5::File::open(source);
  std::vector<std::string> finite;
  if (present.count("agents"))
    for (const char* d : {"params", "rest_pos", "rest_length", "amplitude"}) finite.push_back(std::string("agents/final/") + d);
  if (present.count("connectors"))
    for (const std::string& kind : cfg.connectors.kinds) finite.push_back("connectors/" + kind + "/params");
  if (continued && config::stage_enabled(cfg, "connectors") && !present.count("connectors"))
    for (const char* d : {"params", "adam_m", "adam_v"}) finite.push_back(std::string("connectors/state/") + d);
  for (const std::string& d : finite) {
    if (!f.has(d)) continue;
    const std::vector<double> v = f.read<double>(d);
    size_t bad = 0, first = 0;
    for (size_t i = v.size(); i-- > 0;)
      if (!std::isfinite(v[i])) ++bad, first = i;
    if (bad > 0)
      throw InputError(msg() << source << ": " << d << " holds " << bad << " non-finite value(s) (the first at flat index "
                             << first << ") where none may be; the stored stage is damaged: rerun it into a new "
                             << "file (--from, or a new run) instead of continuing this one");
  }
}

}  // namespace

void check_inputs(const config::RunConfig& cfg, bool agents_only, const std::string& existing, const std::string& from,
                  const std::string& base) {
  std::set<std::string> present;
  auto note_complete = [&](const std::string& file, const std::string& before) {
    io::h5::File f = io::h5::File::open(file);
    for (const std::string& s : config::stage_names()) {
      if (s == before) break;
      if (complete(f, s)) present.insert(s);
    }
  };
  if (!existing.empty()) note_complete(existing, "");
  if (!from.empty()) note_complete(base, from);
  const std::string source = !existing.empty() ? existing : base;
  if (!source.empty()) check_finite(cfg, present, source, !existing.empty());
  const std::string where = !existing.empty() ? existing : !from.empty() ? base : std::string();
  for (const config::StageInfo& s : config::kStageTable) {
    const std::string stage(s.name);
    const bool runs = agents_only ? stage == "agents" : config::stage_enabled(cfg, stage);
    if (!runs || present.count(stage)) continue;
    for (const std::string& need : io::split(std::string(s.reads))) {
      if (present.count(need) || (!agents_only && config::stage_enabled(cfg, need))) continue;
      throw InputError(msg() << "stage " << stage << " reads the results of stage " << need << ", but " << need
                             << " is neither in run.stages nor complete in "
                             << (where.empty() ? "a new run file" : where)
                             << ": add it to run.stages, or continue a run file that has it (--resume, or --from "
                             << stage << " --base OLD.h5)");
    }
  }
}

Tape largest_tape(const config::RunConfig& cfg, bool agents_only) {
  Rng rng = make_rng(cfg.run.seed, 0, 0);
  morph::Agent a = collective::random_agent(rng), b = collective::random_agent(rng);
  const sim::RunPhysics physics = config::run_physics(cfg);
  sim::RunOptions opt = physics.options();
  opt.grad = true;
  Tape tape;
  auto consider = [&](const sim::Scene& s, int steps, const std::string& key) {
    opt.steps = steps;
    const uint64_t n = episode_bytes(s, opt);
    if (n > tape.bytes)
      tape.bytes = n, tape.what = key + " = " + std::to_string(steps) + ", " + std::to_string(sim::substeps_needed(s)) +
                                  " substep(s) per step";
  };
  if (agents_only || config::stage_enabled(cfg, "agents") || config::stage_enabled(cfg, "graded"))
    consider(collective::agent_scene(a, "flat", physics.contact), cfg.agents.episode_steps, "agents.episode_steps");
  if (!agents_only && (config::stage_enabled(cfg, "connectors") || config::stage_enabled(cfg, "specialists") ||
                       config::stage_enabled(cfg, "graded"))) {
    a.anchors = collective::compute_anchors(a, physics);
    b.anchors = collective::compute_anchors(b, physics);
    const std::vector<double> w = morph::init_connector_params(rng, morph::kConnectorInitGains[2]);
    double k = cfg.connectors.weak_stiffness;
    for (const std::string& kind : cfg.connectors.kinds)
      if (config::stage_enabled(cfg, "connectors")) k = std::max(k, config::stiffness(cfg.connectors, kind));
    std::vector<std::string> envs = {"flat"};
    if (config::stage_enabled(cfg, "specialists")) envs = cfg.deploy.environments;
    for (const std::string& env : envs)
      consider(collective::pair_scene(a, b, w, {k, cfg.connectors.amplitude}, env, physics.contact),
               cfg.connectors.episode_steps, "connectors.episode_steps");
  }
  return tape;
}

}  // namespace divcoll::stages
