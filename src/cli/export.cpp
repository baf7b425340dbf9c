// divcoll export: the scene file of exactly one episode behind a number of a run file (SPEC §9), so it
// can be simulated, inspected and rendered. The episode is named by what the run file stores: an agent
// alone, a deployed pair (collective type, replicate, pair), a specialist's pair, or a scaling chain.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cli/commands.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/builders.hpp"
#include "common/check.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "io/h5.hpp"
#include "io/run_read.hpp"
#include "io/scene_file.hpp"

namespace divcoll::cli {
namespace {

using io::split;

int index_of(const std::vector<std::string>& v, const std::string& x, const std::string& what) {
  for (size_t i = 0; i < v.size(); ++i)
    if (v[i] == x) return static_cast<int>(i);
  std::string all;
  for (const auto& y : v) all += (all.empty() ? "" : ", ") + y;
  throw InputError(msg() << what << " '" << x << "' is not in the run file (it has: " << all << ")");
}

void check_range(const char* flag, int v, int n) {
  DIVCOLL_THROW_UNLESS(v >= 0 && v < n, flag << " = " << v << " is out of range [0, " << n - 1 << "]");
}

// the flat index of `idx` in a row-major array of `dims`
size_t flat_index(const std::vector<int>& idx, const io::h5::Dims& dims) {
  size_t f = 0;
  for (size_t k = 0; k < dims.size(); ++k) f = f * dims[k] + idx[k];
  return f;
}

}  // namespace

int export_scene(const ExportArgs& a) {
  check_output_path(a.out, a.force, {a.run});
  io::h5::quiet_errors();
  const io::h5::File f = io::h5::File::open(a.run);
  DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run",
                       a.run << " is not a divcoll run file");
  const config::RunConfig cfg = config::parse_config(f.read_string("config"), a.run + " (stored config)");
  // the episode's scene under the run's contact law (written into the scene file)
  const sim::ContactLaw law = config::run_physics(cfg).contact;
  std::vector<morph::Agent> agents;
  for (const auto& x : io::read_final_population(f)) agents.push_back(x.agent);
  // pairs and chains need the anchors the connectors stage stored (the ones every stage used)
  auto with_anchors = [&] {
    const std::string at = io::anchors_path("agents");
    DIVCOLL_THROW_UNLESS(f.has(at), a.run << " has no " << at << ": run the connectors stage first");
    io::read_anchors(f, at, agents);
  };
  const int pop = static_cast<int>(agents.size());

