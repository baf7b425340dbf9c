// the run configuration of `divcoll evolve CONFIG` / `divcoll run CONFIG`: a TOML file with the sections
// [run] [agents] [connectors] [deploy] [specialists] [scaling] [graded] [analysis] [output].
//
// One schema table in config.cpp lists every key (type, default, allowed range or values, unit, doc);
// parsing, checking, the resolved TOML echo, the flat key/value list for HDF5 attributes and configs/README.md's
// table all come from it. Defaults are the paper's counts (SPEC §4.4, §6.4, §7).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "sim/engine.hpp"

namespace divcoll::config {

// every value of a run; get one from default_config() or parse_config(), never from a bare RunConfig{}
// (that is all zeros and fails validate)
struct RunConfig {
  struct Run {
    std::uint64_t seed{};  // run seed: every draw is seeded by (seed, stage, item)
    std::string name;      // run name, used in output file names
    std::vector<std::string>
        stages;                 // stages to run, from agents connectors deploy specialists scaling graded analysis
    double progress_every_s{};  // seconds between progress lines (0 = none)
    double stop_grace_s{};      // after SIGTERM/SIGINT/SIGUSR1: longest wait for the next checkpoint
    double memory_limit_gb{};   // per node, for every rank's simulator tape together (0 = 80% of MemAvailable)
    std::string precision;      // double | float_networks (the controllers' networks in float; run_physics)
    std::string contact;        // coulomb | no_slip: the contact law of every environment (run_physics)
    bool operator==(const Run&) const = default;
  };
  struct Agents {
    int population{};          // agents per population
    int generations{};         // generations of evolution after generation 0
    int epochs{};              // GD epochs per training
    int episode_steps{};       // steps of one training rollout
    std::string gd_rule;       // paper | keep_best | adam
    double gd_step{};          // normalized-gradient step θ ← θ − step·g/‖g‖
    double adam_lr{};          // Adam learning rate (gd_rule = adam)
    double rest_move_max{};    // u per epoch, largest rest-position move
    double rest_length_min{};  // × 0.05 u, shortest rest length
    double rest_length_max{};  // × 0.05 u, longest rest length
    double body_flip_p{};      // per body bit
    double spring_flip_p{};    // per spring bit
    double rest_jitter_sd{};   // u, offspring rest-position jitter
    std::string selection;     // deletion score: "paper" or "rank"
    int uniqueness_k{};        // nearest neighbours in the uniqueness score
    bool body_fixed{};         // one body shape for all (graded-diversity variant, SPEC §7.5)
    bool springs_fixed{};      // one spring genotype for all
    bool rest_moves{};         // GD moves rest positions
    bool operator==(const Agents&) const = default;
  };
  struct Connectors {
    int replicates{};                // connectors trained per kind
    int iterations{};                // optimizer steps per connector
    int batch_pairs{};               // pairs per batch
    int episode_steps{};             // steps of one training rollout
    double weak_stiffness{};         // spring stiffness of weak connectors
    double strong_stiffness{};       // spring stiffness of strong connectors
    double amplitude{};              // actuation amplitude of connector springs (fraction of rest length)
    double damping{};                // dashpot c_s of connector springs, 1/s (SPEC §2.2; 0 = SPEC §6.2)
    bool follower{};                 // connector springs exert no elastic or actuation force (stiffness 0)
    std::string optimizer;           // adam | normalized | cmaes
    double lr{};                     // learning rate (Adam) or step (normalized)
    double clip_norm{};              // gradient norm clip
    std::string clip;                // global | per_pair: what clip_norm clips (the batch mean or each pair's gradient)
    double init_out_gain{};          // init gain of the connector network's output layer
    std::string init;                // random | follower: the weights training starts from
    std::string network;             // per_spring | joint: the connector's network (sim::connector_param_count)
    double init_noise{};             // init = follower: sd of the noise on every weight
    std::vector<std::string> kinds;  // from weak_uniform weak_diverse strong_uniform strong_diverse
    std::string lr_schedule;         // constant | cosine | exponential (src/evo/connector_opt.hpp)
    double lr_final{};               // the rate at the last iteration as a fraction of lr (decaying schedules)
    int bptt_window{};               // truncated backpropagation window, steps (0 = the whole episode)
    int horizon_start{};             // horizon curriculum: training episode steps at the first iteration (0 = none)
    int horizon_ramp{};              // iterations over which the training episode grows to episode_steps
    int grad_samples{};              // gradients averaged per step, at weights perturbed by N(0, grad_sigma²)
    double grad_sigma{};             // sd of those perturbations
    bool keep_best{};                // return the weights best on a fixed validation batch
    int validation_pairs{};          // pairs of that batch
    int es_popsize{};                // cmaes: candidates per iteration
    double es_sigma{};               // cmaes: initial sd of the search distribution per weight
    bool operator==(const Connectors&) const = default;
  };
  struct Deploy {
    int episode_steps{};                    // steps of one deployment episode
    int pairs{};                            // pairs per connector replicate
    std::vector<std::string> environments;  // names from configs/environments.toml, flat among them
    int hidden_subsample{};                 // hidden states kept per environment (0 = all)
    int early_step{};                       // also record travel at this step (0 = no)
    std::string uniform_agents;             // training | held_out: the agents of uniform deployments
    std::string feature_placement;          // front | pair_mean | rear: where an agent alone meets features
    bool references{};                      // also deploy the reference connectors (free, passive, follower)
    bool operator==(const Deploy&) const = default;
  };
  struct Specialists {
    int replicates{};  // connectors per novel environment
    int iterations{};  // optimizer steps per connector
    bool operator==(const Specialists&) const = default;
  };
  struct Scaling {
    std::vector<int> sizes;  // chain sizes N
    int draws{};             // diverse chains per replicate and size
    int episode_steps{};     // steps of one chain episode
    bool operator==(const Scaling&) const = default;
  };
  struct Graded {
    bool enabled{};    // run the graded-diversity populations
    int population{};  // agents per graded population
    bool operator==(const Graded&) const = default;
  };
  struct Analysis {
    int dtw_every{};           // steps between behaviour frames for the DTW adversity
    double dtw_band{};         // Sakoe–Chiba band radius as a fraction of the series length
    int max_states{};          // hidden states per environment in one PaCMAP fit
    int bootstrap_resamples{};  // percentile-bootstrap resamples of the CIs
    std::string alone_protocol;  // same_length | training_length | training_rate (claims' agents-alone numbers)
    std::string dtw_cost;        // euclidean | squared_sqrt (ANALYSIS.md §2.2)
    std::string dtw_step;        // symmetric1 | symmetric2
    std::string dtw_norm;        // path_length | sum_lengths | max_length (ANALYSIS.md §2.4)
    double cell_scale{};         // familiarity cells: round(cell_scale · PaCMAP coordinate)
    double calibrated_cell_scale{};  // > 0: familiarity counts also at this cell scale (counts_calibrated)
    std::string familiarity_on;  // hidden | inputs: what the familiarity PaCMAP embeds (SPEC §8.2: hidden)
    bool operator==(const Analysis&) const = default;
  };
  struct Output {
    std::string dir;         // directory of run files
    int checkpoint_every{};  // generations / iterations between commits of a stage's state
    double checkpoint_interval_s{};  // least wall time between copies of the run file to its checkpoint
    bool operator==(const Output&) const = default;
  };

