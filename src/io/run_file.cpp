// the run-file schema table, its lookup by path, the attributes it puts on new datasets, the check of a
// whole file against it, and mpi/README.md's tables made from it.
#include "io/run_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "common/check.hpp"
#include "common/version.hpp"
#include "config/config.hpp"
#include "sim/scene.hpp"

namespace divcoll::io::run_file {

namespace {

using Labels = Axis::Labels;

// the attributes every stage group gets from the run command (timing; `divcoll compare` ignores them)
const std::string kTiming =
    "wall_s,wall_s_last_session,busy_s_per_rank_last_session,master_serial_s_last_session,"
    "compute_cpu_s_per_rank_last_session,serve_cpu_s_per_rank_last_session";

std::vector<std::string> split(std::string_view s, char sep = ',') {
  std::vector<std::string> out;
  if (s.empty()) return out;
  size_t pos = 0;
  while (true) {
    const size_t next = s.find(sep, pos);
    out.emplace_back(s.substr(pos, next == std::string_view::npos ? std::string_view::npos : next - pos));
    if (next == std::string_view::npos) break;
    pos = next + 1;
  }
  return out;
}

std::string join(const std::vector<std::string>& v, const std::string& sep = ",") {
  std::string out;
  for (size_t k = 0; k < v.size(); ++k) out += (k ? sep : "") + v[k];
  return out;
}

std::vector<Axis> make_axes() {
  const auto fixed = [](std::string name, std::string labels, std::string doc) {
    const auto n = static_cast<hsize_t>(split(labels).size());
    return Axis{std::move(name), Labels::fixed, std::move(labels), n, std::move(doc)};
  };
  return {
      {"env", Labels::attribute, "environments", 0,
       "an environment of the enclosing stage's `environments` attribute (flat first; in /specialists the novel ones)"},
      {"novel_env", Labels::attribute, "novel_environments", 0, "a novel environment (every one but flat)"},
      {"type", Labels::attribute, "types", 0, "a deployment type `<kind>@uniform` or `<kind>@diverse`"},
      {"reference", Labels::attribute, "references", 0,
       "a reference connector deployed on uniform or diverse pairs, `<name>@uniform` or `<name>@diverse` (free, passive, "
       "follower: deploy.references)"},
      {"variant", Labels::attribute, "variants", 0, "a chain variant: uniform (clones) or diverse"},
      {"size", Labels::dataset, "sizes", 0, "a chain size N (`scaling.sizes`)"},
      {"agent", Labels::none, "", 0,
       "an agent of the population (in gen_NNN a candidate: gen_000 the P trained random agents, later P parents then P offspring)"},
      {"replicate", Labels::none, "", 0, "a connector replicate (`connectors.replicates`; `specialists.replicates` in /specialists)"},
      {"pair", Labels::none, "", 0, "a deployment pair (`deploy.pairs`): uniform = agent i with its clone, diverse = row i of `diverse_pairs`"},
      {"draw", Labels::none, "", 0, "a chain of one size and replicate (`scaling.draws`): uniform = clones of agent `draw`"},
      {"chain", Labels::none, "", 0, "a diverse chain: replicate · draws + draw"},
      {"position", Labels::none, "", 0, "an agent's place in a chain (binary tree in heap order)"},
      {"connector", Labels::none, "", 0,
       "a connector being trained, in training order: kind-major (specialists: environment-major), then replicate"},
      {"iteration", Labels::none, "", 0, "an optimizer step of connector training (the value is from before it)"},
      {"evaluation", Labels::none, "", 0, "an evaluation of an agent's gradient descent (epochs + 1)"},
      {"es_candidate", Labels::none, "", 0, "iteration · `connectors.es_popsize` + candidate of the cmaes optimizer"},
      {"sample", Labels::none, "", 0, "a sampled (step, connector spring) of an episode: ⌈`deploy.hidden_subsample` / pairs⌉"},
      {"state", Labels::none, "", 0, "a hidden state in the PaCMAP fit: training states first, then novel; NaN padded to 2 · `analysis.max_states`"},
      {"agent_weight", Labels::none, "", 0, "a weight of the agent's controller (54 → 32 → 32 → 21: 3509, W then b per layer)"},
      {"connector_weight", Labels::none, "", static_cast<hsize_t>(sim::connector_param_count()),
       "a weight of a connector's controller, W then b per layer: 11 → 32 → 32 → 1 (connectors.network = per_spring), "
       "or 55 → 32 → 32 → 5 (joint)", static_cast<hsize_t>(sim::connector_param_count(true))},
      {"mass", Labels::none, "", static_cast<hsize_t>(sim::kAgentMasses), "a point mass of an agent"},
      {"spring", Labels::none, "", static_cast<hsize_t>(sim::kAgentSprings), "a spring of an agent"},
      {"neuron", Labels::none, "", static_cast<hsize_t>(sim::kHidden), "a unit of the connector's second hidden layer"},
      {"input", Labels::none, "", static_cast<hsize_t>(sim::kConnectorInputs), "an input of the connector's network (SPEC §6.3)"},
      {"component", Labels::none, "", 2, "a coordinate of the 2-D PaCMAP embedding"},
      fixed("xy", "x,y", "a coordinate"),
      fixed("descriptor", "height,width,aspect,compact,cx,cy,sd_y,sym_v,sym_h", "an entry of the behaviour descriptor (SPEC §4.2)"),
      fixed("slot", "posterior,anterior", "an agent's place in a pair"),
      fixed("best", "score,iteration", "keep-best: the best validation travel (BL) and the iteration whose weights scored it"),
      fixed("anchor", "back_foot,front_foot,back_upper,front_upper", "an anchor mass of an agent (SPEC §6.1)"),
      fixed("role", "worse,better", "the agent of a pair that travelled less / more alone"),
      fixed("estimate", "mean,ci_low,ci_high", "the mean over replicates and its bootstrap 95% CI"),
      fixed("welch", "t,df,p", "Welch's t-test, uniform against diverse type"),
      fixed("count", "states_both,states_train_only,states_novel_only,cells_both,cells_train_only,cells_novel_only",
            "states in cells holding both / only training / only novel states, then those cells"),
      fixed("source", "training,novel", "where the hidden states were recorded"),
      fixed("cell_class", "both,train_only,novel_only", "a class of cells of the embedding"),
      fixed("table_column", "diverse_mean,uniform_mean,welch_p", "Table S1's columns"),
  };
}

// the rows, before the graded copies; the groups first in each part
std::vector<Entry> base_entries() {
  const auto G = [](std::string path, std::string attrs, std::string doc, bool graded = false) {
    return Entry{std::move(path), "group", "", "", std::move(doc), std::move(attrs), graded};
  };
  const auto D = [](std::string path, std::string dtype, std::string axes, std::string unit, std::string doc,
                    bool graded = false) {
    return Entry{std::move(path), std::move(dtype), std::move(axes), std::move(unit), std::move(doc), "", graded};
  };
  // a dataset written only under some settings (connectors.keep_best, optimizer = cmaes, deploy.references,
  // analysis.calibrated_cell_scale, ...)
  const auto O = [&D](std::string path, std::string dtype, std::string axes, std::string unit, std::string doc,
                      bool graded = false) {
    Entry e = D(std::move(path), std::move(dtype), std::move(axes), std::move(unit), std::move(doc), graded);
    e.optional = true;
    return e;
  };
  const std::string travel_ok = "; NaN unless status is 0";
  const std::string status_doc = "0 ok, 1 nan, 2 unstable";
  return {
      G("", "format,version,divcoll_version,git_commit,seed,ranks,config,start_time,end_time,hostname,resumed,"
            "kernels,cpu,build_target,derived_from,base_git_commit,base_start_time",
        "the run: format = divcoll-run, provenance (git_commit with -dirty if the build's tree was; kernels, cpu and "
        "build_target: the MLP's kernel path, the CPU and the build's instruction set of the last session, rank 0's; "
        "derived_from and base_*: the reused stages of a --from run) and config, the resolved TOML of every key"),
      // agents (SPEC §4)
      G("agents", "status,generations_done,population," + kTiming,
        "the agents stage: evolution and gradient descent; generations_done counts the complete gen_NNN", true),
      G("agents/{generation}", "",
        "gen_NNN: every candidate of generation NNN, one row each; final: the surviving population, read by the later stages",
        true),
      D("agents/{generation}/id", "int64", "agent", "index", "the agent's id, unique in its population", true),
      D("agents/{generation}/parent", "int64", "agent", "index", "its parent's id (−1 in generation 0)", true),
      D("agents/{generation}/cells", "int64", "agent", "bits", "body genotype: one bit per lattice cell (28)", true),
      D("agents/{generation}/springs", "int64", "agent", "bits", "spring genotype: one bit per spring (21)", true),
      D("agents/{generation}/rest_pos", "float64", "agent,mass,xy", "u", "rest positions of the masses", true),
      D("agents/{generation}/spring_i", "int32", "agent,spring", "index", "first mass of each spring", true),
      D("agents/{generation}/spring_j", "int32", "agent,spring", "index", "second mass of each spring", true),
      D("agents/{generation}/rest_length", "float64", "agent,spring", "u", "rest length of each spring", true),
      D("agents/{generation}/amplitude", "float64", "agent,spring", "1",
        "actuation amplitude of each spring, a fraction of its rest length (0 = passive)", true),
      D("agents/{generation}/params", "float64", "agent,agent_weight", "1", "the controller's weights", true),
      D("agents/{generation}/fitness", "float64", "agent", "BL", "travel on flat with the trained weights", true),
      D("agents/{generation}/travel_u", "float64", "agent", "u", "the same travel in u", true),
      D("agents/{generation}/status", "uint8", "agent", "code", "its training episode: " + status_doc, true),
      D("agents/{generation}/descriptor", "float64", "agent,descriptor", "1", "behaviour descriptor (SPEC §4.2)", true),
      D("agents/{generation}/uniqueness", "float64", "agent", "1",
        "mean distance to its k nearest neighbours in descriptor space, in the whole pool", true),
      D("agents/{generation}/survived", "uint8", "agent", "1", "1 if it survived selection", true),
      D("agents/{generation}/curve_u", "float64", "agent,evaluation", "u",
        "travel at each evaluation of this generation's training (NaN for parents)", true),
      // connectors (SPEC §6)
      G("connectors", "status,kinds,replicates,iterations_done," + kTiming,
        "the connectors stage: every kind and replicate trained by backpropagation through its pairs", true),
      D("connectors/anchors", "int32", "agent,anchor", "index",
        "each agent's anchor masses (SPEC §6.1), stored once with the population's connectors and read back", true),
      G("connectors/{kind}", "", "one connector kind: weak_uniform, weak_diverse, strong_uniform, strong_diverse", true),
      D("connectors/{kind}/params", "float64", "replicate,connector_weight", "1", "trained weights", true),
      D("connectors/{kind}/curve_u", "float64", "iteration,replicate", "u",
        "mean pair travel of the iteration's batch (its ok pairs)", true),
      D("connectors/{kind}/curve_bl", "float64", "iteration,replicate", "BL", "the same in body lengths", true),
      D("connectors/{kind}/nan_pairs", "float64", "iteration,replicate", "count",
        "pairs of the batch whose episode was not ok or whose gradient was not finite (left out of the mean and the "
        "step)", true),
      O("connectors/{kind}/val_bl", "float64", "iteration,replicate", "BL",
        "keep_best: mean validation travel of the weights before each step, then (row I) of the final weights", true),
      O("connectors/{kind}/best_iteration", "float64", "replicate", "index",
        "keep_best: the row of val_bl whose weights were kept", true),
      G("connectors/state", "", "the optimizer at the last checkpoint (resume)", true),
      D("connectors/state/params", "float64", "connector,connector_weight", "1", "weights", true),
      D("connectors/state/adam_m", "float64", "connector,connector_weight", "1", "Adam's first moment", true),
      D("connectors/state/adam_v", "float64", "connector,connector_weight", "1", "Adam's second moment", true),
      O("connectors/state/best_params", "float64", "connector,connector_weight", "1", "the validation-best weights (optimisation keys)", true),
      O("connectors/state/best", "float64", "connector,best", "1", "keep-best score and iteration (optimisation keys)", true),
      O("connectors/state/es_fitness", "float64", "connector,es_candidate", "u", "cmaes: −batch travel of every candidate so far (replayed on resume)", true),
      // deploy (SPEC §7.1–7.2)
      G("deploy", "status,environments,types,references,envs_done," + kTiming,
        "the deployment: every agent alone and the eight collective types in every environment, no learning"),
      D("deploy/diverse_pairs", "int32", "pair,slot", "index", "the agents (final rows) of each diverse pair"),
      G("deploy/agents", "", "every agent alone"),
      D("deploy/agents/travel_bl", "float64", "env,agent", "BL", "travel" + travel_ok),
      D("deploy/agents/travel_u", "float64", "env,agent", "u", "travel" + travel_ok),
      D("deploy/agents/status", "uint8", "env,agent", "code", status_doc),
      D("deploy/agents/travel_bl_early", "float64", "env,agent", "BL",
        "travel at step deploy.early_step of the same episodes (only when deploy.early_step > 0)" + travel_ok),
      G("deploy/collectives", "", "pairs joined by a trained connector"),
      D("deploy/collectives/travel_bl", "float64", "env,type,replicate,pair", "BL", "travel of the pair" + travel_ok),
      D("deploy/collectives/travel_u", "float64", "env,type,replicate,pair", "u", "travel of the pair" + travel_ok),
      D("deploy/collectives/status", "uint8", "env,type,replicate,pair", "code", status_doc),
      D("deploy/collectives/travel_bl_early", "float64", "env,type,replicate,pair", "BL",
        "travel at step deploy.early_step of the same episodes (only when deploy.early_step > 0)" + travel_ok),
      Entry{"deploy/references", "group", "", "",
            "pairs joined by a reference connector, no training (only when deploy.references; src/collective/references.hpp)",
            "", false, true},
      O("deploy/references/travel_bl", "float64", "env,reference,pair", "BL", "travel of the pair" + travel_ok),
      O("deploy/references/travel_u", "float64", "env,reference,pair", "u", "travel of the pair" + travel_ok),
      O("deploy/references/status", "uint8", "env,reference,pair", "code", status_doc),
      O("deploy/references/travel_bl_early", "float64", "env,reference,pair", "BL",
        "travel at step deploy.early_step of the same episodes (only when deploy.early_step > 0)" + travel_ok),
      G("deploy/hidden", "", "connector hidden states for the familiarity analysis (SPEC §8.2)"),
      G("deploy/hidden/{type}", "", "weak_uniform@uniform and weak_diverse@diverse (the weak connectors as trained)"),
      D("deploy/hidden/{type}/states", "float32", "env,replicate,pair,sample,neuron", "1",
        "the connector's second hidden layer at the sampled (step, spring); NaN if the episode was not ok"),
      D("deploy/hidden/{type}/index", "int32", "env,replicate,pair,sample", "index", "which: step · 5 + connector spring"),
      O("deploy/hidden/{type}/inputs", "float32", "env,replicate,pair,sample,input", "1",
        "the connector's network inputs at the same sampled (step, spring) (only when analysis.familiarity_on = "
        "inputs); NaN if the episode was not ok"),
      // specialists (SPEC §7.3)
      G("specialists", "status,environments,replicates,iterations_done,envs_done," + kTiming,
        "weak connectors trained on diverse pairs in each novel environment (environments = the novel ones)"),
      G("specialists/{env}", "", "the specialists of one novel environment"),
      D("specialists/{env}/params", "float64", "replicate,connector_weight", "1", "trained weights"),
      D("specialists/{env}/curve_u", "float64", "iteration,replicate", "u", "as connectors/{kind}/curve_u"),
      D("specialists/{env}/curve_bl", "float64", "iteration,replicate", "BL", "as connectors/{kind}/curve_bl"),
      D("specialists/{env}/nan_pairs", "float64", "iteration,replicate", "count", "as connectors/{kind}/nan_pairs"),
      O("specialists/{env}/val_bl", "float64", "iteration,replicate", "BL",
        "keep_best: mean validation travel of the weights before each step, then (row I) of the final weights"),
      O("specialists/{env}/best_iteration", "float64", "replicate", "index", "keep_best: the row of val_bl whose weights were kept"),
      G("specialists/state", "", "the optimizer at the last checkpoint (resume)"),
      D("specialists/state/params", "float64", "connector,connector_weight", "1", "weights"),
      D("specialists/state/adam_m", "float64", "connector,connector_weight", "1", "Adam's first moment"),
      D("specialists/state/adam_v", "float64", "connector,connector_weight", "1", "Adam's second moment"),
      O("specialists/state/best_params", "float64", "connector,connector_weight", "1", "the validation-best weights (optimisation keys)"),
      O("specialists/state/best", "float64", "connector,best", "1", "keep-best score and iteration (optimisation keys)"),
      O("specialists/state/es_fitness", "float64", "connector,es_candidate", "u", "cmaes: −batch travel of every candidate so far (replayed on resume)"),
      D("specialists/travel_bl", "float64", "env,replicate,pair", "BL",
        "each specialist in its environment on deploy's diverse pairs" + travel_ok),
      D("specialists/travel_u", "float64", "env,replicate,pair", "u", "the same in u"),
      D("specialists/status", "uint8", "env,replicate,pair", "code", status_doc),
      // scaling (SPEC §7.4)
      G("scaling", "status,environments,variants,envs_done," + kTiming,
        "chains of N agents: uniform = N clones with a weak uniform-trained connector, diverse = N distinct agents with a "
        "weak diverse-trained one"),
      D("scaling/sizes", "int64", "size", "count", "the chain sizes N"),
      G("scaling/n{N}", "", "the chains of size N"),
      D("scaling/n{N}/diverse_agents", "int32", "chain,position", "index", "the agents of each diverse chain"),
      D("scaling/travel_bl", "float64", "env,size,variant,replicate,draw", "BL", "travel of the chain" + travel_ok),
      D("scaling/travel_u", "float64", "env,size,variant,replicate,draw", "u", "the same in u"),
      D("scaling/status", "uint8", "env,size,variant,replicate,draw", "code", status_doc),
      // graded diversity (SPEC §7.5)
      G("graded", "status,environments,populations,shape_cells,shape_springs," + kTiming,
        "populations of one body shape (shape_cells, the main population's commonest body; shape_springs its commonest "
        "spring genotype)"),
      G("graded/{population}", "status,diversity_sources,envs_done",
        "same_shape (evolved springs) or same_shape_springs (controllers only); holds agents/, connectors/weak_diverse/ "
        "and connectors/state/ as the main run does"),
      D("graded/{population}/diverse_pairs", "int32", "pair,slot", "index", "the agents of each diverse pair"),
      G("graded/{population}/deploy", "", "the population deployed"),
      G("graded/{population}/deploy/agents", "", "every agent alone"),
      D("graded/{population}/deploy/agents/travel_bl", "float64", "env,agent", "BL", "travel" + travel_ok),
      D("graded/{population}/deploy/agents/travel_u", "float64", "env,agent", "u", "travel" + travel_ok),
      D("graded/{population}/deploy/agents/status", "uint8", "env,agent", "code", status_doc),
      G("graded/{population}/deploy/pairs", "", "diverse pairs with the population's weak diverse-trained connector"),
      D("graded/{population}/deploy/pairs/travel_bl", "float64", "env,replicate,pair", "BL", "travel" + travel_ok),
      D("graded/{population}/deploy/pairs/travel_u", "float64", "env,replicate,pair", "u", "travel" + travel_ok),
      D("graded/{population}/deploy/pairs/status", "uint8", "env,replicate,pair", "code", status_doc),
      // analysis (SPEC §8)
      G("analysis", "status,types,environments,novel_environments,dtw_envs_done,familiarity_envs_done," + kTiming,
        "DTW adversity and PaCMAP familiarity of weak_uniform@uniform and weak_diverse@diverse, Fig. 3 and Table S1"),
      G("analysis/adversity", "deploy_mismatches",
        "behaviour change of each agent when tethered (SPEC §8.1); deploy_mismatches: re-simulated episodes whose travel "
        "differs from deploy's (0)"),
      G("analysis/adversity/{type}", "", "one deployment type"),
      D("analysis/adversity/{type}/dtw", "float64", "env,replicate,pair,slot", "u",
        "DTW per step between the agent's tethered and independent behaviour; NaN unless the pair and both agents alone were ok"),
      D("analysis/adversity/{type}/worse_slot", "uint8", "env,replicate,pair", "index",
        "the slot of the agent that travelled less alone (ties: posterior)"),
      D("analysis/adversity/replicate_means", "float64", "type,role,replicate", "u", "mean DTW per replicate"),
      D("analysis/adversity/summary", "float64", "type,role,estimate", "u", "over replicates"),
      D("analysis/adversity/welch", "float64", "role,welch", "1", "uniform against diverse type"),
      G("analysis/familiarity", "", "hidden states of flat and a novel environment in one PaCMAP fit (SPEC §8.2)"),
      G("analysis/familiarity/{type}", "", "one deployment type"),
      D("analysis/familiarity/{type}/counts", "int64", "novel_env,replicate,count", "count",
        "states and cells by what the cells hold"),
      O("analysis/familiarity/{type}/counts_calibrated", "int64", "novel_env,replicate,count", "count",
        "counts as above at analysis.calibrated_cell_scale (when > 0)"),
      D("analysis/familiarity/{type}/n_states", "int64", "novel_env,replicate,source", "count", "states in the fit"),
      D("analysis/familiarity/{type}/embedding", "float32", "novel_env,replicate,state,component", "1",
        "the fit's 2-D coordinates"),
      D("analysis/familiarity/table", "float64", "novel_env,cell_class,table_column", "count (p: 1)",
        "Table S1: per class of states, the mean over replicates of each type and Welch's p (NaN when a type is missing)"),
  };
}

// "graded/{population}/" + the rows marked graded
std::vector<Entry> with_graded_copies(std::vector<Entry> rows) {
  const size_t n = rows.size();
  for (size_t k = 0; k < n; ++k) {
    if (!rows[k].graded) continue;
    Entry e = rows[k];
    e.path = "graded/{population}/" + e.path;
    e.graded = false;
    rows.push_back(std::move(e));
  }
  return rows;
}

// does `segment` match pattern segment `pat` ("gen_{NNN}" matches "gen_003")? returns its literal count
// (2 for a literal match, 1 for a placeholder) or 0 for no match
int match_segment(std::string_view pat, std::string_view segment) {
  const size_t open = pat.find('{');
  if (open == std::string_view::npos) return pat == segment ? 2 : 0;
  const size_t close = pat.find('}', open);
  const std::string_view prefix = pat.substr(0, open), suffix = pat.substr(close + 1);
  if (segment.size() <= prefix.size() + suffix.size()) return 0;
  if (segment.substr(0, prefix.size()) != prefix) return 0;
  if (segment.substr(segment.size() - suffix.size()) != suffix) return 0;
  return 1;
}

// the score of `path` against `pattern` (higher = more literal), 0 for no match
int match(std::string_view pattern, std::string_view path) {
  const auto p = split(pattern, '/'), s = split(path, '/');
  if (p.size() != s.size()) return 0;
  int score = 1;
  for (size_t k = 0; k < p.size(); ++k) {
    const int m = match_segment(p[k], s[k]);
    if (m == 0) return 0;
    score = score * 3 + m;
  }
  return score;
}

std::string strip_slash(std::string_view p) {
  while (!p.empty() && p.front() == '/') p.remove_prefix(1);
  return std::string(p);
}

std::string parent_of(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "" : path.substr(0, slash);
}

// does the dataset at `path` carry labels along `axis`? (not a plain index axis, and not the dataset that
// holds the labels itself: scaling/sizes)
bool labelled(const Axis& axis, const std::string& path) {
  if (axis.labels == Labels::none) return false;
  return !(axis.labels == Labels::dataset && path.substr(path.rfind('/') + 1) == axis.source);
}

// the labels of `axis` for the dataset at `path`: fixed, or looked up on the enclosing groups; "" if none found
std::string labels_for(const h5::Node& root, const Axis& axis, const std::string& path) {
  if (axis.labels == Labels::fixed) return axis.source;
  if (axis.labels == Labels::none) return "";
  for (std::string g = parent_of(path);; g = parent_of(g)) {
    if (g.empty() || root.has(g)) {
      std::optional<h5::Node> sub;
      if (!g.empty()) sub.emplace(root.group(g));
      const h5::Node& node = g.empty() ? root : *sub;
      if (axis.labels == Labels::attribute && node.has_attribute(axis.source)) return node.read_string(axis.source);
      if (axis.labels == Labels::dataset && node.has(axis.source)) {
        std::vector<std::string> v;
        for (int64_t x : node.read<int64_t>(axis.source)) v.push_back(std::to_string(x));
        return join(v);
      }
    }
    if (g.empty()) return "";
  }
}

// the disagreements of dataset `path` (element type name `dtype`, dims `dims`) with its row `e`
std::vector<std::string> disagreements(const h5::Node& root, const Entry& e, const std::string& path,
                                       const std::string& dtype, const h5::Dims& dims) {
  std::vector<std::string> out;
  if (e.is_group()) return {path + ": a dataset where the schema has a group (" + e.path + ")"};
  if (dtype != e.dtype) out.push_back(path + ": " + dtype + " elements, the schema says " + e.dtype);
  const auto names = e.axis_names();
  if (names.size() != dims.size()) {
    out.push_back(path + ": dims " + h5::dims_string(dims) + ", the schema's axes are " + e.axes);
    return out;
  }
  for (size_t k = 0; k < names.size(); ++k) {
    const Axis* a = find_axis(names[k]);
    if (!a) {
      out.push_back(path + ": axis " + names[k] + " is not in the axes table");
      continue;
    }
    if (!a->fits(dims[k]))
      out.push_back(path + ": axis " + a->name + " has length " + std::to_string(dims[k]) + ", always " + a->lengths());
    if (labelled(*a, path)) {
      const auto labels = split(labels_for(root, *a, path));
      if (labels.size() != dims[k])
        out.push_back(path + ": axis " + a->name + " has length " + std::to_string(dims[k]) + " but " +
                      std::to_string(labels.size()) + " labels (" + a->source + ")");
    }
  }
  return out;
}

// names of the attributes of an object
std::vector<std::string> attribute_names(hid_t obj) {
  std::vector<std::string> names;
  H5Aiterate2(
      obj, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5A_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

// a variable-length string attribute of an object; false if missing or of another type
bool string_attribute(hid_t obj, const std::string& attr, std::string* out) {
  if (H5Aexists(obj, attr.c_str()) <= 0) return false;
  h5::Handle a(H5Aopen(obj, attr.c_str(), H5P_DEFAULT), H5Aclose);
  h5::Handle t(H5Aget_type(a.id()), H5Tclose);
  if (!t.valid() || H5Tis_variable_str(t.id()) <= 0) return false;
  h5::Handle mt(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mt.id(), H5T_VARIABLE);
  H5Tset_cset(mt.id(), H5Tget_cset(t.id()));
  char* s = nullptr;
  if (H5Aread(a.id(), mt.id(), &s) < 0) return false;
  *out = s ? s : "";
  H5free_memory(s);
  return true;
}

// float64 / float32 / int64 / int32 / uint8 ... of a dataset
std::string dtype_name(hid_t dataset) {
  h5::Handle type(H5Dget_type(dataset), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.id());
  const size_t bits = 8 * H5Tget_size(type.id());
  if (cls == H5T_FLOAT) return "float" + std::to_string(bits);
  if (cls == H5T_INTEGER) return (H5Tget_sign(type.id()) == H5T_SGN_2 ? "int" : "uint") + std::to_string(bits);
  return "other";
}

}  // namespace

std::string Axis::lengths() const {
  return std::to_string(length) + (alt_length > 0 ? " or " + std::to_string(alt_length) : std::string());
}

std::vector<std::string> Entry::axis_names() const { return split(axes); }

const std::vector<Axis>& axes() {
  static const std::vector<Axis> table = make_axes();
  return table;
}

const std::vector<Entry>& entries() {
  static const std::vector<Entry> table = with_graded_copies(base_entries());
  return table;
}

const Axis* find_axis(std::string_view name) {
  for (const Axis& a : axes())
    if (a.name == name) return &a;
  return nullptr;
}

const Entry* find(std::string_view path) {
  const std::string p = strip_slash(path);
  const Entry* best = nullptr;
  int best_score = 0;
  for (const Entry& e : entries()) {
    const int s = p.empty() ? (e.path.empty() ? 1 : 0) : match(e.path, p);
    if (s > best_score) best = &e, best_score = s;
  }
  return best;
}

const Entry& dataset(std::string_view path) {
  const Entry* e = find(path);
  if (!e || e->is_group())
    throw std::logic_error("run file: no schema row for dataset " + std::string(path) +
                           " (add one to src/io/run_file.cpp)");
  return *e;
}

h5::Dims shape(std::string_view path, const std::map<std::string, hsize_t>& lengths) {
  const Entry& e = dataset(path);
  h5::Dims d;
  for (const std::string& name : e.axis_names()) {
    const Axis* a = find_axis(name);
    const auto it = lengths.find(name);
    if (it != lengths.end()) {
      d.push_back(it->second);
    } else if (a && a->length > 0) {
      d.push_back(a->length);
    } else {
      throw std::logic_error("run file: " + std::string(path) + " needs the length of axis " + name);
    }
  }
  return d;
}

Layout layout(const h5::Node& root, const std::string& path, std::string_view expected_axes) {
  Layout out;
  out.dims = root.dims(path);
  std::string axes;
  {
    h5::Handle d(H5Dopen2(root.id(), path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!d.valid() || !string_attribute(d.id(), "axes", &axes)) {
      const Entry* e = find(path);
      axes = e && !e->is_group() ? e->axes : "";
    }
  }
  out.axes = split(axes);
  const std::vector<std::string> want = split(expected_axes);
  auto fail = [&](const std::string& expected) {
    throw InputError(root.where(path) + " has the shape " + h5::dims_string(out.dims) + " (" + axes + "), expected " +
                     expected);
  };
  if (out.axes != want || out.dims.size() != want.size()) fail("the axes (" + std::string(expected_axes) + ")");
  for (size_t k = 0; k < want.size(); ++k) {
    const Axis* a = find_axis(want[k]);
    if (a && !a->fits(out.dims[k])) fail(want[k] + " = " + a->lengths() + " (axis " + std::to_string(k) + ")");
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> attributes(const h5::Node& root, const std::string& path,
                                                            const std::string& dtype, const h5::Dims& dims) {
  if (!root.has_attribute("format") || root.read_string("format") != kFormat) return {};
  const Entry& e = dataset(path);
  const auto problems = disagreements(root, e, path, dtype, dims);
  if (!problems.empty()) throw std::logic_error("run file: " + problems.front() + " (src/io/run_file.cpp)");
  std::vector<std::pair<std::string, std::string>> out = {{"axes", e.axes}, {"unit", e.unit}, {"doc", e.doc}};
  for (const std::string& name : e.axis_names()) {
    const Axis* a = find_axis(name);
    if (labelled(*a, path)) out.emplace_back("labels_" + name, labels_for(root, *a, path));
  }
  return out;
}

std::vector<std::string> check(const h5::File& f, bool every_row) {
  struct Visit {
    const h5::File* file;
    std::vector<std::string> out;
    std::vector<const Entry*> seen;
    // attributes of `obj` that row `e` does not list
    void unlisted(hid_t obj, const Entry& e, const std::string& where) {
      const auto listed = split(e.attributes);
      for (const std::string& a : attribute_names(obj))
        if (std::find(listed.begin(), listed.end(), a) == listed.end())
          out.push_back(where + ": attribute " + a + " is not in the schema's row " + (e.path.empty() ? "/" : e.path));
    }
  } v{&f, {}, {}};
  v.seen.push_back(find(""));
  v.unlisted(f.id(), *find(""), "/");
  auto visit = [](hid_t obj, const char* name, const H5O_info_t* info, void* data) -> herr_t {
    Visit& v = *static_cast<Visit*>(data);
    const std::string path = name;
    if (path == ".") return 0;
    const Entry* e = find(path);
    if (!e) {
      v.out.push_back(path + ": no row in the schema (src/io/run_file.cpp)");
      return 0;
    }
    v.seen.push_back(e);
    if (info->type == H5O_TYPE_GROUP) {
      if (!e->is_group()) {
        v.out.push_back(path + ": a group where the schema has a dataset (" + e->path + ")");
        return 0;
      }
      h5::Handle g(H5Gopen2(obj, name, H5P_DEFAULT), H5Gclose);
      v.unlisted(g.id(), *e, path);
      return 0;
    }
    if (info->type != H5O_TYPE_DATASET) return 0;
    h5::Handle d(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose);
    for (auto& p : disagreements(*v.file, *e, path, dtype_name(d.id()), v.file->dims(path))) v.out.push_back(std::move(p));
    // the attributes the writer attaches
    std::vector<std::pair<std::string, std::string>> expected = {{"axes", e->axes}, {"unit", e->unit}, {"doc", e->doc}};
    for (const std::string& axis : e->axis_names()) {
      const Axis* a = find_axis(axis);
      if (a && labelled(*a, path)) expected.emplace_back("labels_" + axis, labels_for(*v.file, *a, path));
    }
    for (const auto& [k, want] : expected) {
      std::string got;
      if (!string_attribute(d.id(), k, &got))
        v.out.push_back(path + ": attribute " + k + " missing (or not a string)");
      else if (got != want)
        v.out.push_back(path + ": attribute " + k + " = \"" + got + "\", the schema says \"" + want + "\"");
    }
    return 0;
  };
  if (H5Ovisit(f.id(), H5_INDEX_NAME, H5_ITER_INC, visit, &v) < 0) v.out.push_back(f.file() + ": cannot visit every object");
  if (every_row)
    for (const Entry& e : entries())
      if (!e.optional && std::find(v.seen.begin(), v.seen.end(), &e) == v.seen.end())
        v.out.push_back(e.path + ": a schema row with nothing in the file");
  return v.out;
}

std::string markdown() {
  std::string out =
      "| axis | length | labels | meaning |\n"
      "|---|---|---|---|\n";
  for (const Axis& a : axes()) {
    std::string labels;
    if (a.labels == Labels::fixed) labels = "`" + join(split(a.source), "`, `") + "`";
    if (a.labels == Labels::attribute) labels = "attribute `" + a.source + "` of the enclosing group";
    if (a.labels == Labels::dataset) labels = "dataset `" + a.source + "` of the enclosing group";
    out += "| `" + a.name + "` | " + (a.length > 0 ? a.lengths() : "run") + " | " + labels + " | " +
           a.doc + " |\n";
  }
  out +=
      "\n"
      "| path | type | axes | unit | meaning |\n"
      "|---|---|---|---|---|\n";
  for (const Entry& e : base_entries()) {
    const std::string path = (e.graded ? "[graded/{population}/]" : "") + (e.path.empty() ? "/" : e.path);
    if (e.is_group()) {
      const auto attrs = split(e.attributes);
      out += "| `" + path + "` | group | | | " + e.doc +
             (attrs.empty() ? "" : "; attributes `" + join(attrs, "`, `") + "`") + " |\n";
    } else {
      out += "| `" + path + "` | " + e.dtype + " | " + join(e.axis_names(), " × ") + " | " + e.unit + " | " +
             e.doc + " |\n";
    }
  }
  return out;
}

void derive(const h5::Node& root, const std::string& from, const std::string& config_toml,
            const std::string& start_time, const std::string& derived_from) {
  bool later = false;
  for (const std::string& s : config::stage_names()) {
    later = later || s == from;
    if (later) root.remove(s);
  }
  // the earlier stages' provenance is kept under base_*; the new stages' is this binary's
  if (root.has_attribute("git_commit")) root.write_string("base_git_commit", root.read_string("git_commit"));
  if (root.has_attribute("start_time")) root.write_string("base_start_time", root.read_string("start_time"));
  for (const char* a : {"end_time", "resumed", "config", "git_commit", "start_time", "divcoll_version"})
    root.remove_attribute(a);
  root.write_string("config", config_toml);
  root.write_string("git_commit", git_commit());
  root.write_string("divcoll_version", DIVCOLL_VERSION);
  root.write_string("start_time", start_time);
  root.write_string("derived_from", derived_from);
}

}  // namespace divcoll::io::run_file
