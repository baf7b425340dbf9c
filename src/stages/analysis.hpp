// the analysis stage (SPEC §8): DTW adversity and PaCMAP familiarity of the weak connectors deployed as
// trained (weak_uniform@uniform: clones; weak_diverse@diverse: the deployment's diverse pairs), with the
// statistics of Fig. 3A and Table S1. It reads only the agents, connectors and deploy groups, so it can be
// added to any finished run with `divcoll run CONFIG --from analysis --base RUN.h5 --out NEW.h5`.
//
// Two plans (stages/plan.hpp), both counting in /analysis; their statistics are each plan's
// finish(), over its rows restored after a resume.
// Adversity (§8.1), one round of two farm passes per environment (committed after each, dtw_envs_done):
//   1. every agent alone, recorded: its behaviour = its 11 masses relative to its centre of mass every
//      analysis.dtw_every steps (frames × 22), broadcast to every rank;
//   2. every pair episode of the two types, recorded: for each of its two agents the DTW distance between
//      the tethered and the independent behaviour — symmetric1, Euclidean local cost, Sakoe–Chiba band
//      ceil(analysis.dtw_band · frames), divided by the warping path's length.
//   Both rounds re-simulate deploy's episodes; their travel must equal deploy's bit for bit (counted in the
//   attribute adversity/deploy_mismatches, printed if not 0).
//   Worse / better agent: the one that travelled less / more alone in that environment. Clones (uniform pairs)
//   tie; a tie makes the posterior agent the worse one (not counted: for weak_uniform@uniform every pair ties).
// Familiarity (§8.2), one round per novel environment (committed after each, familiarity_envs_done): per
//   type and replicate, the hidden states deploy recorded in flat and in the environment (ok episodes only; at most
//   analysis.max_states per environment, a seeded subsample), one PaCMAP fit on both together, coordinates
//   rounded half to even, each state counted as in a cell holding both / only training / only novel states.
// Statistics (§8.3): per replicate the mean DTW of the worse and of the better agents over environments and
//   pairs; over replicates the mean, a seeded percentile-bootstrap 95% CI, Welch's t-test between the types.
//   Table S1: per novel environment, the counts' mean over replicates per type and Welch's p between them.
//
// Run file, group /analysis (attributes status, types, environments, novel_environments, dtw_envs_done,
// familiarity_envs_done):
//   adversity/<type>/dtw          (E × R × pairs × 2)  DTW per agent slot (0 posterior, 1 anterior); NaN
//                                                      unless the pair and both agents alone were ok
//   adversity/<type>/worse_slot   (E × R × pairs)      slot of the worse agent (uint8)
//   adversity/replicate_means     (types × 2 × R)      mean DTW of the worse (0) / better (1) agents
//   adversity/summary             (types × 2 × 3)      mean over replicates, CI low, CI high
//   adversity/welch               (2 × 3)              worse / better: t, df, p (uniform vs diverse type)
//   familiarity/<type>/counts     (novel E × R × 6)    states in both / train-only / novel-only cells, then
//                                                      the cells: both / train-only / novel-only
//   familiarity/<type>/counts_calibrated  (novel E × R × 6)  the same counts at analysis.calibrated_cell_scale
//                                                      (only when it is > 0)
//   familiarity/<type>/n_states   (novel E × R × 2)    training and novel states in the fit
//   familiarity/<type>/embedding  (novel E × R × 2·max_states × 2, float32)  the fit's 2-D coordinates:
//                                                      training states first, then novel; NaN padding
//   familiarity/table             (novel E × 3 × 3)    per count (both, train-only, novel-only): mean over
//                                                      replicates of the diverse type, of the uniform type,
//                                                      Welch's p (NaN when a type is missing)
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kAnalysisStage = config::stage_stream("analysis");

// the two types the analyses compare: weak connectors deployed as trained
inline const std::array<std::string, 2> kAnalysisTypes = {"weak_uniform@uniform", "weak_diverse@diverse"};

// deploy's travel and status, agents alone (E × pop) and collectives (E × T × R × NP), to check the
// re-simulated episodes against (master)
struct Deployed {
  std::vector<double> alone, pairs;
  std::vector<uint8_t> alone_status, pairs_status;
};

// the config values the analyses read: the run's seed, the [analysis] section, the [deploy] section (its
// environments, pairs, episode length, uniform agents and feature placement, as deploy ran them), from
// [connectors] the replicates, batch_pairs and the weak connector's springs, and the run's physics
struct AnalysisDef {
  uint64_t seed = 0;
  config::RunConfig::Analysis analysis;
  config::RunConfig::Deploy deploy;
  config::RunConfig::Connectors connectors;
  sim::RunPhysics physics;  // run.contact, run.precision
};
AnalysisDef analysis_def(const config::RunConfig& cfg);

// the adversity analysis (§8.1) as a plan. Per type of kAnalysisTypes: its weights (one per replicate), its pairs
// and its index among deploy's `deploy_types` types; `novel`: the novel environments. It keeps a reference to
// `agents`, which must outlive it
std::unique_ptr<Plan> make_adversity_plan(const AnalysisDef& def, const std::vector<morph::Agent>& agents,
                                          std::array<std::vector<std::vector<double>>, 2> weights,
                                          std::array<std::vector<std::pair<int, int>>, 2> pairs,
                                          std::array<int, 2> type_index, int deploy_types,
                                          std::vector<std::string> novel, Deployed deployed);

// the familiarity analysis (§8.2) as a plan. `hidden`: deploy's states of the two types (E × R × NP × K × dim:
// hidden states, dim 32, or the network inputs, dim 11)
std::unique_ptr<Plan> make_familiarity_plan(const AnalysisDef& def, std::vector<std::string> novel,
                                            std::array<std::vector<float>, 2> hidden, int K, int dim);

}  // namespace divcoll::stages
