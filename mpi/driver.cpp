#include "mpi/driver.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <map>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>

#include <boost/serialization/utility.hpp>

#include "common/check.hpp"
#include "mpi/checkpoint.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

// what every rank must know of a record to take part in its write
struct RecordHead {
  std::string path;
  std::vector<uint64_t> dims;
  int32_t type = 0;  // index into Record::values
};
template <class Ar>
void serialize(Ar& ar, RecordHead& h, unsigned) {
  ar & h.path & h.dims & h.type;
}

std::string bcast_string(MPI_Comm comm, const std::string& s) { return broadcast(comm, s); }

// DIVCOLL_DEBUG_EXIT_IN_COMMIT=<group>:<done> (or <group>@<counter>:<done>, where plans share a group):
// every rank flushes the file and exits between the state and the counter of that commit (a kill placed by
// the program itself, for tests/mpi/commit_kill_test.sh)
bool debug_exit_wanted(const std::string& group, const std::string& counter, int done) {
  const char* e = std::getenv("DIVCOLL_DEBUG_EXIT_IN_COMMIT");
  if (!e) return false;
  const std::string want = std::string(e), at = std::to_string(done);
  return want == group + ':' + at || want == group + '@' + counter + ':' + at;
}

void debug_exit_in_commit(MPI_Comm comm, const io::h5::File& file, const std::string& group, const std::string& counter,
                          int done) {
  if (!debug_exit_wanted(group, counter, done)) return;
  H5Fflush(file.id(), H5F_SCOPE_GLOBAL);
  MPI_Barrier(comm);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) std::printf("debug: exit between the state and the counter of %s, %d rounds done\n", group.c_str(), done);
  std::fflush(stdout);
  std::_Exit(86);
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

void RecordQueue::add(Records records) {
  for (Record& r : records) {
    const size_t size = std::visit([](const auto& v) { return v.size() * sizeof(v[0]); }, r.values);
    bytes_ += size;
    auto it = index_.find(r.path);
    if (it == index_.end()) {
      index_.emplace(r.path, waiting_.size());
      waiting_.push_back(std::move(r));
      continue;
    }
    Record& w = waiting_[it->second];
    DIVCOLL_DEMAND(w.dims == r.dims && w.values.index() == r.values.index());
    std::visit(
        [&](auto& into) {
          const auto& from = std::get<std::decay_t<decltype(into)>>(r.values);
          const size_t width = r.rows.empty() ? 0 : from.size() / r.rows.size();
          for (size_t k = 0; k < r.rows.size(); ++k) {
            const auto at = std::find(w.rows.begin(), w.rows.end(), r.rows[k]);
            if (at != w.rows.end()) {
              std::copy_n(from.begin() + k * width, width, into.begin() + (at - w.rows.begin()) * width);
            } else {
              w.rows.push_back(r.rows[k]);
              into.insert(into.end(), from.begin() + k * width, from.begin() + (k + 1) * width);
            }
          }
        },
        w.values);
  }
}

Records RecordQueue::take() {
  Records out = std::move(waiting_);
  waiting_.clear();
  index_.clear();
  bytes_ = 0;
  return out;
}

void write_records(MPI_Comm comm, const io::h5::Node& file, const Records& records) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::vector<RecordHead> heads;
  if (rank == 0)
    for (const Record& r : records) heads.push_back({r.path, r.dims, static_cast<int32_t>(r.values.index())});
  heads = broadcast(comm, heads);
  for (size_t i = 0; i < heads.size(); ++i) {
    const RecordHead& h = heads[i];
    const io::h5::Dims dims(h.dims.begin(), h.dims.end());
    static const std::vector<int64_t> none;
    const std::vector<int64_t>& rows = rank == 0 ? records[i].rows : none;
    auto write = [&](auto zero) {
      using T = decltype(zero);
      static const std::vector<T> empty;
      file.write_rows<T>(h.path, dims, rows, rank == 0 ? std::get<std::vector<T>>(records[i].values) : empty);
    };
    switch (h.type) {
      case 0: write(double{}); break;
      case 1: write(int64_t{}); break;
      case 2: write(int32_t{}); break;
      case 3: write(uint8_t{}); break;
      default: write(float{}); break;
    }
  }
}

