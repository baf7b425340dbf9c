// the runs of a study: one per (seed, variant) that runs at that seed, seed by seed, each seed's variants in file
// order, each with its config built and validated, and the earlier run whose stages it reuses. The base of a run
// is the earlier run of the same seed that shares the most leading stages (the earliest on a tie): their keys agree
// for those stages (config::incompatible_keys, as divcoll run --from asks), so variants that differ only in deploy keys
// do not retrain agents or connectors.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "study/study_file.hpp"

namespace divcoll::study {

// one run of the study and how it is made
struct PlannedRun {
  int variant = 0;
  std::uint64_t seed = 0;
  std::vector<std::string> overrides;  // scale, then the variant's, then run.seed
  config::RunConfig cfg;
  std::string path;                    // relative to the study folder: <variant>/seed<k>.h5
  int base_run = -1;                   // index of the run whose earlier stages it reuses (-1: none)
  std::string from;                    // the first stage it computes when it reuses
};

// every run with its config (validated against s.base; InputError naming the variant and seed) and what it reuses
std::vector<PlannedRun> plan(const Study& s);

// the stages a run computes itself (indices into config::stage_names()), given the stage it starts from ("": all)
std::vector<int> computed(const config::RunConfig& cfg, const std::string& from);
std::vector<int> computed(const PlannedRun& r);
// "agents,connectors,deploy"
std::string stages_text(const std::vector<int>& stages);

// the run --run names: its 1-based number in the plan, or its path (baseline/seed3.h5, or baseline/seed3)
int find_run(const std::vector<PlannedRun>& runs, const std::string& which);

}  // namespace divcoll::study
