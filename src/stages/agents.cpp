#include "stages/agents.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "io/run_read.hpp"
#include "morph/body.hpp"
#include "stages/payload.hpp"

namespace divcoll::stages {
namespace {

constexpr int M11 = sim::kAgentMasses, S21 = sim::kAgentSprings;

// one pool row for writing: everything of an Individual plus the selection results
struct Row {
  const evo::Individual* ind = nullptr;
  double uniqueness = 0;
  uint8_t survived = 0;
};

// the rows of group `g`: one per candidate
Records pool_records(const std::string& g, const std::vector<Row>& rows, int epochs) {
  const uint64_t M = rows.size();
  std::vector<int64_t> all(M);
  for (uint64_t i = 0; i < M; ++i) all[i] = static_cast<int64_t>(i);
  size_t P = 0;
  for (const Row& r : rows) P = std::max(P, r.ind->agent.params.size());
  const uint64_t C = static_cast<uint64_t>(epochs) + 1;
  Records out;
  // a column of every row: `get` appends a row's values
  auto column = [&](const std::string& name, std::vector<uint64_t> dims, auto zero, auto get) {
    std::vector<decltype(zero)> v;
    for (const Row& r : rows) get(r, v);
    dims.insert(dims.begin(), M);
    out.push_back({g + "/" + name, dims, all, std::move(v)});
  };
  auto append = [](auto& v, const auto& src) { v.insert(v.end(), src.begin(), src.end()); };
  using Int = int64_t (*)(const evo::Individual&);
  for (const auto& [name, get] : {std::pair<const char*, Int>{"id", [](const evo::Individual& x) -> int64_t { return x.id; }},
                                  {"parent", [](const evo::Individual& x) -> int64_t { return x.parent; }},
                                  {"cells", [](const evo::Individual& x) -> int64_t { return x.agent.cells; }},
                                  {"springs", [](const evo::Individual& x) -> int64_t { return x.agent.springs; }}})
    column(name, {}, int64_t{}, [get = get](const Row& r, auto& v) { v.push_back(get(*r.ind)); });
  column("rest_pos", {M11, 2}, double{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.rest_pos); });
  column("spring_i", {S21}, int32_t{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.spring_i); });
  column("spring_j", {S21}, int32_t{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.spring_j); });
  column("rest_length", {S21}, double{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.rest_length); });
  column("amplitude", {S21}, double{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.amplitude); });
  column("params", {P}, double{}, [&](const Row& r, auto& v) { append(v, r.ind->agent.params); });
  column("fitness", {}, double{}, [](const Row& r, auto& v) { v.push_back(r.ind->train.fitness_bl); });
  column("travel_u", {}, double{}, [](const Row& r, auto& v) { v.push_back(r.ind->train.travel_u); });
  column("status", {}, uint8_t{}, [](const Row& r, auto& v) { v.push_back(static_cast<uint8_t>(r.ind->train.status)); });
  column("descriptor", {morph::kDescriptorSize}, double{}, [&](const Row& r, auto& v) { append(v, r.ind->descriptor); });
  column("curve_u", {C}, double{}, [&](const Row& r, auto& v) {
    for (uint64_t q = 0; q < C; ++q)
      v.push_back(q < r.ind->train.curve_u.size() ? r.ind->train.curve_u[q] : std::numeric_limits<double>::quiet_NaN());
  });
  column("uniqueness", {}, double{}, [](const Row& r, auto& v) { v.push_back(r.uniqueness); });
  column("survived", {}, uint8_t{}, [](const Row& r, auto& v) { v.push_back(r.survived); });
  return out;
}

// a trained agent, and how long its training took (seconds of compute(): only to hand out the next
// generation's dearest items first, never recorded)
struct Trained {
  evo::Individual x;
  double train_s = 0;
};
template <class Ar>
void serialize(Ar& ar, Trained& t, unsigned) {
  ar & t.x & t.train_s;
}