  Run run;
  Agents agents;
  Connectors connectors;
  Deploy deploy;
  Specialists specialists;
  Scaling scaling;
  Graded graded;
  Analysis analysis;
  Output output;

  bool operator==(const RunConfig&) const = default;
};

// the defaults of the schema (the paper's counts)
RunConfig default_config();

// parses a TOML text, then applies `overrides` ("section.key=value", value in TOML syntax; a bare word
// is taken as a string, a comma list as a list), then runs validate(). Keys left out keep their default.
// Throws InputError naming the key on an unknown section or key (with the nearest known key), a wrong type,
// an out-of-range value or an impossible combination. `origin` names the source in messages.
RunConfig parse_config(const std::string& toml_text, const std::string& origin,
                       const std::vector<std::string>& overrides = {});
// reads and parses the file at `path` (InputError if it cannot be read)
RunConfig load_config(const std::string& path, const std::vector<std::string>& overrides = {});
// applies "section.key=value" overrides to a resolved config, with the same checks
RunConfig apply_overrides(const RunConfig& cfg, const std::vector<std::string>& overrides);

// checks every key's range and every cross-key rule; throws InputError naming the keys
void validate(const RunConfig& cfg);

// whether a stage runs: listed in run.stages (and, for "graded", graded.enabled)
bool stage_enabled(const RunConfig& cfg, const std::string& stage);
// the pipeline's stages in the order they run: agents connectors deploy specialists scaling graded analysis
const std::vector<std::string>& stage_names();
// the sections whose keys decide what the stages before `stage` computed (beside run.seed, run.precision and
// run.contact, which every stage uses)
std::vector<std::string> sections_before(const std::string& stage);
// the keys that decide what the stages before `from` computed (those sections, run.seed, run.precision,
// run.contact, and analysis.familiarity_on, which the deploy stage reads, when deploy is before `from`) that differ
// between two configs, as " key (old -> new)" items. Empty: a run of `now` may start at `from` on a copy of a run of
// `base` (divcoll run --from; a study reuses a run's stages only then, so a precision variant computes every stage)
std::string incompatible_keys(const RunConfig& base, const RunConfig& now, const std::string& from);

// the fully resolved config as TOML, every key with its doc as a comment; parses back to `cfg`
std::string to_toml(const RunConfig& cfg);
// ("section.key", value) for every key in schema order: numbers and booleans as in TOML, strings bare,
// lists as TOML arrays; every pair is also a valid override, so apply_overrides(default, flat(c)) == c
std::vector<std::pair<std::string, std::string>> flat(const RunConfig& cfg);
// every key as "section.key", in schema order
std::vector<std::string> config_keys();
// a markdown table of every key: key, type, default, allowed, unit, meaning
std::string schema_markdown();

// the config's run-wide physics (run.contact, run.precision), for whatever builds the run's scenes and episodes
// (the stage plans, and the commands that rebuild a run's scenes from its stored config): the contact law goes
// into every environment placed, the precision into every episode's sim::RunOptions. InputError on a name that
// is not a law or a precision
sim::RunPhysics run_physics(const RunConfig& cfg);

}  // namespace divcoll::config
