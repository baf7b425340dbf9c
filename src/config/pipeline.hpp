// the pipeline's fixed tables, one home each: its stages in the order they run with the random stream each
// draws from (SPEC §10: every draw is seeded by (run.seed, stream, item)) and what each reads, and the
// connector kinds (SPEC §6.2, §6.4) with the config key that gives their stiffness. The config schema takes
// its allowed names from here, `divcoll run` its stages, the stages their stream ids, the commands their stiffness.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/check.hpp"
#include "config/config.hpp"

namespace divcoll::config {

// ---- stages --------------------------------------------------------------------------------------
// The one stage list, in the order the stages run: X(name, first random stream id, the stages whose results
// it reads (comma separated)). A stage's runner is run_<name>_stage (declared from this list in
// src/stages/driver.hpp, defined beside its plans in src/stages/<name>.cpp); its rows are in the run-file
// schema (io/run_file.cpp). Adding a stage: a line here, its runner and plans, its rows; `run.stages`, `divcoll
// run`'s checks and postprocess/'s stage list (divcoll_post.reader.STAGES reads the X(name, ...) lines) follow.
// Streams: agents 1000 + generation; connectors 2000 + kind·R + replicate; deploy 3000 (pairs) and 3001
// (hidden states); specialists 4000 + env·R + replicate; scaling 5000 + size; analysis 6000 + 1..3;
// graded 1000000 + 100000·population (+ 50000 + replicate for its connectors, + 90000 for its pairs)
#define DIVCOLL_STAGES(X)                         \
  X(agents, 1000, "")                             \
  X(connectors, 2000, "agents")                   \
  X(deploy, 3000, "agents,connectors")            \
  X(specialists, 4000, "agents")                  \
  X(scaling, 5000, "agents,connectors")           \
  X(graded, 1000000, "agents")                    \
  X(analysis, 6000, "agents,connectors,deploy")

struct StageInfo {
  std::string_view name;
  uint64_t stream;         // first random stream id; a stage may use ids from here up (see each stage's plan)
  std::string_view reads;  // the stages whose results it reads, comma separated
};
#define DIVCOLL_STAGE_INFO(name, stream, reads) StageInfo{#name, stream, reads},
inline constexpr std::array kStageTable = {DIVCOLL_STAGES(DIVCOLL_STAGE_INFO)};
#undef DIVCOLL_STAGE_INFO
constexpr uint64_t stage_stream(std::string_view name) {
  for (const StageInfo& s : kStageTable)
    if (s.name == name) return s.stream;
  return 0;  // not reached for a known name (a constant expression with an unknown one fails to compile)
}

// ---- the items of a connector's random stream ---------------------------------------------------------
// Every connector being trained (a slot of the connectors, specialists or graded stage) draws from its own stream
// (seed, the slot's stream id above); items 0, 1, ... are its batches' random pairs, and these items the rest:
inline constexpr uint64_t kItemInitialWeights = 1000000;    // its initial weights (connectors.init)
inline constexpr uint64_t kItemCmaesSeed = 1000001;         // cmaes: the seed of pagmo2's generator
inline constexpr uint64_t kItemValidationPairs = 2000000;   // keep_best: the diverse validation batch
inline constexpr uint64_t kItemGradPerturbation = 3000000;  // + iteration: grad_samples' perturbations
inline constexpr uint64_t kItemEsPerturbation = 4000000;    // + iteration: es's antithetic perturbations

// ---- connector kinds -----------------------------------------------------------------------------
struct ConnectorKind {
  std::string_view name;
  bool weak;     // stiffness connectors.weak_stiffness (else connectors.strong_stiffness)
  bool diverse;  // trained on random pairs of different agents (else on an agent and its clone)
};
inline constexpr std::array<ConnectorKind, 4> kConnectorKinds = {{{"weak_uniform", true, false},
                                                                 {"weak_diverse", true, true},
                                                                 {"strong_uniform", false, false},
                                                                 {"strong_diverse", false, true}}};

inline std::vector<std::string> connector_kind_names() {
  std::vector<std::string> v;
  for (const ConnectorKind& k : kConnectorKinds) v.emplace_back(k.name);
  return v;
}
// the kind of that name; InputError naming the known ones otherwise
inline const ConnectorKind& connector_kind(std::string_view name) {
  for (const ConnectorKind& k : kConnectorKinds)
    if (k.name == name) return k;
  std::string all;
  for (const ConnectorKind& k : kConnectorKinds) all += (all.empty() ? "" : ", ") + std::string(k.name);
  throw InputError(msg() << "unknown connector kind '" << name << "' (" << all << ")");
}
// the stiffness of a kind, force/u, from the config's [connectors] section
inline double stiffness(const RunConfig::Connectors& c, const ConnectorKind& k) {
  return k.weak ? c.weak_stiffness : c.strong_stiffness;
}
inline double stiffness(const RunConfig::Connectors& c, std::string_view kind) { return stiffness(c, connector_kind(kind)); }
// the stiffness of a strength alone ("weak" or "strong"), as `divcoll scene --connector` names it
inline double strength_stiffness(const RunConfig::Connectors& c, std::string_view strength) {
  if (strength == "weak") return c.weak_stiffness;
  if (strength == "strong") return c.strong_stiffness;
  throw InputError(msg() << "--connector must be weak or strong (got '" << strength << "')");
}

}  // namespace divcoll::config