  sim::Scene s;
  std::string stage, what;
  std::vector<int> idx;  // the episode's index in <stage>/travel_u
  int steps = 0;
  if (a.what == "alone" || a.what == "pair") {
    DIVCOLL_THROW_UNLESS(f.has("deploy/agents/travel_u"), a.run << " has no deployment results");
    const auto envs = split(f.group("deploy").read_string("environments"));
    const int e = index_of(envs, a.env, "environment");
    steps = cfg.deploy.episode_steps;
    if (a.what == "alone") {
      check_range("--agent", a.agent, pop);
      s = collective::agent_scene(agents[a.agent], a.env, law, {},
                                  collective::alone_feature_offset(cfg.deploy, agents[a.agent]));
      idx = {e, a.agent};
      what = "agent " + std::to_string(a.agent) + " alone";
    } else {
      const auto types = split(f.group("deploy").read_string("types"));
      const int t = index_of(types, a.type, "collective type");
      const std::string kind = a.type.substr(0, a.type.find('@'));
      const bool diverse = a.type.substr(a.type.find('@') + 1) == "diverse";
      check_range("--pair", a.pair, cfg.deploy.pairs);
      const std::vector<int32_t> dp = f.read<int32_t>("deploy/diverse_pairs");
      const auto up = collective::deploy_uniform_pairs(cfg.deploy, cfg.connectors)[a.pair];
      const int p = diverse ? dp[2 * a.pair] : up.first, q = diverse ? dp[2 * a.pair + 1] : up.second;
      with_anchors();
      const collective::Tether k = collective::tether(cfg.connectors, kind);
      s = collective::pair_scene(agents[p], agents[q], io::read_weights_row(f, "connectors/" + kind, a.replicate), k,
                                 a.env, law);
      idx = {e, t, a.replicate, a.pair};
      what = a.type + " replicate " + std::to_string(a.replicate) + ", pair " + std::to_string(a.pair) + " (agents " +
             std::to_string(p) + " behind " + std::to_string(q) + ")";
    }
    stage = a.what == "alone" ? "deploy/agents" : "deploy/collectives";
  } else if (a.what == "specialist") {
    DIVCOLL_THROW_UNLESS(f.has("specialists/travel_u"), a.run << " has no specialists results");
    const auto envs = split(f.group("specialists").read_string("environments"));
    const int e = index_of(envs, a.env, "novel environment");
    check_range("--pair", a.pair, cfg.deploy.pairs);
    const std::vector<int32_t> dp = f.read<int32_t>("deploy/diverse_pairs");
    const int p = dp[2 * a.pair], q = dp[2 * a.pair + 1];
    with_anchors();
    s = collective::pair_scene(agents[p], agents[q], io::read_weights_row(f, "specialists/" + a.env, a.replicate),
                               collective::tether(cfg.connectors, "weak_diverse"), a.env, law);
    idx = {e, a.replicate, a.pair};
    steps = cfg.deploy.episode_steps;
    stage = "specialists";
    what = "the " + a.env + " specialist " + std::to_string(a.replicate) + ", pair " + std::to_string(a.pair);
  } else if (a.what == "chain") {
    DIVCOLL_THROW_UNLESS(f.has("scaling/travel_u"), a.run << " has no scaling results");
    const auto envs = split(f.group("scaling").read_string("environments"));
    const int e = index_of(envs, a.env, "environment");
    const std::vector<int64_t> sizes = f.read<int64_t>("scaling/sizes");
    int si = -1;
    for (size_t k = 0; k < sizes.size(); ++k)
      if (sizes[k] == a.size) si = static_cast<int>(k);
    DIVCOLL_THROW_UNLESS(si >= 0, "--size " << a.size << " is not a chain size of the run file");
    DIVCOLL_THROW_UNLESS(a.variant == "uniform" || a.variant == "diverse", "--variant must be uniform or diverse");
    const int v = a.variant == "diverse";
    check_range("--replicate", a.replicate, cfg.connectors.replicates);
    check_range("--draw", a.draw, cfg.scaling.draws);
    std::vector<int32_t> members(a.size, a.draw);
    if (v) {
      const std::vector<int32_t> all = f.read<int32_t>("scaling/n" + std::to_string(a.size) + "/diverse_agents");
      const size_t row = static_cast<size_t>(a.replicate) * cfg.scaling.draws + a.draw;
      members.assign(all.begin() + row * a.size, all.begin() + (row + 1) * a.size);
    }
    with_anchors();
    std::vector<const morph::Agent*> ptr;
    for (int32_t m : members) ptr.push_back(&agents[m]);
    s = collective::chain_scene(ptr, io::read_weights_row(f, v ? "connectors/weak_diverse" : "connectors/weak_uniform", a.replicate),
                                collective::tether(cfg.connectors, v ? "weak_diverse" : "weak_uniform"), a.env, law);
    idx = {e, si, v, a.replicate, a.draw};
    steps = cfg.scaling.episode_steps;
    stage = "scaling";
    what = "a " + a.variant + " chain of " + std::to_string(a.size) + ", replicate " + std::to_string(a.replicate) +
           ", draw " + std::to_string(a.draw);
  } else {
    throw InputError(msg() << "--what must be alone, pair, specialist or chain (got '" << a.what << "')");
  }
  io::h5::Dims dims;
  const std::vector<double> tu = f.read<double>(stage + "/travel_u", &dims);
  const std::vector<double> tb = f.read<double>(stage + "/travel_bl");
  const std::vector<uint8_t> st = f.read<uint8_t>(stage + "/status");
  DIVCOLL_THROW_UNLESS(dims.size() == idx.size(), stage << "/travel_u has an unexpected shape " << io::h5::dims_string(dims));
  const size_t q = flat_index(idx, dims);
  io::write_scene(a.out, s, a.force);
  static const char* status_name[] = {"ok", "nan", "unstable"};
  std::printf("%s: %s in %s; the run file records travel %.17g u (%.6g BL), status %s, over %d steps.\n"
              "Reproduce it: divcoll simulate --scene %s --steps %d --out TRAJ.h5\n",
              a.out.c_str(), what.c_str(), a.env.c_str(), tu[q], tb[q], st[q] < 3 ? status_name[st[q]] : "?", steps,
              a.out.c_str(), steps);
  return 0;
}

}  // namespace divcoll::cli