// the agents stage (SPEC §4) as a plan: one round per generation (0 .. agents.generations), one item per
// agent trained (created or mutated on the master); the master's selection is the round's reduction
class AgentsPlan final : public Plan {
 public:
  AgentsPlan(const AgentsDef& def, const AgentsSpec& spec, std::vector<evo::Individual> population)
      : def_(def), A_(def_.agents), spec_(spec), P_(A_.population), gd_(evo::gd_options(A_)),
        mut_(evo::mutation_options(A_)), population_(std::move(population)) {}
  Info info() const override { return {spec_.label, spec_.group, "generations_done", "generation", "agents", 0}; }
  int rounds() const override { return A_.generations + 1; }
  std::vector<Attribute> attributes() const override { return {{"population", int64_t{P_}}}; }
  void start(int, const StoredState&) override {}  // the population of the last committed generation came with the plan
  std::vector<std::string> items(int g) override {
    std::vector<std::string> tasks;
    for (int i = 0; i < P_; ++i) {
      Rng rng = make_rng(def_.seed, spec_.stream + g, i);
      evo::Individual x;
      if (g == 0) {
        x.agent = spec_.fixed_cells ? collective::make_agent(spec_.fixed_cells,
                                                             spec_.fixed_springs ? spec_.fixed_springs : morph::random_springs(rng), rng)
                                    : collective::random_agent(rng);
        x.id = i;
      } else {
        x.agent = evo::make_offspring(population_[i].agent, rng, mut_, gd_);
        x.id = static_cast<int64_t>(g) * P_ + i;
        x.parent = population_[i].id;
      }
      tasks.push_back(pack(x));
    }
    trained_.assign(P_, {});
    trained_s_.assign(P_, 0.0);
    return tasks;
  }
  // an offspring trains about as long as its parent did (contacts, the body); generation 0 and the first
  // generation after a resume have no times
  std::vector<double> item_costs(int g) const override {
    if (g == 0 || static_cast<int>(parent_s_.size()) != P_) return {};
    for (double s : parent_s_)
      if (!(s > 0)) return {};  // a parent from before a resume
    return parent_s_;
  }
  std::string compute(const std::string& bytes) override {
    const auto t0 = std::chrono::steady_clock::now();
    Trained t{unpack<evo::Individual>(bytes)};
    t.x.train = evo::train_agent(t.x.agent, gd_, def_.physics, sim_);
    t.x.descriptor = spec_.spring_descriptor ? evo::spring_layout_descriptor(t.x.agent) : evo::agent_descriptor(t.x.agent);
    t.train_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return pack(t);
  }
  void reduce(int, int64_t i, const std::string& bytes) override {
    Trained t = unpack<Trained>(bytes);
    trained_[i] = std::move(t.x);
    trained_s_[i] = t.train_s;
  }
  // the pool (parents, then the new agents), its selection, and its rows
  Records end_round(int g) override {
    std::vector<evo::Individual> pool = g == 0 ? std::vector<evo::Individual>{} : population_;
    for (const auto& x : trained_)  // numerical trouble, said where it happened (its training stopped there)
      if (x.train.nonfinite_gradient_epoch >= 0)
        warnings_.push_back(spec_.label + ": generation " + std::to_string(g) + ": agent " + std::to_string(x.id) +
                            ": gradient not finite at epoch " + std::to_string(x.train.nonfinite_gradient_epoch) +
                            " of " + std::to_string(A_.epochs) + "; its training stopped there");
    for (auto& x : trained_) pool.push_back(std::move(x));
    // training times beside the pool (a parent's unknown after a resume: 0)
    std::vector<double> pool_s(pool.size() - trained_s_.size(), 0.0);
    if (parent_s_.size() == pool_s.size()) pool_s = parent_s_;
    pool_s.insert(pool_s.end(), trained_s_.begin(), trained_s_.end());
    std::vector<Row> rows(pool.size());
    for (size_t i = 0; i < pool.size(); ++i) rows[i].ind = &pool[i];
    std::vector<double> uniq;
    const std::vector<int> keep = evo::select_survivors(pool, P_, A_.uniqueness_k, &uniq, A_.selection == "rank");
    std::vector<evo::Individual> next;
    parent_s_.clear();
    for (int i : keep) rows[i].survived = 1, next.push_back(pool[i]), parent_s_.push_back(pool_s[i]);
    for (size_t i = 0; i < pool.size(); ++i) rows[i].uniqueness = uniq[i];
    Records out = pool_records(gen_name(spec_.group, g), rows, A_.epochs);
    population_ = std::move(next);
    return out;
  }
  std::vector<std::string> take_warnings() override { return std::exchange(warnings_, {}); }
  std::string summary(int) const override {
    double best = -std::numeric_limits<double>::infinity(), mean = 0;
    int n = 0, failed = 0;
    for (const auto& x : population_) {
      if (x.train.status != sim::Status::ok || !std::isfinite(x.train.fitness_bl)) {
        ++failed;
        continue;
      }
      best = std::max(best, x.train.fitness_bl);
      mean += x.train.fitness_bl;
      ++n;
    }
    char b[160];
    std::snprintf(b, sizeof b, "best %.3f BL, mean %.3f BL%s", best, n ? mean / n : NAN, failed ? " (some failed)" : "");
    return b;
  }
  // the final population, for the later stages
  Records finish() override {
    std::vector<double> uniq;
    std::vector<evo::Individual> pop = population_;
    evo::select_survivors(pop, P_, A_.uniqueness_k, &uniq, A_.selection == "rank");
    std::vector<Row> rows(P_);
    for (int i = 0; i < P_; ++i) rows[i] = {&population_[i], uniq[i], 1};
    return pool_records(spec_.group + "/final", rows, A_.epochs);
  }

