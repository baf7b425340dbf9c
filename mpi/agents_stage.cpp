#include "mpi/agents_stage.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/check.hpp"
#include "io/run_read.hpp"
#include "morph/body.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

using io::h5::Dims;
constexpr int M11 = sim::kAgentMasses, S21 = sim::kAgentSprings;

// one pool row for writing: everything of an Individual plus the selection results
struct Row {
  const evo::Individual* ind = nullptr;
  double uniqueness = 0;
  uint8_t survived = 0;
};

// writes `rows` into group `g` (collective): each rank writes the rows whose owner is its rank
void write_pool(MPI_Comm comm, const io::h5::Node& file, const std::string& g, const std::vector<Row>& rows,
                const std::vector<int>& owner, int rank, int epochs) {
  const hsize_t M = rows.size();
  std::vector<int64_t> mine;
  for (hsize_t i = 0; i < M; ++i)
    if (owner[i] == rank) mine.push_back(static_cast<int64_t>(i));
  auto column = [&](auto get, auto zero, size_t width) {
    std::vector<decltype(zero)> v;
    v.reserve(mine.size() * width);
    for (int64_t i : mine) get(rows[i], v);
    return v;
  };
  const int P = rows.empty() || !rows[0].ind ? 0 : static_cast<int>(rows[0].ind->agent.params.size());
  int P_all = P;
  MPI_Allreduce(MPI_IN_PLACE, &P_all, 1, MPI_INT, MPI_MAX, comm);
  const hsize_t C = static_cast<hsize_t>(epochs) + 1;
  file.write_rows<int64_t>(g + "/id", {M}, mine, column([](const Row& r, auto& v) { v.push_back(r.ind->id); }, int64_t{}, 1));
  file.write_rows<int64_t>(g + "/parent", {M}, mine,
                           column([](const Row& r, auto& v) { v.push_back(r.ind->parent); }, int64_t{}, 1));
  file.write_rows<int64_t>(g + "/cells", {M}, mine,
                           column([](const Row& r, auto& v) { v.push_back(r.ind->agent.cells); }, int64_t{}, 1));
  file.write_rows<int64_t>(g + "/springs", {M}, mine,
                           column([](const Row& r, auto& v) { v.push_back(r.ind->agent.springs); }, int64_t{}, 1));
  auto append = [](auto& v, const auto& src) { v.insert(v.end(), src.begin(), src.end()); };
  file.write_rows<double>(g + "/rest_pos", {M, M11, 2}, mine,
                          column([&](const Row& r, auto& v) { append(v, r.ind->agent.rest_pos); }, double{}, 2 * M11));
  file.write_rows<int32_t>(g + "/spring_i", {M, S21}, mine,
                           column([&](const Row& r, auto& v) { append(v, r.ind->agent.spring_i); }, int32_t{}, S21));
  file.write_rows<int32_t>(g + "/spring_j", {M, S21}, mine,
                           column([&](const Row& r, auto& v) { append(v, r.ind->agent.spring_j); }, int32_t{}, S21));
  file.write_rows<double>(g + "/rest_length", {M, S21}, mine,
                          column([&](const Row& r, auto& v) { append(v, r.ind->agent.rest_length); }, double{}, S21));
  file.write_rows<double>(g + "/amplitude", {M, S21}, mine,
                          column([&](const Row& r, auto& v) { append(v, r.ind->agent.amplitude); }, double{}, S21));
  file.write_rows<double>(g + "/params", {M, static_cast<hsize_t>(P_all)}, mine,
                          column([&](const Row& r, auto& v) { append(v, r.ind->agent.params); }, double{}, P_all));
  file.write_rows<double>(g + "/fitness", {M}, mine,
                          column([](const Row& r, auto& v) { v.push_back(r.ind->train.fitness_bl); }, double{}, 1));
  file.write_rows<double>(g + "/travel_u", {M}, mine,
                          column([](const Row& r, auto& v) { v.push_back(r.ind->train.travel_u); }, double{}, 1));
  file.write_rows<uint8_t>(g + "/status", {M}, mine, column([](const Row& r, auto& v) {
                             v.push_back(static_cast<uint8_t>(r.ind->train.status));
                           }, uint8_t{}, 1));
  file.write_rows<double>(g + "/descriptor", {M, morph::kDescriptorSize}, mine,
                          column([&](const Row& r, auto& v) { append(v, r.ind->descriptor); }, double{},
                                 morph::kDescriptorSize));
  file.write_rows<double>(g + "/curve_u", {M, C}, mine, column([&](const Row& r, auto& v) {
                            for (hsize_t q = 0; q < C; ++q)
                              v.push_back(q < r.ind->train.curve_u.size() ? r.ind->train.curve_u[q]
                                                                          : std::numeric_limits<double>::quiet_NaN());
                          }, double{}, C));
  // selection results: known on the master only
  std::vector<int64_t> master_rows;
  std::vector<double> uniq;
  std::vector<uint8_t> surv;
  if (rank == 0)
    for (hsize_t i = 0; i < M; ++i) {
      master_rows.push_back(static_cast<int64_t>(i));
      uniq.push_back(rows[i].uniqueness);
      surv.push_back(rows[i].survived);
    }
  file.write_rows<double>(g + "/uniqueness", {M}, master_rows, uniq);
  file.write_rows<uint8_t>(g + "/survived", {M}, master_rows, surv);
}