namespace {

// the group and the attribute name of a plan's attribute `name` (relative to `group`; '/' names a subgroup)
std::pair<std::string, std::string> attribute_at(const std::string& group, const std::string& name) {
  const size_t slash = name.rfind('/');
  if (slash == std::string::npos) return {group, name};
  return {group + "/" + name.substr(0, slash), name.substr(slash + 1)};
}

void write_attribute(const io::h5::File& file, const std::string& group, const std::string& name,
                     const std::variant<std::string, int64_t>& value) {
  const auto [g, a] = attribute_at(group, name);
  if (!file.has(g)) file.create_group(g);
  if (const auto* text = std::get_if<std::string>(&value)) file.group(g).write_string(a, *text);
  else file.group(g).write_int(a, std::get<int64_t>(value));
}

}  // namespace

DriverClock& driver_clock() {
  static DriverClock clock;
  return clock;
}

void drive(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file, Plan& plan,
           const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const Plan::Info info = plan.info();
  const std::string& label = info.label;
  if (!file.has(info.group)) file.create_group(info.group);
  io::h5::Node group = file.group(info.group);
  for (const Attribute& a : plan.attributes()) write_attribute(file, info.group, a.name, a.value);
  write_records(comm, file, rank == 0 ? plan.setup() : Records{});
  const int R = plan.rounds(), passes = info.passes;
  DIVCOLL_DEMAND(passes >= 1);
  const int done = group.has_attribute(info.counter) ? static_cast<int>(group.read_int(info.counter)) : 0;

  // where to start: the state committed with the counter. Every rank reads it (a read made by one rank
  // alone unbalances the ranks' HDF5 metadata caches: io/h5.hpp); the master's plan holds it
  StoredState stored;
  if (done > 0) {
    for (const std::string& p : plan.state_paths()) stored[p] = file.read<double>(p);
    for (const auto& [name, value] : plan.state_attributes()) {
      const auto [g, a] = attribute_at(info.group, name);
      if (file.has(g) && file.group(g).has_attribute(a))
        stored[name] = {static_cast<double>(file.group(g).read_int(a))};
    }
  }
  if (rank == 0) {
    plan.start(done, stored);
    if (done >= R)
      std::printf("%s: all %d %ss were already done\n", label.c_str(), R, info.round_word.c_str());
    else if (done > 0)
      std::printf("%s: resuming after %s %d\n", label.c_str(), info.round_word.c_str(), done);
  }
  // A round's rows and the state of its commit wait on the master until a commit copies the run file to its
  // checkpoint (or the drive ends): --resume only ever starts from a copy, so rows and state written between
  // copies were never used, and writing them every round made the workers wait for each write. Rows of one
  // dataset from many rounds then go out in one write. With output.checkpoint_interval_s = 0 every commit
  // copies, and every round is written at its commit as before.
  RecordQueue deferred;
  int pending_done = -1;  // the rounds done of the commit not yet written, -1: none
  double records_s = 0;   // time in flush() writing rows (reset by `timed` below)
  auto flush = [&] {
    const auto tr = std::chrono::steady_clock::now();
    write_records(comm, file, rank == 0 ? deferred.take() : Records{});
    records_s += since(tr);
    const int done_now = broadcast(comm, pending_done);
    if (done_now < 0) return;
    write_records(comm, file, rank == 0 ? plan.state() : Records{});
    using Counts = std::vector<std::pair<std::string, int64_t>>;
    for (const auto& [name, value] : broadcast(comm, rank == 0 ? plan.state_attributes() : Counts{}))
      write_attribute(file, info.group, name, value);
    debug_exit_in_commit(comm, file, info.group, info.counter, done_now);
    group.write_int(info.counter, done_now);
    pending_done = -1;
  };
  // rank 0 asks for a copy (which writes what waits) once it holds more than this
  constexpr size_t kDeferredMaxBytes = size_t{256} << 20;
  DeferredWrites defer(flush, [&] { return deferred.bytes() > kDeferredMaxBytes; });
  auto commit = [&](int rounds_done) {
    pending_done = rounds_done;
    // the debug exit sits between this commit's state and counter: they are written now, copy or not
    if (debug_exit_wanted(info.group, info.counter, rounds_done)) flush();
    checkpoint();
  };

  DriverClock& clock = driver_clock();
  // runs a flush or a commit (which may flush): the time writing rows counts as writes, the rest as commits
  auto timed = [&](const auto& f) {
    const auto tc = std::chrono::steady_clock::now();
    records_s = 0;
    f();
    clock.writes_s += records_s;
    clock.commits_s += since(tc) - records_s;
  };

  const auto t_stage = std::chrono::steady_clock::now();
  double last_print = -1e9;
  const int end = R + (plan.closing_round() ? 1 : 0);
  int size = 1;
  MPI_Comm_size(comm, &size);
  DIVCOLL_DEMAND(!info.independent_rounds || passes == 1);
  for (int r = done; r < end;) {
    // the closing round changes the plan's state: a commit still waiting is written with its own state first
    if (r >= R) timed(flush);
    const auto t0 = std::chrono::steady_clock::now();
    // the steps of this farm: one pass of round r, or rounds r .. r + m - 1 of a plan with independent rounds
    std::vector<std::string> items;
    std::vector<int64_t> first = {0};  // where each step's items start in `items`
    std::vector<double> costs;         // the plan's cost estimates of `items`, if it gave them for every step
    bool costed = true;
    auto add_costs = [&](int step, size_t count) {
      std::vector<double> c = plan.item_costs(step);
      DIVCOLL_DEMAND(c.empty() || c.size() == count);
      costed = costed && !c.empty();
      costs.insert(costs.end(), c.begin(), c.end());
    };
    int m = 0;
    auto tp = std::chrono::steady_clock::now();
    auto lap = [&](double& into) {
      const auto now = std::chrono::steady_clock::now();
      into += std::chrono::duration<double>(now - tp).count();
      tp = now;
    };
    const bool together = info.independent_rounds && r < R;
    if (together) {
      if (rank == 0)
        do {
          const std::string in = plan.round_input(r + m);
          DIVCOLL_DEMAND(in.empty());
          plan.take_input(r + m, in);
          std::vector<std::string> more = plan.items(r + m);
          add_costs(r + m, more.size());
          std::move(more.begin(), more.end(), std::back_inserter(items));
          first.push_back(static_cast<int64_t>(items.size()));
          ++m;
        } while (r + m < R && items.size() < kTogetherItemsPerRank * static_cast<size_t>(size) &&
                 !debug_exit_wanted(info.group, info.counter, r + m));  // the debug exit's commit stays one
      m = broadcast(comm, m);
      if (rank != 0)
        for (int k = 0; k < m; ++k) plan.take_input(r + k, std::string());
      lap(clock.items_s);
    } else {
      m = 1;
    }
    size_t n_items = 0;
    for (int pass = 0; pass < passes; ++pass) {
      const int step = r * passes + pass;
      if (!together) {
        plan.take_input(step, bcast_string(comm, rank == 0 ? plan.round_input(step) : std::string()));
        lap(clock.input_s);
        items = rank == 0 ? plan.items(step) : std::vector<std::string>{};
        costs.clear(), costed = true;
        if (rank == 0) add_costs(step, items.size());
        first = {0, static_cast<int64_t>(items.size())};
        lap(clock.items_s);
      }
      n_items += items.size();
      FarmOptions fo;
      if (rank == 0 && costed) fo.costs = std::move(costs);  // the farm hands out the dearest first
      size_t at = 0;  // the step of the latest result (results come in item order)
      fo.on_result = [&](int64_t i, const std::string& bytes) {
        while (i >= first[at + 1]) ++at;
        plan.reduce(together ? r + static_cast<int>(at) : step, i - first[at], bytes);
      };
      fo.progress = [&](int k, int n) {
        const double now = since(t_stage);
        if (cfg.run.progress_every_s > 0 && now - last_print >= cfg.run.progress_every_s) {
          last_print = now;
          const std::string rounds = m > 1 ? std::to_string(r + 1) + "-" + std::to_string(r + m) : std::to_string(r + 1);
          std::printf("%s: %s %s/%d, %d/%d %s, %.1f s\n", label.c_str(), info.round_word.c_str(), rounds.c_str(), R, k,
                      n, info.item_word.c_str(), now);
          std::fflush(stdout);
        }
      };
      farm(comm, items, [&](const std::string& b) { return plan.compute(b); }, fo);
      tp = std::chrono::steady_clock::now();  // farm() keeps its own time (FarmClock::farm_s)
      if (rank == 0) {
        if (together)
          for (int k = 0; k < m; ++k) deferred.add(plan.end_round(r + k));
        else
          deferred.add(plan.end_round(step));
      }
      lap(clock.writes_s);
    }
    clock.rounds += m;
    if (r >= R) {  // the closing round: recorded, not counted
      timed(flush);
      ++r;
      continue;
    }
    // a commit after the last round of this farm if a commit point (every `every` rounds, the last round) lies
    // among its rounds: the state is the state after all of them
    const int every = info.commit_every > 0 ? info.commit_every : cfg.output.checkpoint_every;
    if ((r + m) / every > r / every || r + m == R) timed([&] { commit(r + m); });
    if (rank == 0) {
      const double dt = since(t0), el = since(t_stage);
      for (int k = 0; k < m; ++k)
        std::printf("%s: %s %d/%d: %s; %.0f %s/s, %.0f s, ETA %.0f s\n", label.c_str(), info.round_word.c_str(),
                    r + k + 1, R, plan.summary(r + k).c_str(), n_items / dt, info.item_word.c_str(), el,
                    (R - r - m) * dt / m);
      std::fflush(stdout);
    }
    r += m;
  }
  timed(flush);  // what still waits is written before the stage goes on (its later steps and stages read it)
  write_records(comm, file, rank == 0 ? plan.finish() : Records{});
  if (rank == 0) {
    const std::string s = plan.finish_summary();
    if (!s.empty()) std::printf("%s: %s\n", label.c_str(), s.c_str());
    std::fflush(stdout);
  }
}

bool run_with_status(io::h5::File& file, const std::string& group, const std::function<void()>& checkpoint,
                     const std::function<void()>& body) {
  if (complete(file, group)) return false;
  if (!file.has(group)) file.create_group(group);
  file.group(group).write_string("status", "running");
  body();
  file.group(group).write_string("status", "complete");
  checkpoint();
  return true;
}

MpiDriver::MpiDriver(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file, const std::function<void()>& checkpoint)
    : comm_(comm), cfg_(cfg), file_(file), checkpoint_(checkpoint) {
  MPI_Comm_rank(comm, &rank_);
}

void MpiDriver::drive(Plan& plan) { mpi::drive(comm_, cfg_, file_, plan, checkpoint_); }

std::string MpiDriver::broadcast(const std::string& bytes) { return mpi::broadcast(comm_, bytes); }

void MpiDriver::write(const Records& records) { write_records(comm_, file_, records); }

bool MpiDriver::with_status(const std::string& group, const std::function<void()>& body) {
  return run_with_status(file_, group, checkpoint_, body);
}

}  // namespace divcoll::mpi
