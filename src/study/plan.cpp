#include "study/plan.hpp"

#include <algorithm>

#include "common/check.hpp"

namespace divcoll::study {
namespace {

// the stages `cfg` runs, as indices into config::stage_names()
std::vector<int> enabled(const config::RunConfig& cfg) {
  std::vector<int> out;
  const auto& names = config::stage_names();
  for (int i = 0; i < static_cast<int>(names.size()); ++i)
    if (config::stage_enabled(cfg, names[i])) out.push_back(i);
  return out;
}

bool has(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

// the leading stages run `r` can take from the earlier run `earlier` of its seed: every one it needs the other
// computed, with the same keys
int shared_stages(const PlannedRun& earlier, const PlannedRun& r) {
  const auto& names = config::stage_names();
  const int S = static_cast<int>(names.size());
  const std::vector<int> mine = enabled(r.cfg), theirs = enabled(earlier.cfg);
  int k = 0;
  while (k < S) {
    if (has(mine, k) && !has(theirs, k)) break;
    if (!config::incompatible_keys(earlier.cfg, r.cfg, k + 1 < S ? names[k + 1] : std::string()).empty()) break;
    ++k;
  }
  return k;
}

// run `r`'s base among the earlier `runs` and the first stage it computes: after the reused ones, at most its
// last stage (which is then recomputed on a copy, so that every run has a stage of its own), never agents
// (--from cannot)
void choose_base(const std::vector<PlannedRun>& runs, PlannedRun& r) {
  int best_k = 0;
  for (int j = 0; j < static_cast<int>(runs.size()); ++j) {
    if (runs[j].seed != r.seed) continue;
    const int k = shared_stages(runs[j], r);
    if (k > best_k) best_k = k, r.base_run = j;
  }
  const std::vector<int> mine = enabled(r.cfg);
  if (r.base_run >= 0 && !mine.empty()) {
    const int from = std::min(best_k, mine.back());
    if (from >= 1) r.from = config::stage_names()[from];
    else r.base_run = -1;
  } else {
    r.base_run = -1;
  }
}

}  // namespace

std::vector<PlannedRun> plan(const Study& s) {
  std::vector<PlannedRun> runs;
  for (std::uint64_t seed : s.seeds)
    for (int v = 0; v < static_cast<int>(s.variants.size()); ++v) {
      const std::vector<std::uint64_t>& only = s.variants[v].seeds;
      if (!only.empty() && std::find(only.begin(), only.end(), seed) == only.end()) continue;
      PlannedRun r;
      r.variant = v;
      r.seed = seed;
      r.overrides = s.scale;
      r.overrides.insert(r.overrides.end(), s.variants[v].set.begin(), s.variants[v].set.end());
      r.overrides.push_back("run.seed=" + std::to_string(seed));
      try {
        r.cfg = config::load_config(s.base, r.overrides);
      } catch (const InputError& e) {
        throw InputError(msg() << "variant " << s.variants[v].name << " (seed " << seed << "): " << e.what());
      }
      r.path = s.variants[v].name + "/seed" + std::to_string(seed) + ".h5";
      choose_base(runs, r);
      runs.push_back(std::move(r));
    }
  return runs;
}

std::vector<int> computed(const config::RunConfig& cfg, const std::string& from) {
  std::vector<int> out;
  const auto& names = config::stage_names();
  const int f = from.empty() ? 0 : static_cast<int>(std::find(names.begin(), names.end(), from) - names.begin());
  for (int i : enabled(cfg))
    if (i >= f) out.push_back(i);
  return out;
}

std::vector<int> computed(const PlannedRun& r) { return computed(r.cfg, r.from); }

std::string stages_text(const std::vector<int>& stages) {
  std::string t;
  for (int k : stages) t += (t.empty() ? "" : ",") + config::stage_names()[k];
  return t;
}

int find_run(const std::vector<PlannedRun>& runs, const std::string& which) {
  if (!which.empty() && std::all_of(which.begin(), which.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const long k = std::stol(which);
    DIVCOLL_THROW_UNLESS(k >= 1 && k <= static_cast<long>(runs.size()),
                         "--run " << which << ": the study has runs 1 to " << runs.size());
    return static_cast<int>(k - 1);
  }
  for (size_t i = 0; i < runs.size(); ++i)
    if (runs[i].path == which || runs[i].path == which + ".h5") return static_cast<int>(i);
  throw InputError(msg() << "--run " << which << ": no such run in the study (give its number or its path, e.g. "
                         << runs.front().path << ")");
}

}  // namespace divcoll::study
