// the run configuration: one schema table (schema() below) drives parsing, checking, the resolved TOML
// echo, the flat key/value list and configs/README.md's key table
#include "config/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <variant>

#include "common/check.hpp"
#include "config/environments.hpp"
#include "config/pipeline.hpp"
#include "config/toml_doc.hpp"
#include "config/toml_parse.hpp"

namespace divcoll::config {
namespace {

// ---- the schema --------------------------------------------------------------------------------

enum class Type { Int, Double, Bool, String, Choice, StringList, IntList };

using Ref = std::variant<int*, std::uint64_t*, double*, bool*, std::string*, std::vector<std::string>*,
                         std::vector<int>*>;

struct Key {
  std::string section, name;
  Type type;
  std::string def;                   // default, as a TOML value
  std::string range;                 // numbers and list-of-int elements: "[lo, hi]", "(lo, hi]", ...
  std::vector<std::string> choices;  // Choice and StringList: the allowed values
  std::string unit;
  std::string doc;
  Ref (*field)(RunConfig&);
  // the range, parsed from `range`
  double lo = 0, hi = 0;
  bool lo_open = false, hi_open = false;
  // StringList: the allowed names said in words where listing them would change with a file (deploy.environments);
  // empty: "any of" the choices
  std::string choices_text = {};