 private:
  const AgentsDef def_;
  const config::RunConfig::Agents& A_;
  const AgentsSpec spec_;
  const int P_;
  evo::GdOptions gd_;
  evo::MutationOptions mut_;
  std::vector<evo::Individual> population_;  // the master's survivors
  std::vector<evo::Individual> trained_;     // the round's new agents, in item order
  std::vector<double> trained_s_;            // their training times (s)
  std::vector<double> parent_s_;             // the survivors' training times (s), when known
  std::vector<std::string> warnings_;        // of the last end_round
  sim::Simulator sim_;
};

}  // namespace

std::string gen_name(const std::string& group, int g) {
  char b[32];
  std::snprintf(b, sizeof b, "/gen_%03d", g);
  return group + b;
}

AgentsDef agents_def(const config::RunConfig& cfg) { return {cfg.run.seed, cfg.agents, config::run_physics(cfg)}; }

std::unique_ptr<Plan> make_agents_plan(const AgentsDef& def, const AgentsSpec& spec,
                                       std::vector<evo::Individual> population) {
  return std::make_unique<AgentsPlan>(def, spec, std::move(population));
}

void run_agents_stage(Driver& driver) { run_agents(driver, agents_def(driver.config()), AgentsSpec{}); }

void run_agents(Driver& driver, const AgentsDef& def, const AgentsSpec& spec) {
  io::h5::File& file = driver.file();
  const std::string& G = spec.group;
  const auto& A = def.agents;
  const int P = A.population;
  // the committed generations; one that was being written when the run stopped is dropped and redone
  const int64_t done = file.has(G) && file.group(G).has_attribute("generations_done")
                           ? file.group(G).read_int("generations_done")
                           : 0;
  for (int g = static_cast<int>(done); g <= A.generations + 1; ++g) file.remove(gen_name(G, g));
  if (done < A.generations + 1) file.remove(G + "/final");
  // the master's population: the survivors of the last committed generation
  // (read on every rank: a read made by one rank alone unbalances the ranks' HDF5 metadata caches, io/h5.hpp)
  std::vector<evo::Individual> population;
  if (done > 0) {
    std::vector<uint8_t> survived;
    const auto pool = io::read_pool(file, gen_name(G, static_cast<int>(done) - 1), &survived);
    for (size_t i = 0; i < pool.size(); ++i)
      if (survived[i]) population.push_back(pool[i]);
    DIVCOLL_THROW_UNLESS(static_cast<int>(population.size()) == P,
                         file.file() << ": generation " << done - 1 << " has " << population.size()
                                     << " survivors, not agents.population = " << P
                                     << " (was the run started with another config?)");
    if (!driver.master()) population.clear();
  }
  AgentsPlan plan(def, spec, std::move(population));
  driver.drive(plan);
}

}  // namespace divcoll::stages