std::string gen_name(const std::string& group, int g) {
  char b[32];
  std::snprintf(b, sizeof b, "/gen_%03d", g);
  return group + b;
}

struct Summary {
  double best = -std::numeric_limits<double>::infinity(), mean = 0;
  int failed = 0;
};
Summary summarize(const std::vector<evo::Individual>& pop) {
  Summary s;
  int n = 0;
  for (const auto& x : pop) {
    if (x.train.status != sim::Status::ok || !std::isfinite(x.train.fitness_bl)) {
      ++s.failed;
      continue;
    }
    s.best = std::max(s.best, x.train.fitness_bl);
    s.mean += x.train.fitness_bl;
    ++n;
  }
  s.mean = n ? s.mean / n : std::numeric_limits<double>::quiet_NaN();
  return s;
}

}  // namespace

void run_agents_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                      const std::function<void()>& checkpoint) {
  run_agents_stage(comm, cfg, file, checkpoint, AgentsSpec{});
}

void run_agents_stage(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file,
                      const std::function<void()>& checkpoint, const AgentsSpec& spec) {
  const std::string& G = spec.group;
  const char* label = spec.label.c_str();
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const auto& A = cfg.agents;
  const int P = A.population;
  evo::GdOptions gd;
  gd.epochs = A.epochs;
  gd.steps = A.episode_steps;
  gd.rule = evo::gd_rule_from(A.gd_rule);
  gd.step = A.gd_step;
  gd.adam_lr = A.adam_lr;
  gd.rest_moves = A.rest_moves;
  gd.rest_move_max = A.rest_move_max;
  gd.rest_length_min = A.rest_length_min;
  gd.rest_length_max = A.rest_length_max;
  evo::MutationOptions mut;
  mut.body_flip_p = A.body_flip_p;
  mut.spring_flip_p = A.spring_flip_p;
  mut.rest_jitter_sd = A.rest_jitter_sd;
  mut.body_fixed = A.body_fixed;
  mut.springs_fixed = A.springs_fixed;
  mut.rest_moves = A.rest_moves;

  // where to start: after the last complete generation in the file
  int64_t done = file.has(G) && file.group(G).has_attribute("generations_done")
                     ? file.group(G).read_int("generations_done")
                     : 0;
  if (done == 0) {
    if (!file.has(G)) file.create_group(G);
  }
  // a generation that was being written when the run stopped is dropped and redone
  for (int g = static_cast<int>(done); g <= A.generations + 1; ++g)
    if (file.has(gen_name(G, g))) H5Ldelete(file.id(), gen_name(G, g).c_str(), H5P_DEFAULT);
  if (file.has(G + "/final") && done < A.generations + 1) H5Ldelete(file.id(), (G + "/final").c_str(), H5P_DEFAULT);
  io::h5::Node stage = file.group(G);
  stage.write_string("status", "running");
  stage.write_int("population", P);

  // the master's population (rank 0 only)
  std::vector<evo::Individual> population;
  if (done > 0 && rank == 0) {
    std::vector<uint8_t> survived;
    const auto pool = io::read_pool(file, gen_name(G, static_cast<int>(done) - 1), &survived);
    for (size_t i = 0; i < pool.size(); ++i)
      if (survived[i]) population.push_back(pool[i]);
    DIVCOLL_THROW_UNLESS(static_cast<int>(population.size()) == P,
                         file.file() << ": generation " << done - 1 << " has " << population.size()
                                     << " survivors, not agents.population = " << P
                                     << " (was the run started with another config?)");
    if (done > A.generations)
      std::printf("%s: all generations were already done; checking the final population\n", label);
    else
      std::printf("%s: resuming after generation %lld\n", label, static_cast<long long>(done - 1));
  }

  // the work item: train one agent (created or mutated on the master)
  sim::Simulator sim;
  auto train = [&](const std::string& bytes) {
    evo::Individual x = unpack<evo::Individual>(bytes);
    x.train = evo::train_agent(x.agent, gd, sim);
    x.descriptor = spec.spring_descriptor ? evo::spring_layout_descriptor(x.agent) : evo::agent_descriptor(x.agent);
    return pack(x);
  };
  const auto t_stage = std::chrono::steady_clock::now();
  double last_print = -1e9;
  for (int g = static_cast<int>(done); g <= A.generations; ++g) {
    const auto t0 = std::chrono::steady_clock::now();
    // tasks: generation 0 creates random agents, later ones mutate every parent
    std::vector<std::string> tasks;
    if (rank == 0) {
      for (int i = 0; i < P; ++i) {
        Rng rng = make_rng(cfg.run.seed, spec.stream + g, i);
        evo::Individual x;
        if (g == 0) {
          x.agent = spec.fixed_cells ? collective::make_agent(spec.fixed_cells,
                                                              spec.fixed_springs ? spec.fixed_springs : morph::random_springs(rng), rng)
                                     : collective::random_agent(rng);
          x.id = i;
        } else {
          x.agent = evo::make_offspring(population[i].agent, rng, mut, gd);
          x.id = static_cast<int64_t>(g) * P + i;
          x.parent = population[i].id;
        }
        tasks.push_back(pack(x));
      }
    }
    FarmOptions fo;
    fo.master_works = true;
    fo.progress = [&](int k, int n) {
      const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count();
      if (cfg.run.progress_every_s > 0 && now - last_print >= cfg.run.progress_every_s) {
        last_print = now;
        std::printf("%s: generation %d/%d, trained %d/%d, %.1f s\n", label, g, A.generations, k, n, now);
        std::fflush(stdout);
      }
    };
    const FarmResult fr = farm(comm, tasks, train, fo);

    // the pool: parents (held by the master) then the new agents (held by whoever trained them)
    const int off = g == 0 ? 0 : P;
    std::vector<evo::Individual> pool(off + P);
    std::vector<int> owner(off + P, 0);
    for (int i = 0; i < off; ++i)
      if (rank == 0) pool[i] = population[i];
    for (int i = 0; i < P; ++i) {
      owner[off + i] = fr.owner[i];
      if (!fr.results[i].empty()) pool[off + i] = unpack<evo::Individual>(fr.results[i]);
    }
    // selection on the master
    std::vector<Row> rows(pool.size());
    for (size_t i = 0; i < pool.size(); ++i) rows[i].ind = &pool[i];
    if (rank == 0) {
      std::vector<double> uniq;
      const std::vector<int> keep = evo::select_survivors(pool, P, A.uniqueness_k, &uniq, A.selection == "rank");
      std::vector<evo::Individual> next;
      for (int i : keep) rows[i].survived = 1, next.push_back(pool[i]);
      for (size_t i = 0; i < pool.size(); ++i) rows[i].uniqueness = uniq[i];
      population = std::move(next);
    }
    write_pool(comm, file, gen_name(G, g), rows, owner, rank, A.epochs);
    stage.write_int("generations_done", g + 1);
    if ((g + 1) % cfg.output.checkpoint_every == 0) checkpoint();

    if (rank == 0) {
      const Summary s = summarize(population);
      const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stage).count();
      const int left = A.generations - g;
      std::printf("%s: generation %d/%d done: best %.3f BL, mean %.3f BL%s, %.1f agents/s, %.1f s, ETA %.0f s\n", label, g,
                  A.generations, s.best, s.mean, s.failed ? " (some failed)" : "", P / dt, el,
                  left * dt);
      std::fflush(stdout);
    }
  }

  // the final population, for the later stages
  std::vector<Row> rows(P);
  std::vector<int> owner(P, 0);
  for (int i = 0; i < P; ++i) {
    rows[i].ind = rank == 0 ? &population[i] : nullptr;
    rows[i].survived = 1;
  }
  if (rank != 0) {
    // workers hold no final rows; give write_pool empty placeholders it never reads
    static const evo::Individual empty;
    for (auto& r : rows) r.ind = &empty;
  }
  if (!file.has(G + "/final")) {
    if (rank == 0) {
      std::vector<double> uniq;
      std::vector<evo::Individual> pop = population;
      evo::select_survivors(pop, P, A.uniqueness_k, &uniq, A.selection == "rank");
      for (int i = 0; i < P; ++i) rows[i].uniqueness = uniq[i];
    }
    write_pool(comm, file, G + "/final", rows, owner, rank, A.epochs);
  }
  stage.write_int("generations_done", A.generations + 1);
  stage.write_string("status", "complete");
  checkpoint();
}

}  // namespace divcoll::mpi