  std::string full() const { return section + "." + name; }
};

#define DIVCOLL_FIELD(path) [](RunConfig& c) -> Ref { return &c.path; }

// a numeric key (Int, Double, IntList) with its range text
Key num(const char* sec, const char* name, Type t, const char* def, const char* range, const char* unit,
        const char* doc, Ref (*f)(RunConfig&)) {
  Key k{sec, name, t, def, range, {}, unit, doc, f};
  const std::string r = range;
  const size_t comma = r.find(',');
  DIVCOLL_DEMAND(r.size() >= 5 && comma != std::string::npos);
  DIVCOLL_DEMAND((r.front() == '[' || r.front() == '(') && (r.back() == ']' || r.back() == ')'));
  k.lo_open = r.front() == '(';
  k.hi_open = r.back() == ')';
  k.lo = std::strtod(r.substr(1, comma - 1).c_str(), nullptr);
  k.hi = std::strtod(r.substr(comma + 1, r.size() - comma - 2).c_str(), nullptr);
  return k;
}

// a key whose value comes from a list (Choice, StringList)
Key pick(const char* sec, const char* name, Type t, std::string def, std::vector<std::string> choices,
         const char* doc, Ref (*f)(RunConfig&)) {
  return Key{sec, name, t, std::move(def), "", std::move(choices), "", doc, f};
}

// deploy.environments: its names are the tables of configs/environments.toml (the allowed text says so
// rather than listing them, so that adding an environment changes no document)
Key envs_key(std::string def, std::vector<std::string> choices, const char* doc) {
  Key k = pick("deploy", "environments", Type::StringList, std::move(def), std::move(choices), doc,
               DIVCOLL_FIELD(deploy.environments));
  k.choices_text = "names of tables of configs/environments.toml (`divcoll envs`)";
  return k;
}

// the paper's environments (SPEC §3), flat first: deploy.environments' default
const std::vector<std::string> kPaperEnvironments = {"flat", "decline", "gap", "ice", "incline", "low_gravity",
                                                     "obstacle", "sand", "step_down", "step_up", "sticky",
                                                     "treadmill", "wind"};

Key flag(const char* sec, const char* name, const char* def, const char* doc, Ref (*f)(RunConfig&)) {
  return Key{sec, name, Type::Bool, def, "", {}, "", doc, f};
}

Key text(const char* sec, const char* name, const char* def, const char* doc, Ref (*f)(RunConfig&)) {
  return Key{sec, name, Type::String, def, "", {}, "", doc, f};
}

std::string quoted(const std::string& s);

// a TOML array of strings
std::string string_list(const std::vector<std::string>& v) {
  std::string out = "[";
  for (size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + quoted(v[i]);
  return out + "]";
}

// the stage and connector-kind names come from their tables (config/pipeline.hpp)
const std::vector<std::string> kStages = [] {
  std::vector<std::string> v;
  for (const StageInfo& s : kStageTable) v.emplace_back(s.name);
  return v;
}();
const std::vector<std::string> kKinds = connector_kind_names();

// every key of the run configuration, in file order; defaults are SPEC §4.4, §6.4, §7
const std::vector<Key>& schema() {
  using T = Type;
  static const std::vector<Key> keys = [] {
    const std::vector<std::string> envs = environment_names();
    std::vector<Key> k = {
        // [run]
        num("run", "seed", T::Int, "1", "[0, inf)", "",
            "run seed: every random draw is seeded by (seed, stage, item)", DIVCOLL_FIELD(run.seed)),
        text("run", "name", "\"divcoll\"", "run name, used in output file names (a plain file name: no '/', not '..')",
             DIVCOLL_FIELD(run.name)),
        pick("run", "stages", T::StringList, string_list(kStages), kStages,
             "stages to run; they always run in the order of the default list", DIVCOLL_FIELD(run.stages)),
        num("run", "progress_every_s", T::Double, "10.0", "[0, 86400]", "s",
            "time between progress lines (0 = none)", DIVCOLL_FIELD(run.progress_every_s)),
        num("run", "stop_grace_s", T::Double, "120.0", "[0, 86400]", "s",
            "after SIGTERM, SIGINT or SIGUSR1 the run stops right after its next checkpoint (exit 75), or after "
            "this many seconds without one (exit 128 + signal; the last checkpoint is kept)",
            DIVCOLL_FIELD(run.stop_grace_s)),
        num("run", "memory_limit_gb", T::Double, "0.0", "[0, 1e6]", "GB",
            "memory the simulators' tapes of all ranks on one node may take together; a run whose episodes "
            "need more is refused before any work (0 = 80% of MemAvailable)",
            DIVCOLL_FIELD(run.memory_limit_gb)),
        pick("run", "precision", T::Choice, "\"double\"", {"double", "float_networks"},
             "the simulator's arithmetic: double everywhere (SPEC §10, the spec's step), or float_networks: the "
             "controllers' networks (inputs, weights, activations, their gradients) in float and the physics in "
             "double, about 1.3-1.5x faster per episode (jobs/BENCHMARKS.md, the float path) but not bit-comparable with double",
             DIVCOLL_FIELD(run.precision)),
        pick("run", "contact", T::Choice, "\"coulomb\"", {"coulomb", "no_slip"},
             "the contact law of every environment (SPEC §2.4, src/MODEL.md \"Contact laws\"): coulomb is the spec's "
             "(Coulomb friction mu, retention kappa_t, time of impact); no_slip is DiffTaichi's mass_spring.py "
             "advance_toi, where a mass that hits the ground takes the ground's velocity (the belt's on a "
             "treadmill) plus no_slip_keep of its tangential velocity (environments.toml: 0 but ice, 1/3), with "
             "the same contact detection and time of impact; friction and tangent_keep are then unused",
             DIVCOLL_FIELD(run.contact)),
        // [agents]
        num("agents", "population", T::Int, "100", "[2, 100000]", "agents", "size of the evolved population",
            DIVCOLL_FIELD(agents.population)),
        num("agents", "generations", T::Int, "15", "[0, 10000]", "",
            "generations of evolution after the trained random generation 0",
            DIVCOLL_FIELD(agents.generations)),
        num("agents", "epochs", T::Int, "15", "[0, 100000]", "",
            "gradient-descent epochs per training, one rollout on flat each", DIVCOLL_FIELD(agents.epochs)),
        num("agents", "episode_steps", T::Int, "1000", "[1, 1e7]", "steps", "steps of one training rollout",
            DIVCOLL_FIELD(agents.episode_steps)),
        pick("agents", "gd_rule", T::Choice, "\"keep_best\"", {"paper", "keep_best", "adam"},
             "agent GD rule: paper = normalized step, keep_best = the same keeping the best parameters seen, "
             "adam = Adam",
             DIVCOLL_FIELD(agents.gd_rule)),
        num("agents", "gd_step", T::Double, "0.16", "(0, 10]", "",
            "normalized-gradient step: θ ← θ − gd_step·g/‖g‖ (SPEC §4.4)", DIVCOLL_FIELD(agents.gd_step)),
        num("agents", "adam_lr", T::Double, "0.01", "(0, 1]", "", "Adam learning rate (gd_rule = adam)",
            DIVCOLL_FIELD(agents.adam_lr)),
        num("agents", "rest_move_max", T::Double, "0.002", "[0, 0.05]", "u/epoch",
            "largest move of a rest position in one epoch", DIVCOLL_FIELD(agents.rest_move_max)),
        num("agents", "rest_length_min", T::Double, "0.5", "(0, 1]", "x 0.05 u",
            "shortest allowed rest length", DIVCOLL_FIELD(agents.rest_length_min)),
        num("agents", "rest_length_max", T::Double, "1.5", "[1, 10]", "x 0.05 u",
            "longest allowed rest length", DIVCOLL_FIELD(agents.rest_length_max)),
        num("agents", "body_flip_p", T::Double, "0.03571428571428571", "[0, 1]", "",
            "mutation: flip probability of each of the 28 body bits (1/28)",
            DIVCOLL_FIELD(agents.body_flip_p)),
        num("agents", "spring_flip_p", T::Double, "0.047619047619047616", "[0, 1]", "",
            "mutation: flip probability of each of the 21 spring bits (1/21)",
            DIVCOLL_FIELD(agents.spring_flip_p)),
        num("agents", "rest_jitter_sd", T::Double, "0.005", "[0, 0.05]", "u",
            "mutation: standard deviation of the rest-position jitter", DIVCOLL_FIELD(agents.rest_jitter_sd)),
        pick("agents", "selection", T::Choice, "\"rank\"", {"paper", "rank"},
             "deletion score: paper = (fitness - min fitness + 1e-6) x uniqueness; rank = (fitness rank + 1) x "
             "(uniqueness rank + 1) among the remaining pool",
             DIVCOLL_FIELD(agents.selection)),
        num("agents", "uniqueness_k", T::Int, "5", "[1, 1000]", "agents",
            "nearest neighbours averaged in the uniqueness score", DIVCOLL_FIELD(agents.uniqueness_k)),
        flag("agents", "body_fixed", "false",
             "one body shape for every agent, no body mutation (graded-diversity variant, SPEC §7.5)",
             DIVCOLL_FIELD(agents.body_fixed)),
        flag("agents", "springs_fixed", "false", "one spring genotype for every agent, no spring mutation",
             DIVCOLL_FIELD(agents.springs_fixed)),
        flag("agents", "rest_moves", "true", "gradient descent also moves the rest positions",
             DIVCOLL_FIELD(agents.rest_moves)),
        // [connectors]
        num("connectors", "replicates", T::Int, "10", "[1, 1000]", "", "connectors trained per kind",
            DIVCOLL_FIELD(connectors.replicates)),
        num("connectors", "iterations", T::Int, "100", "[0, 1e6]", "", "optimizer steps per connector",
            DIVCOLL_FIELD(connectors.iterations)),
        num("connectors", "batch_pairs", T::Int, "100", "[1, 1e6]", "pairs",
            "pairs per training batch (uniform: agent i with its clone, i < batch_pairs)",
            DIVCOLL_FIELD(connectors.batch_pairs)),
        num("connectors", "episode_steps", T::Int, "1000", "[1, 1e7]", "steps",
            "steps of one training rollout", DIVCOLL_FIELD(connectors.episode_steps)),
        num("connectors", "weak_stiffness", T::Double, "5000.0", "(0, 1e7]", "1/s^2",
            "spring stiffness of weak connectors (per unit mass)", DIVCOLL_FIELD(connectors.weak_stiffness)),
        num("connectors", "strong_stiffness", T::Double, "30000.0", "(0, 1e7]", "1/s^2",
            "spring stiffness of strong connectors (per unit mass)",
            DIVCOLL_FIELD(connectors.strong_stiffness)),
        num("connectors", "amplitude", T::Double, "0.6", "[0, 0.9]", "",
            "actuation amplitude of connector springs, a fraction of their rest length (SPEC §6.2 reads the paper "
            "as 0.6; 0 = passive tethers); every stage that builds a connector uses it",
            DIVCOLL_FIELD(connectors.amplitude)),
        num("connectors", "damping", T::Double, "0.0", "[0, 50]", "1/s",
            "dashpot c_s of the 5 connector springs: the force −c_s·((v_i − v_j)·d̂)·d̂ per unit mass of SPEC §2.2 "
            "(SPEC §6.2 has 0, the default), damping how fast a connector stretches; every stage that builds a "
            "connector uses it and scene files carry it (springs/damping). At most 50: a mass in up to 3 connector "
            "springs keeps 2·3·c_s·Δt = 1.2 below the explicit step's limit of 2",
            DIVCOLL_FIELD(connectors.damping)),
        flag("connectors", "follower", "false",
             "upper bound: the connector springs exert no elastic or actuation force (their stiffness is 0 in every "
             "scene, exported ones included), only connectors.damping's dashpot; the controller still runs but "
             "moves nothing, so its gradient is 0 and training leaves it as initialised. With damping 0 a pair is "
             "its two agents side by side, untethered: what a collective could travel if nothing held it back, "
             "telling an optimisation failure from a physical one. A spring whose rest length followed its length "
             "each step would still push by k·ℓ·a·o through its actuation; with connectors.amplitude = 0 the two "
             "are the same, and stiffness 0 is the force-free reading for any amplitude. Weak and strong "
             "connectors are then alike",
             DIVCOLL_FIELD(connectors.follower)),
        pick("connectors", "optimizer", T::Choice, "\"adam\"", {"adam", "normalized", "cmaes", "es"},
             "connector optimizer: adam, normalized = θ ← θ − lr·g/‖g‖, or a black-box evolution strategy on the "
             "batch travel, no gradient: cmaes = CMA-ES (pagmo2; O(es_popsize·1473³) per iteration), es = "
             "antithetic pairs θ ± es_sigma·ε, centred ranks, Adam on the search gradient (Salimans et al. 2017)",
             DIVCOLL_FIELD(connectors.optimizer)),
        num("connectors", "lr", T::Double, "0.003", "(0, 1]", "", "learning rate (adam) or step (normalized)",
            DIVCOLL_FIELD(connectors.lr)),
        num("connectors", "clip_norm", T::Double, "1.0", "(0, 1e6]", "", "gradient-norm clip (see clip)",
            DIVCOLL_FIELD(connectors.clip_norm)),
        pick("connectors", "clip", T::Choice, "\"global\"", {"global", "per_pair"},
             "what clip_norm clips: global = the batch-mean gradient before an Adam step (SPEC §6.4; normalized "
             "steps ignore clip_norm); per_pair = each pair's gradient, scaled down to clip_norm before the batch "
             "mean (adam and normalized), so a few pairs whose backpropagation explodes cannot set the step's "
             "direction. Not with cmaes or es (no gradient)",
             DIVCOLL_FIELD(connectors.clip)),
        num("connectors", "init_out_gain", T::Double, "0.1", "[0, 10]", "",
            "initial weights of the connector's output layer ~ N(0, (gain·sqrt(2/(in+out)))²); 3 as the agent's, "
            "small = a nearly passive untrained connector", DIVCOLL_FIELD(connectors.init_out_gain)),
        pick("connectors", "init", T::Choice, "\"random\"", {"random", "follower"},
             "the weights training starts from: random = SPEC §6.3's random network (gains 2, 2 and "
             "init_out_gain); follower = the hand-written follower policy (collective::follower_connector_params: "
             "each spring's target length follows its length, src/collective/references.hpp) plus N(0, "
             "init_noise²) on every weight, a reading of the paper's \"random neural controller\" that starts "
             "training where a tether pulls little",
             DIVCOLL_FIELD(connectors.init)),
        pick("connectors", "network", T::Choice, "\"per_spring\"", {"per_spring", "joint"},
             "the network of a connector's controller: per_spring = SPEC §6.3's 11 → 32 → 32 → 1, one weight set "
             "applied to each of the five springs on its own inputs (1473 weights); joint = one 55 → 32 → 32 → 5 "
             "network per connector that reads all five springs' inputs and drives all five (3013 weights), the "
             "other reading of the paper's \"a neural controller\". The joint network has one hidden state per "
             "connector, not per spring, so the analysis stage (SPEC §8.2) cannot run on it",
             DIVCOLL_FIELD(connectors.network)),
        num("connectors", "init_noise", T::Double, "0.01", "[0, 10]", "",
            "init = follower: standard deviation of the Gaussian noise added to every weight of the follower "
            "policy (drawn from the connector's own stream, as the random init)", DIVCOLL_FIELD(connectors.init_noise)),
        pick("connectors", "kinds", T::StringList, string_list(kKinds), kKinds, "connector kinds to train",
             DIVCOLL_FIELD(connectors.kinds)),
        pick("connectors", "lr_schedule", T::Choice, "\"constant\"", {"constant", "cosine", "exponential"},
             "learning-rate schedule over the iterations: constant, cosine (half a cosine from lr to "
             "lr·lr_final) or exponential (geometric from lr to lr·lr_final)",
             DIVCOLL_FIELD(connectors.lr_schedule)),
        num("connectors", "lr_final", T::Double, "0.1", "(0, 1]", "",
            "the rate at the last iteration as a fraction of lr (decaying schedules)",
            DIVCOLL_FIELD(connectors.lr_final)),
        num("connectors", "bptt_window", T::Int, "0", "[0, 1e7]", "steps",
            "truncated backpropagation: the gradient of the per-window displacements, each window's start "
            "state held fixed (0 = the whole episode)",
            DIVCOLL_FIELD(connectors.bptt_window)),
        num("connectors", "horizon_start", T::Int, "0", "[0, 1e7]", "steps",
            "horizon curriculum: the training episode's length at the first iteration, growing linearly to "
            "episode_steps over horizon_ramp iterations (0 = every iteration at episode_steps); keep-best's "
            "validation always runs episode_steps",
            DIVCOLL_FIELD(connectors.horizon_start)),
        num("connectors", "horizon_ramp", T::Int, "0", "[0, 1e6]", "iterations",
            "horizon curriculum: iterations over which the training episode grows from horizon_start to "
            "episode_steps (0 = it stays at horizon_start)",
            DIVCOLL_FIELD(connectors.horizon_ramp)),
        num("connectors", "grad_samples", T::Int, "1", "[1, 1000]", "",
            "gradients averaged per step (Gaussian smoothing): 1 = the gradient at the weights; more = at the "
            "weights ± antithetic N(0, grad_sigma²) perturbations, same batch",
            DIVCOLL_FIELD(connectors.grad_samples)),
        num("connectors", "grad_sigma", T::Double, "0.01", "[0, 10]", "",
            "standard deviation of each weight's perturbation (grad_samples > 1)",
            DIVCOLL_FIELD(connectors.grad_sigma)),
        flag("connectors", "keep_best", "false",
             "return the weights with the best mean travel on a fixed validation batch (scored before every step "
             "and after the last) instead of the last weights",
             DIVCOLL_FIELD(connectors.keep_best)),
        num("connectors", "validation_pairs", T::Int, "32", "[1, 1e6]", "pairs",
            "pairs of the validation batch (keep_best): uniform kinds the clones of agents batch_pairs, "
            "batch_pairs+1, ... (mod population: held out when the population exceeds batch_pairs), diverse "
            "kinds fixed random pairs",
            DIVCOLL_FIELD(connectors.validation_pairs)),
        num("connectors", "es_popsize", T::Int, "16", "[5, 10000]", "",
            "cmaes / es: candidate weight vectors per iteration, each run on the whole batch (es: pairs of them)",
            DIVCOLL_FIELD(connectors.es_popsize)),
        num("connectors", "es_sigma", T::Double, "0.02", "(0, 10]", "",
            "cmaes: initial standard deviation of the search distribution per weight; es: sd of the perturbations",
            DIVCOLL_FIELD(connectors.es_sigma)),
        // [deploy]
        num("deploy", "episode_steps", T::Int, "3000", "[1, 1e7]", "steps",
            "steps of one deployment episode (agents alone and collectives)",
            DIVCOLL_FIELD(deploy.episode_steps)),
        num("deploy", "pairs", T::Int, "100", "[1, 100000]", "pairs",
            "pairs per connector replicate (uniform: agent i with its clone, i < pairs)",
            DIVCOLL_FIELD(deploy.pairs)),
        envs_key(string_list(kPaperEnvironments), envs,
                 "environments of the experiments; flat (the training one) must be listed, the others are novel. "
                 "The default is the paper's 13 (SPEC §3); an environment added to configs/environments.toml "
                 "runs where a config lists it"),
        num("deploy", "hidden_subsample", T::Int, "10000", "[0, 1e9]", "states",
            "hidden states kept per environment for the familiarity analysis (0 = all)",
            DIVCOLL_FIELD(deploy.hidden_subsample)),
        num("deploy", "early_step", T::Int, "0", "[0, 1e7]", "steps",
            "also record every deployment episode's travel at this step, as deploy/agents/travel_bl_early and "
            "deploy/collectives/travel_bl_early (NaN unless the episode is ok); 0 = not recorded; 1000 = the "
            "training episode length", DIVCOLL_FIELD(deploy.early_step)),
        pick("deploy", "uniform_agents", T::Choice, "\"training\"", {"training", "held_out"},
             "agents of the uniform deployments: training = agent i with its clone, i < deploy.pairs (the agents "
             "uniform connectors were trained on when i < connectors.batch_pairs); held_out = agent "
             "connectors.batch_pairs + i, which no uniform training batch held",
             DIVCOLL_FIELD(deploy.uniform_agents)),
        pick("deploy", "feature_placement", T::Choice, "\"front\"", {"front", "pair_mean", "rear"},
             "terrain features of an agent deployed alone: front = 0.05 u ahead of its front (as for every "
             "scene); pair_mean = (w + 0.05)/2 further, the mean runway of the two agents of a pair of its clones "
             "(w its body length); rear = w + 0.05 further, the runway of such a pair's rear agent. Collectives "
             "always get front", DIVCOLL_FIELD(deploy.feature_placement)),
        flag("deploy", "references", "false",
             "also deploy the three reference connectors, which need no training, on the same uniform and diverse "
             "pairs in every environment: free (no tether: the agents side by side), passive (a weak connector "
             "whose rest lengths stay fixed) and follower (a weak connector whose hand-written policy sets each "
             "spring's target length to its length); deploy/references/* (src/collective/references.hpp)",
             DIVCOLL_FIELD(deploy.references)),
        // [specialists]
        num("specialists", "replicates", T::Int, "10", "[1, 1000]", "",
            "weak connectors trained per novel environment", DIVCOLL_FIELD(specialists.replicates)),
        num("specialists", "iterations", T::Int, "100", "[0, 1e6]", "", "optimizer steps per specialist",
            DIVCOLL_FIELD(specialists.iterations)),
        // [scaling]
        num("scaling", "sizes", T::IntList, "[5, 10, 20]", "[2, 1000]", "agents",
            "chain sizes N (binary tree in heap order)", DIVCOLL_FIELD(scaling.sizes)),
        num("scaling", "draws", T::Int, "100", "[1, 100000]", "chains",
            "chains per connector replicate, size and variant (uniform: clones of agent i < draws; diverse: random draws)", DIVCOLL_FIELD(scaling.draws)),
        num("scaling", "episode_steps", T::Int, "3000", "[1, 1e7]", "steps", "steps of one chain episode",
            DIVCOLL_FIELD(scaling.episode_steps)),
        // [graded]
        flag("graded", "enabled", "true",
             "run the graded-diversity populations (when graded is in run.stages)",
             DIVCOLL_FIELD(graded.enabled)),
        num("graded", "population", T::Int, "100", "[2, 100000]", "agents", "size of each graded population",
            DIVCOLL_FIELD(graded.population)),
        // [analysis]
        num("analysis", "dtw_every", T::Int, "10", "[1, 1e6]", "steps",
            "behaviour frames for the DTW adversity: mass positions relative to the centre of mass every this many "
            "steps (SPEC §8.1)", DIVCOLL_FIELD(analysis.dtw_every)),
        num("analysis", "dtw_band", T::Double, "0.1", "[0, 1]", "",
            "Sakoe-Chiba band radius of the DTW as a fraction of the series length", DIVCOLL_FIELD(analysis.dtw_band)),
        num("analysis", "max_states", T::Int, "10000", "[10, 1e6]", "states",
            "hidden states per environment in one PaCMAP fit (training + novel, SPEC §8.2)",
            DIVCOLL_FIELD(analysis.max_states)),
        num("analysis", "bootstrap_resamples", T::Int, "1000", "[100, 1e7]", "",
            "resamples of the seeded percentile-bootstrap 95% CIs (SPEC §8.3)",
            DIVCOLL_FIELD(analysis.bootstrap_resamples)),
        pick("analysis", "alone_protocol", T::Choice, "\"same_length\"",
             {"same_length", "training_length", "training_rate"},
             "the agents-alone numbers the claims compare collectives with: same_length = their deployment travel "
             "over deploy.episode_steps, as the collectives'; training_length = their travel at deploy.early_step "
             "(the paper's training-length numbers; needs deploy.early_step); training_rate = their deployment "
             "travel × connectors.episode_steps / deploy.episode_steps", DIVCOLL_FIELD(analysis.alone_protocol)),
        pick("analysis", "dtw_cost", T::Choice, "\"euclidean\"", {"euclidean", "squared_sqrt"},
             "DTW local cost and aggregation (ANALYSIS.md §2.2): euclidean = ‖a − b‖ summed along the path; "
             "squared_sqrt = √ of ‖a − b‖² summed (tslearn)", DIVCOLL_FIELD(analysis.dtw_cost)),
        pick("analysis", "dtw_step", T::Choice, "\"symmetric1\"", {"symmetric1", "symmetric2"},
             "DTW step pattern: symmetric1 = every step adds the local cost once; symmetric2 = a diagonal step adds "
             "it twice (dtw-python's default)", DIVCOLL_FIELD(analysis.dtw_step)),
        pick("analysis", "dtw_norm", T::Choice, "\"path_length\"", {"path_length", "sum_lengths", "max_length"},
             "DTW per step (ANALYSIS.md §2.4): the distance over the optimal path's length, over n + m, or over "
             "max(n, m)", DIVCOLL_FIELD(analysis.dtw_norm)),
        num("analysis", "cell_scale", T::Double, "1.0", "(0, 1000]", "1/cell",
            "familiarity cells: PaCMAP coordinates × cell_scale are rounded to integers (1 = the paper's unit "
            "cells; 2 = cells half as wide, ANALYSIS.md §5)", DIVCOLL_FIELD(analysis.cell_scale)),
        num("analysis", "calibrated_cell_scale", T::Double, "0.0", "[0, 1000]", "1/cell",
            "familiarity counts also at this second cell scale, from the same fits (0 = none): "
            "analysis/familiarity/<type>/counts_calibrated. The protocol's statistic C24c reads it at the scale "
            "configs/studies/verdicts_cells.toml calibrates (configs/studies/verdicts_protocol.md, A6)",
            DIVCOLL_FIELD(analysis.calibrated_cell_scale)),
        pick("analysis", "familiarity_on", T::Choice, "\"hidden\"", {"hidden", "inputs"},
             "what the familiarity analysis embeds: hidden = the connector's second hidden layer (32 values, SPEC "
             "§8.2); inputs = its 11 network inputs, its percepts (SPEC §6.3), at the same sampled (step, spring): "
             "whether novel environments look new to the connector before its network transforms them. With inputs "
             "the deploy stage also stores deploy/hidden/{type}/inputs; the hidden states are kept as they are",
             DIVCOLL_FIELD(analysis.familiarity_on)),
        // [output]
        text("output", "dir", "\"runs\"", "directory of run files and checkpoints",
             DIVCOLL_FIELD(output.dir)),
        num("output", "checkpoint_every", T::Int, "1", "[1, 1e6]", "",
            "generations (or iterations) between commits of a stage's state, where a copy to the checkpoint may "
            "be made (a stop on a signal waits for the next one)", DIVCOLL_FIELD(output.checkpoint_every)),
        num("output", "checkpoint_interval_s", T::Double, "30.0", "[0, 86400]", "s",
            "least wall time between copies of the run file to its checkpoint RUN.h5.ckpt, which --resume "
            "continues from (a copy and its read-back cost the file's size twice while every rank waits); a "
            "copy is made at the first commit after this time, at the end of every stage and on a stop; 0 = "
            "at every commit. Rounds after the last copy are redone on --resume with the same results",
            DIVCOLL_FIELD(output.checkpoint_interval_s)),
    };
    return k;
  }();
  return keys;
}

#undef DIVCOLL_FIELD

// the sections in schema order
std::vector<std::string> sections() {
  std::vector<std::string> s;
  for (const Key& k : schema())
    if (std::find(s.begin(), s.end(), k.section) == s.end()) s.push_back(k.section);
  return s;
}

const Key* find_key(const std::string& section, const std::string& name) {
  for (const Key& k : schema())
    if (k.section == section && k.name == name) return &k;
  return nullptr;
}

// ---- text helpers ------------------------------------------------------------------------------

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

// levenshtein distance
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// the candidate nearest to `s`, or "" when none is within half of s's length
std::string nearest(const std::string& s, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::numeric_limits<size_t>::max();
  for (const auto& c : candidates) {
    const size_t d = edit_distance(s, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best_d <= std::max<size_t>(2, s.size() / 2) ? best : "";
}

// " (did you mean X?)" for an unknown section.key, else the known keys of the section
std::string suggestion(const std::string& section, const std::string& name) {
  for (const Key& k : schema())
    if (k.name == name) return " (did you mean " + k.full() + "?)";
  std::vector<std::string> all;
  for (const Key& k : schema()) all.push_back(k.full());
  const std::string near = nearest(section + "." + name, all);
  if (!near.empty()) return " (did you mean " + near + "?)";
  std::vector<std::string> in_section;
  for (const Key& k : schema())
    if (k.section == section) in_section.push_back(k.name);
  return " (known keys of [" + section + "]: " + join(in_section) + ")";
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// shortest text that reads back to the same double, always with a '.' or exponent so TOML sees a float
std::string double_text(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

// "a string", "an integer", ... for type messages
std::string node_kind(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "a list";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

std::string expected_kind(Type t) {
  switch (t) {
    case Type::Int:
      return "an integer";
    case Type::Double:
      return "a number";
    case Type::Bool:
      return "a boolean (true or false)";
    case Type::String:
      return "a string";
    case Type::Choice:
      return "a string";
    case Type::StringList:
      return "a list of strings";
    case Type::IntList:
      return "a list of integers";
  }
  return "";
}

// ---- per-key checks ----------------------------------------------------------------------------

bool in_range(const Key& k, double v) {
  const bool lo_ok = k.lo_open ? v > k.lo : v >= k.lo;
  const bool hi_ok = k.hi_open ? v < k.hi : v <= k.hi;
  return lo_ok && hi_ok;  // false for NaN
}

void check_int(const Key& k, long long v, const std::string& what) {
  DIVCOLL_THROW_UNLESS(in_range(k, static_cast<double>(v)),
                       what << " = " << v << " is out of range " << k.range);
}

void check_double(const Key& k, double v, const std::string& what) {
  DIVCOLL_THROW_UNLESS(in_range(k, v), what << " = " << double_text(v) << " is out of range " << k.range);
}

void check_string(const Key& k, const std::string& s) {
  DIVCOLL_THROW_UNLESS(!s.empty(), k.full() << " must not be empty");
  const bool clean = std::none_of(s.begin(), s.end(), [](char c) {
    return c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
  });
  DIVCOLL_THROW_UNLESS(clean && trim(s) == s,
                       k.full() << " = " << quoted(s)
                                << " must not hold quotes, control characters or leading/trailing spaces");
}

void check_choice(const Key& k, const std::string& s, const std::string& what) {
  const bool ok = std::find(k.choices.begin(), k.choices.end(), s) != k.choices.end();
  if (ok) return;
  const std::string near = nearest(s, k.choices);
  throw InputError(msg() << what << " = " << quoted(s) << " is not one of " << join(k.choices)
                         << (near.empty() ? "" : " (did you mean " + near + "?)"));
}

// checks the value of one key as stored in `cfg`
void check_key(const Key& k, RunConfig& cfg) {
  const Ref ref = k.field(cfg);
  switch (k.type) {
    case Type::Int:
      if (auto* p = std::get_if<int*>(&ref)) check_int(k, **p, k.full());
      if (auto* p = std::get_if<std::uint64_t*>(&ref)) {
        DIVCOLL_THROW_UNLESS(**p <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()),
                             k.full() << " = " << **p << " is out of range [0, 2^63)");
      }
      break;
    case Type::Double:
      check_double(k, *std::get<double*>(ref), k.full());
      break;
    case Type::Bool:
      break;
    case Type::String:
      check_string(k, *std::get<std::string*>(ref));
      break;
    case Type::Choice:
      check_choice(k, *std::get<std::string*>(ref), k.full());
      break;
    case Type::StringList: {
      const auto& v = *std::get<std::vector<std::string>*>(ref);
      DIVCOLL_THROW_UNLESS(!v.empty(),
                           k.full() << " must list at least one value (allowed: " << join(k.choices) << ")");
      for (size_t i = 0; i < v.size(); ++i) {
        check_choice(k, v[i], k.full() + "[" + std::to_string(i) + "]");
        for (size_t j = 0; j < i; ++j)
          DIVCOLL_THROW_UNLESS(v[j] != v[i], k.full() << " lists " << quoted(v[i]) << " twice");
      }
      break;
    }
    case Type::IntList: {
      const auto& v = *std::get<std::vector<int>*>(ref);
      DIVCOLL_THROW_UNLESS(!v.empty(), k.full() << " must list at least one value");
      for (size_t i = 0; i < v.size(); ++i) {
        check_int(k, v[i], k.full() + "[" + std::to_string(i) + "]");
        for (size_t j = 0; j < i; ++j)
          DIVCOLL_THROW_UNLESS(v[j] != v[i], k.full() << " lists " << v[i] << " twice");
      }
      break;
    }
  }
}

// ---- reading TOML nodes ------------------------------------------------------------------------

[[noreturn]] void wrong_type(const std::string& what, Type t, const toml::node& n) {
  throw InputError(msg() << what << " must be " << expected_kind(t) << ", got " << node_kind(n));
}

long long read_int(const Key& k, const toml::node& n, const std::string& what) {
  if (!n.is_integer()) wrong_type(what, Type::Int, n);
  const long long v = n.as_integer()->get();
  check_int(k, v, what);  // before narrowing to int
  return v;
}

std::string read_string(const toml::node& n, const std::string& what) {
  if (!n.is_string()) wrong_type(what, Type::String, n);
  return n.as_string()->get();
}

// converts a TOML value to the key's type, checks it and stores it in `cfg`
void read_value(const Key& k, const toml::node& n, RunConfig& cfg) {
  const Ref ref = k.field(cfg);
  const std::string what = k.full();
  switch (k.type) {
    case Type::Int: {
      const long long v = read_int(k, n, what);
      if (auto* p = std::get_if<int*>(&ref)) **p = static_cast<int>(v);
      if (auto* p = std::get_if<std::uint64_t*>(&ref)) **p = static_cast<std::uint64_t>(v);
      break;
    }
    case Type::Double:
      if (!n.is_number()) wrong_type(what, k.type, n);
      *std::get<double*>(ref) = *n.value<double>();
      break;
    case Type::Bool:
      if (!n.is_boolean()) wrong_type(what, k.type, n);
      *std::get<bool*>(ref) = n.as_boolean()->get();
      break;
    case Type::String:
    case Type::Choice:
      *std::get<std::string*>(ref) = read_string(n, what);
      break;
    case Type::StringList:
    case Type::IntList: {
      const toml::array* arr = n.as_array();
      if (!arr) wrong_type(what, k.type, n);
      std::vector<std::string> strings;
      std::vector<int> ints;
      for (size_t i = 0; i < arr->size(); ++i) {
        const std::string at = what + "[" + std::to_string(i) + "]";
        if (k.type == Type::StringList)
          strings.push_back(read_string((*arr)[i], at));
        else
          ints.push_back(static_cast<int>(read_int(k, (*arr)[i], at)));
      }
      if (k.type == Type::StringList)
        *std::get<std::vector<std::string>*>(ref) = strings;
      else
        *std::get<std::vector<int>*>(ref) = ints;
      break;
    }
  }
  check_key(k, cfg);
}

// the value of an override as a TOML node: TOML syntax, or a bare word (string keys) or comma list (lists)
toml::table override_value(const Key& k, const std::string& value, const std::string& where) {
  toml::table doc;
  bool ok = false;
  try {
    doc = toml::parse("v = " + value);
    ok = doc.size() == 1 && doc.contains("v");
  } catch (const toml::parse_error&) {
  }
  const toml::node* n = ok ? doc.get("v") : nullptr;
  toml::table out;
  switch (k.type) {
    case Type::String:
    case Type::Choice:
      if (n && n->is_string())
        out.insert("v", *n);
      else
        out.insert("v", value);
      return out;
    case Type::StringList:
      if (n && n->is_array()) {
        out.insert("v", *n);
      } else {
        toml::array arr;
        std::stringstream ss(value);
        for (std::string item; std::getline(ss, item, ',');) arr.push_back(trim(item));
        out.insert("v", std::move(arr));
      }
      return out;
    case Type::IntList:
      if (n && n->is_integer()) {
        out.insert("v", toml::array{n->as_integer()->get()});
        return out;
      }
      if (!n || !n->is_array()) {
        try {
          doc = toml::parse("v = [" + value + "]");
          n = doc.size() == 1 ? doc.get("v") : nullptr;
        } catch (const toml::parse_error&) {
          n = nullptr;
        }
      }
      break;
    default:
      break;
  }
  DIVCOLL_THROW_UNLESS(
      n, k.full() << " must be " << expected_kind(k.type) << ", got " << value << " (in " << where << ")");
  out.insert("v", *n);
  return out;
}

// ---- cross-key checks --------------------------------------------------------------------------

bool listed(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

void check_combinations(const RunConfig& c) {
  const auto& a = c.agents;
  // uniqueness needs k other agents
  DIVCOLL_THROW_UNLESS(a.uniqueness_k < a.population,
                       "agents.uniqueness_k = " << a.uniqueness_k
                                                << " must be less than agents.population = " << a.population
                                                << " (the score averages over k other agents)");
  if (stage_enabled(c, "graded")) {
    DIVCOLL_THROW_UNLESS(
        a.uniqueness_k < c.graded.population,
        "agents.uniqueness_k = " << a.uniqueness_k
                                 << " must be less than graded.population = " << c.graded.population
                                 << " (the graded populations evolve with the same score)");
  }
  // rest positions need room to move
  DIVCOLL_THROW_UNLESS(
      !a.rest_moves || a.rest_length_min < a.rest_length_max,
      "agents.rest_length_min = " << double_text(a.rest_length_min)
                                  << " and agents.rest_length_max = " << double_text(a.rest_length_max)
                                  << " leave rest lengths no room while agents.rest_moves = true");
  // a fixed body keeps its shape
  if (a.body_fixed) {
    DIVCOLL_THROW_UNLESS(a.body_flip_p == 0, "agents.body_fixed = true but agents.body_flip_p = "
                                                 << double_text(a.body_flip_p) << " (set it to 0)");
    DIVCOLL_THROW_UNLESS(!a.rest_moves,
                         "agents.body_fixed = true keeps one shape, but agents.rest_moves = true "
                         "reshapes bodies (set it to false)");
    DIVCOLL_THROW_UNLESS(a.rest_jitter_sd == 0,
                         "agents.body_fixed = true keeps one shape, but agents.rest_jitter_sd = "
                             << double_text(a.rest_jitter_sd) << " reshapes offspring (set it to 0)");
  }
  DIVCOLL_THROW_UNLESS(!a.springs_fixed || a.spring_flip_p == 0,
                       "agents.springs_fixed = true but agents.spring_flip_p = "
                           << double_text(a.spring_flip_p) << " (set it to 0)");
  DIVCOLL_THROW_UNLESS(!(a.body_fixed && a.springs_fixed) || a.generations == 0,
                       "agents.body_fixed and agents.springs_fixed leave every agent the same descriptor, so "
                       "uniqueness selection over agents.generations = "
                           << a.generations << " is undefined (set agents.generations = 0)");
  // weak is weaker than strong
  DIVCOLL_THROW_UNLESS(c.connectors.weak_stiffness < c.connectors.strong_stiffness,
                       "connectors.weak_stiffness = " << double_text(c.connectors.weak_stiffness)
                                                      << " must be less than connectors.strong_stiffness = "
                                                      << double_text(c.connectors.strong_stiffness));
  DIVCOLL_THROW_UNLESS(c.connectors.clip != "per_pair" ||
                           (c.connectors.optimizer != "cmaes" && c.connectors.optimizer != "es"),
                       "connectors.clip = per_pair clips each pair's gradient, but connectors.optimizer = "
                           << c.connectors.optimizer << " uses no gradient (set clip = \"global\" or a gradient "
                           << "optimizer: adam, normalized)");
  DIVCOLL_THROW_UNLESS(c.connectors.network != "joint" || !stage_enabled(c, "analysis"),
                       "connectors.network = joint has one hidden state per connector, but the analysis stage reads "
                       "one per connector spring (SPEC §8.2): leave \"analysis\" out of run.stages");
  // uniform batches and deployments pair agent i with its clone, i < count
  const auto& kinds = c.connectors.kinds;
  if (stage_enabled(c, "connectors") && (listed(kinds, "weak_uniform") || listed(kinds, "strong_uniform"))) {
    DIVCOLL_THROW_UNLESS(c.connectors.batch_pairs <= a.population,
                         "connectors.batch_pairs = " << c.connectors.batch_pairs
                                                     << " is more than agents.population = " << a.population
                                                     << ": a uniform batch pairs agent i with its clone for "
                                                        "i < batch_pairs");
  }
  if (stage_enabled(c, "deploy")) {
    DIVCOLL_THROW_UNLESS(
        c.deploy.pairs <= a.population,
        "deploy.pairs = " << c.deploy.pairs << " is more than agents.population = " << a.population
                          << ": uniform deployment pairs agent i with its clone for i < pairs");
  }
  // the study's variant keys (SPEC-free readings of the paper; defaults are the spec's)
  DIVCOLL_THROW_UNLESS(c.deploy.early_step < c.deploy.episode_steps,
                       "deploy.early_step = " << c.deploy.early_step << " must be less than deploy.episode_steps = "
                                              << c.deploy.episode_steps);
  DIVCOLL_THROW_UNLESS(c.analysis.alone_protocol != "training_length" || c.deploy.early_step > 0,
                       "analysis.alone_protocol = training_length reads the agents' travel at deploy.early_step, "
                       "but deploy.early_step = 0 (set it, e.g. to 1000)");
  if (stage_enabled(c, "deploy") && c.deploy.uniform_agents == "held_out") {
    DIVCOLL_THROW_UNLESS(c.connectors.batch_pairs + c.deploy.pairs <= a.population,
                         "deploy.uniform_agents = held_out deploys agents connectors.batch_pairs = "
                             << c.connectors.batch_pairs << " and up, but connectors.batch_pairs + deploy.pairs = "
                             << c.connectors.batch_pairs + c.deploy.pairs << " is more than agents.population = "
                             << a.population);
  }
  // novel environments for the stages that use them
  for (const char* stage : {"specialists", "scaling"}) {
    DIVCOLL_THROW_UNLESS(!stage_enabled(c, stage) || c.deploy.environments.size() >= 2,
                         "run.stages has "
                             << stage << ", which runs in the novel environments, but deploy.environments"
                             << " lists only flat");
  }
  // diverse chains of N need N distinct agents and both weak connector kinds
  if (stage_enabled(c, "scaling")) {
    for (int n : c.scaling.sizes)
      DIVCOLL_THROW_UNLESS(n <= a.population, "scaling.sizes has "
                                                  << n << " but agents.population = " << a.population
                                                  << ": a diverse chain needs N distinct agents");
    DIVCOLL_THROW_UNLESS(c.scaling.draws <= a.population,
                         "scaling.draws = " << c.scaling.draws << " is more than agents.population = " << a.population
                                            << ": uniform chains are clones of agent i for i < draws");
    for (const char* kind : {"weak_uniform", "weak_diverse"})
      DIVCOLL_THROW_UNLESS(listed(kinds, kind), "run.stages has scaling, which uses "
                                                    << kind << " connectors, but connectors.kinds"
                                                    << " lacks " << kind);
  }
}

}  // namespace

// ---- public ------------------------------------------------------------------------------------

RunConfig default_config() {
  static const RunConfig defaults = [] {
    RunConfig c;
    for (const Key& k : schema()) {
      const toml::table doc = toml::parse("v = " + k.def);
      read_value(k, *doc.get("v"), c);
    }
    return c;
  }();
  return defaults;
}

RunConfig parse_config(const std::string& toml_text, const std::string& origin,
                       const std::vector<std::string>& overrides) {
  toml::table root = parse_toml_table(toml_text, origin);
  const std::vector<std::string> secs = sections();

  // overrides replace (or add) values in the parsed document, so they get the checks below
  std::map<std::string, std::string> from_override;  // key -> the override that set it
  for (const std::string& o : overrides) {
    const std::string where = "command-line override '" + o + "'";
    const size_t eq = o.find('=');
    DIVCOLL_THROW_UNLESS(eq != std::string::npos, where << " must look like section.key=value");
    const std::string name = trim(o.substr(0, eq));
    const size_t dot = name.find('.');
    DIVCOLL_THROW_UNLESS(dot != std::string::npos, where << " must look like section.key=value");
    const std::string sec = name.substr(0, dot), key = name.substr(dot + 1);
    const Key* k = find_key(sec, key);
    if (!k) throw InputError(msg() << "unknown key " << name << " in " << where << suggestion(sec, key));
    toml::table value = override_value(*k, trim(o.substr(eq + 1)), where);
    if (!root.contains(sec)) root.insert(sec, toml::table{});
    toml::table* t = root.get(sec)->as_table();
    DIVCOLL_THROW_UNLESS(t, sec << " in " << origin << " must be a section [" << sec << "]");
    t->insert_or_assign(key, std::move(*value.get("v")));
    from_override[name] = o;
  }

  RunConfig cfg = default_config();
  for (auto&& [sk, snode] : root) {
    const std::string sec(sk.str());
    if (!listed(secs, sec)) {
      if (!snode.is_table()) {
        const std::string s = suggestion("", sec);
        throw InputError(msg() << "key " << sec << " in " << origin << " sits outside every section"
                               << (s.rfind(" (did", 0) == 0 ? s : ""));
      }
      const std::string near = nearest(sec, secs);
      throw InputError(msg() << "unknown section [" << sec << "] in " << origin
                             << (near.empty() ? " (known sections: " + join(secs) + ")"
                                              : " (did you mean [" + near + "]?)"));
    }
    const toml::table* t = snode.as_table();
    DIVCOLL_THROW_UNLESS(
        t, sec << " in " << origin << " must be a section [" << sec << "], got " << node_kind(snode));
    for (auto&& [kk, node] : *t) {
      const std::string key(kk.str()), name = sec + "." + key;
      const Key* k = find_key(sec, key);
      if (!k) throw InputError(msg() << "unknown key " << name << " in " << origin << suggestion(sec, key));
      try {
        read_value(*k, node, cfg);
      } catch (const InputError& e) {
        if (from_override.count(name))
          throw InputError(msg() << e.what() << " (in command-line override '" << from_override[name]
                                 << "')");
        throw InputError(msg() << e.what() << " (in " << origin << ", line " << node.source().begin.line
                               << ")");
      }
    }
  }
  validate(cfg);
  return cfg;
}

RunConfig load_config(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  DIVCOLL_THROW_UNLESS(in, "cannot read config file " << path);
  std::stringstream ss;
  ss << in.rdbuf();
  // a file that sets nothing would silently start the paper-scale run (every key at its paper value)
  bool empty = false;
  try {
    empty = parse_toml_table(ss.str(), path).empty();
  } catch (const TomlSyntaxError&) {
    // parse_config reports it with the line
  }
  DIVCOLL_THROW_UNLESS(!empty, path << " sets no key, so every key would take its paper-scale default (hours on "
                                      "many cores); name a preset instead (configs/tiny.toml, configs/quick.toml, or "
                                      "configs/paper.toml for the whole paper) or set the keys you mean");
  return parse_config(ss.str(), path, overrides);
}

RunConfig apply_overrides(const RunConfig& cfg, const std::vector<std::string>& overrides) {
  return parse_config(to_toml(cfg), "the resolved config", overrides);
}

void validate(const RunConfig& cfg) {
  RunConfig c = cfg;
  for (const Key& k : schema()) check_key(k, c);
  // the run file is <output.dir>/<run.name>.h5: the name must not lead out of output.dir
  const std::string& name = c.run.name;
  DIVCOLL_THROW_UNLESS(name.find('/') == std::string::npos && name != "." && name != ".." &&
                           std::none_of(name.begin(), name.end(), [](char ch) { return static_cast<unsigned char>(ch) < 32; }),
                       "run.name = " << quoted(name) << " must be a plain file name (no '/', not '.' or '..', no control "
                                     "characters): the run file is <output.dir>/<run.name>.h5");
  DIVCOLL_THROW_UNLESS(
      listed(c.deploy.environments, "flat"),
      "deploy.environments must list flat, the training environment every experiment compares "
      "against");
  DIVCOLL_THROW_UNLESS(c.connectors.horizon_start <= c.connectors.episode_steps,
                       "connectors.horizon_start (" + std::to_string(c.connectors.horizon_start) +
                           ") must not exceed connectors.episode_steps (" +
                           std::to_string(c.connectors.episode_steps) + ")");
  check_combinations(c);
}

const std::vector<std::string>& stage_names() { return kStages; }

bool stage_enabled(const RunConfig& cfg, const std::string& stage) {
  if (stage == "graded" && !cfg.graded.enabled) return false;
  return listed(cfg.run.stages, stage);
}

std::vector<std::string> sections_before(const std::string& stage) {
  std::vector<std::string> out;
  for (const std::string& s : stage_names()) {
    if (s == stage) break;
    out.push_back(s);
  }
  return out;
}

std::string incompatible_keys(const RunConfig& base, const RunConfig& now, const std::string& from) {
  const auto a = flat(base), b = flat(now);
  const auto secs = sections_before(from);
  std::string diff;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string sec = a[i].first.substr(0, a[i].first.find('.'));
    // analysis.familiarity_on = inputs has the deploy stage store the connectors' inputs too: bound with [deploy]
    const bool deploy_reads = a[i].first == "analysis.familiarity_on" && listed(secs, "deploy");
    const bool bound = a[i].first == "run.seed" || a[i].first == "run.precision" || a[i].first == "run.contact" ||
                       deploy_reads || listed(secs, sec);
    if (bound && a[i].second != b[i].second) diff += " " + a[i].first + " (" + a[i].second + " -> " + b[i].second + ")";
  }
  return diff;
}

namespace {

// the value of one key as a TOML literal; strings bare when `bare_strings`
std::string value_text(const Key& k, RunConfig& c, bool bare_strings) {
  const Ref ref = k.field(c);
  if (auto* p = std::get_if<int*>(&ref)) return std::to_string(**p);
  if (auto* p = std::get_if<std::uint64_t*>(&ref)) return std::to_string(**p);
  if (auto* p = std::get_if<double*>(&ref)) return double_text(**p);
  if (auto* p = std::get_if<bool*>(&ref)) return **p ? "true" : "false";
  if (auto* p = std::get_if<std::string*>(&ref)) return bare_strings ? **p : quoted(**p);
  if (auto* p = std::get_if<std::vector<std::string>*>(&ref)) return string_list(**p);
  const auto& v = *std::get<std::vector<int>*>(ref);
  std::string out = "[";
  for (size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + std::to_string(v[i]);
  return out + "]";
}

// "in [2, 100000]", "one of a, b", "any of a, b" ...
std::string allowed_text(const Key& k) {
  switch (k.type) {
    case Type::Int:
    case Type::Double:
      return k.range;
    case Type::IntList:
      return "each in " + k.range;
    case Type::Bool:
      return "true, false";
    case Type::String:
      return "non-empty";
    case Type::Choice:
      return "one of " + join(k.choices);
    case Type::StringList:
      return k.choices_text.empty() ? "any of " + join(k.choices) : k.choices_text;
  }
  return "";
}

// a comment wrapped at 110 columns
std::string comment(const std::string& text) {
  std::string out, line = "#";
  std::stringstream ss(text);
  for (std::string word; ss >> word;) {
    if (line.size() > 1 && line.size() + 1 + word.size() > 110) {
      out += line + "\n";
      line = "#  ";
    }
    line += " " + word;
  }
  return out + line + "\n";
}

// a `key = [a, b, ...]` line longer than 110 columns as a multi-line array
std::string wrapped(const std::string& line) {
  const size_t open = line.find(" = [");
  if (line.size() <= 110 || open == std::string::npos) return line + "\n";
  std::string out = line.substr(0, open + 4) + "\n", row = "   ";
  std::stringstream ss(line.substr(open + 4, line.size() - open - 5));
  for (std::string item; std::getline(ss, item, ',');) {
    item = trim(item) + ",";
    if (row.size() > 3 && row.size() + 1 + item.size() > 110) {
      out += row + "\n";
      row = "   ";
    }
    row += " " + item;
  }
  return out + row + "\n]\n";
}

std::string type_text(Type t) {
  switch (t) {
    case Type::Int:
      return "int";
    case Type::Double:
      return "float";
    case Type::Bool:
      return "bool";
    case Type::String:
      return "string";
    case Type::Choice:
      return "string";
    case Type::StringList:
      return "list of strings";
    case Type::IntList:
      return "list of ints";
  }
  return "";
}

}  // namespace

std::string to_toml(const RunConfig& cfg) {
  RunConfig c = cfg;
  std::string out =
      "# divcoll run configuration, fully resolved: every key, its value and what it means\n"
      "# (run it with `divcoll run FILE`; keys and ranges: configs/README.md, or `divcoll keys`)\n";
  std::string section;
  for (const Key& k : schema()) {
    if (k.section != section) {
      section = k.section;
      out += "\n[" + section + "]\n";
    }
    out += comment(k.doc + (k.unit.empty() ? "" : "; unit " + k.unit) + "; allowed " + allowed_text(k));
    out += wrapped(k.name + " = " + value_text(k, c, false));
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> flat(const RunConfig& cfg) {
  RunConfig c = cfg;
  std::vector<std::pair<std::string, std::string>> out;
  for (const Key& k : schema()) out.emplace_back(k.full(), value_text(k, c, true));
  return out;
}

std::vector<std::string> config_keys() {
  std::vector<std::string> out;
  for (const Key& k : schema()) out.push_back(k.full());
  return out;
}

std::string schema_markdown() {
  std::string out =
      "| key | type | default | allowed | unit | meaning |\n"
      "|---|---|---|---|---|---|\n";
  for (const Key& k : schema()) {
    std::string def = k.def;
    if (k.type == Type::StringList && k.choices_text.empty() && def == string_list(k.choices)) def = "all";
    out += "| `" + k.full() + "` | " + type_text(k.type) + " | `" + def + "` | " + allowed_text(k) + " | " +
           k.unit + " | " + k.doc + " |\n";
  }
  return out;
}

sim::RunPhysics run_physics(const RunConfig& cfg) {
  sim::RunPhysics p;
  DIVCOLL_THROW_UNLESS(sim::contact_law_from_name(cfg.run.contact, &p.contact),
                       "run.contact = \"" << cfg.run.contact << "\" is not a contact law (coulomb, no_slip)");
  DIVCOLL_THROW_UNLESS(cfg.run.precision == "double" || cfg.run.precision == "float_networks",
                       "run.precision = \"" << cfg.run.precision << "\" is not a precision (double, float_networks)");
  p.float_networks = cfg.run.precision == "float_networks";
  return p;
}

}  // namespace divcoll::config
