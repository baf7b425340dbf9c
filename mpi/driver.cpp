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

namespace {

// one drive() of a plan: its start or resume, its farms of rounds, the rows waiting for a copy, the commits and the
// progress lines
class PlanDrive {
 public:
  PlanDrive(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file, Plan& plan,
            const std::function<void()>& checkpoint)
      : comm_(comm), cfg_(cfg), file_(file), plan_(plan), checkpoint_(checkpoint), info_(plan.info()),
        passes_(info_.passes) {
    MPI_Comm_rank(comm, &rank_);
    MPI_Comm_size(comm, &size_);
  }
  void run();

 private:
  int start();
  void flush();
  void commit(int rounds_done);
  // runs a flush or a commit (which may flush): the time writing rows counts as writes, the rest as commits
  template <class F>
  void timed(const F& f) {
    const auto tc = std::chrono::steady_clock::now();
    records_s_ = 0;
    f();
    clock_.writes_s += records_s_;
    clock_.commits_s += since(tc) - records_s_;
  }
  // the items of rounds r .. r + m - 1 of a plan with independent rounds, farmed together; returns m
  int gather_together(int r, std::vector<std::string>& items, std::vector<int64_t>& first, std::vector<double>& costs,
                      bool& costed);
  // farms round r (each pass), or rounds r .. r + m - 1 together; returns the items farmed
  size_t farm_rounds(int r, int& m);
  // the master: each round's end, with what it warns of on standard error (a plan prints nothing itself)
  void end_round(int step);
  void print_rounds(int r, int m, size_t n_items, std::chrono::steady_clock::time_point t0) const;

  MPI_Comm comm_;
  const io::RunConfig& cfg_;
  io::h5::File& file_;
  Plan& plan_;
  const std::function<void()>& checkpoint_;
  const Plan::Info info_;
  const int passes_;
  int R_ = 0;  // the plan's counted rounds (asked once its setup is written)
  int rank_ = 0, size_ = 1;
  // A round's rows and the state of its commit wait on the master until a commit copies the run file to its
  // checkpoint (or the drive ends): --resume only ever starts from a copy, so rows and state written between
  // copies were never used, and writing them every round made the workers wait for each write. Rows of one
  // dataset from many rounds then go out in one write. With output.checkpoint_interval_s = 0 every commit
  // copies, and every round is written at its commit as before.
  RecordQueue deferred_;
  int pending_done_ = -1;  // the rounds done of the commit not yet written, -1: none
  double records_s_ = 0;   // time in flush() writing rows (reset by timed())
  DriverClock& clock_ = driver_clock();
  std::chrono::steady_clock::time_point t_stage_;
  double last_print_ = -1e9;
};

// writes the plan's attributes and setup rows, reads the round counter and the state committed with it, and
// starts the master's plan from them; returns the rounds done
int PlanDrive::start() {
  const std::string& label = info_.label;
  if (!file_.has(info_.group)) file_.create_group(info_.group);
  io::h5::Node group = file_.group(info_.group);
  for (const Attribute& a : plan_.attributes()) write_attribute(file_, info_.group, a.name, a.value);
  write_records(comm_, file_, rank_ == 0 ? plan_.setup() : Records{});
  R_ = plan_.rounds();
  DIVCOLL_DEMAND(passes_ >= 1);
  const int done = group.has_attribute(info_.counter) ? static_cast<int>(group.read_int(info_.counter)) : 0;

  // where to start: the state committed with the counter. Every rank reads it (a read made by one rank
  // alone unbalances the ranks' HDF5 metadata caches: io/h5.hpp); the master's plan holds it
  StoredState stored;
  if (done > 0) {
    for (const std::string& p : plan_.state_paths()) stored[p] = file_.read<double>(p);
    for (const auto& [name, value] : plan_.state_attributes()) {
      const auto [g, a] = attribute_at(info_.group, name);
      if (file_.has(g) && file_.group(g).has_attribute(a))
        stored[name] = {static_cast<double>(file_.group(g).read_int(a))};
    }
  }
  if (rank_ == 0) {
    plan_.start(done, stored);
    if (done >= R_)
      std::printf("%s: all %d %ss were already done\n", label.c_str(), R_, info_.round_word.c_str());
    else if (done > 0)
      std::printf("%s: resuming after %s %d\n", label.c_str(), info_.round_word.c_str(), done);
  }
  return done;
}

void PlanDrive::flush() {
  const auto tr = std::chrono::steady_clock::now();
  write_records(comm_, file_, rank_ == 0 ? deferred_.take() : Records{});
  records_s_ += since(tr);
  const int done_now = broadcast(comm_, pending_done_);
  if (done_now < 0) return;
  write_records(comm_, file_, rank_ == 0 ? plan_.state() : Records{});
  using Counts = std::vector<std::pair<std::string, int64_t>>;
  for (const auto& [name, value] : broadcast(comm_, rank_ == 0 ? plan_.state_attributes() : Counts{}))
    write_attribute(file_, info_.group, name, value);
  debug_exit_in_commit(comm_, file_, info_.group, info_.counter, done_now);
  file_.group(info_.group).write_int(info_.counter, done_now);
  pending_done_ = -1;
}

void PlanDrive::commit(int rounds_done) {
  pending_done_ = rounds_done;
  // the debug exit sits between this commit's state and counter: they are written now, copy or not
  if (debug_exit_wanted(info_.group, info_.counter, rounds_done)) flush();
  checkpoint_();
}

int PlanDrive::gather_together(int r, std::vector<std::string>& items, std::vector<int64_t>& first,
                               std::vector<double>& costs, bool& costed) {
  int m = 0;
  if (rank_ == 0)
    do {
      const std::string in = plan_.round_input(r + m);
      DIVCOLL_DEMAND(in.empty());
      plan_.take_input(r + m, in);
      std::vector<std::string> more = plan_.items(r + m);
      std::vector<double> c = plan_.item_costs(r + m);
      DIVCOLL_DEMAND(c.empty() || c.size() == more.size());
      costed = costed && !c.empty();
      costs.insert(costs.end(), c.begin(), c.end());
      std::move(more.begin(), more.end(), std::back_inserter(items));
      first.push_back(static_cast<int64_t>(items.size()));
      ++m;
    } while (r + m < R_ && items.size() < kTogetherItemsPerRank * static_cast<size_t>(size_) &&
             !debug_exit_wanted(info_.group, info_.counter, r + m));  // the debug exit's commit stays one
  m = broadcast(comm_, m);
  if (rank_ != 0)
    for (int k = 0; k < m; ++k) plan_.take_input(r + k, std::string());
  return m;
}

void PlanDrive::end_round(int step) {
  deferred_.add(plan_.end_round(step));
  for (const std::string& w : plan_.take_warnings()) std::fprintf(stderr, "%s\n", w.c_str());
}

size_t PlanDrive::farm_rounds(int r, int& m) {
  // the steps of this farm: one pass of round r, or rounds r .. r + m - 1 of a plan with independent rounds
  std::vector<std::string> items;
  std::vector<int64_t> first = {0};  // where each step's items start in `items`
  std::vector<double> costs;         // the plan's cost estimates of `items`, if it gave them for every step
  bool costed = true;
  auto tp = std::chrono::steady_clock::now();
  auto lap = [&](double& into) {
    const auto now = std::chrono::steady_clock::now();
    into += std::chrono::duration<double>(now - tp).count();
    tp = now;
  };
  const bool together = info_.independent_rounds && r < R_;
  m = 1;
  if (together) {
    m = gather_together(r, items, first, costs, costed);
    lap(clock_.items_s);
  }
  size_t n_items = 0;
  for (int pass = 0; pass < passes_; ++pass) {
    const int step = r * passes_ + pass;
    if (!together) {
      plan_.take_input(step, bcast_string(comm_, rank_ == 0 ? plan_.round_input(step) : std::string()));
      lap(clock_.input_s);
      items = rank_ == 0 ? plan_.items(step) : std::vector<std::string>{};
      costs.clear(), costed = true;
      if (rank_ == 0) {
        costs = plan_.item_costs(step);
        DIVCOLL_DEMAND(costs.empty() || costs.size() == items.size());
        costed = !costs.empty();
      }
      first = {0, static_cast<int64_t>(items.size())};
      lap(clock_.items_s);
    }
    n_items += items.size();
    FarmOptions fo;
    if (rank_ == 0 && costed) fo.costs = std::move(costs);  // the farm hands out the dearest first
    size_t at = 0;  // the step of the latest result (results come in item order)
    fo.on_result = [&](int64_t i, const std::string& bytes) {
      while (i >= first[at + 1]) ++at;
      plan_.reduce(together ? r + static_cast<int>(at) : step, i - first[at], bytes);
    };
    fo.progress = [&](int k, int n) {
      const double now = since(t_stage_);
      if (cfg_.run.progress_every_s > 0 && now - last_print_ >= cfg_.run.progress_every_s) {
        last_print_ = now;
        const std::string rounds = m > 1 ? std::to_string(r + 1) + "-" + std::to_string(r + m) : std::to_string(r + 1);
        std::printf("%s: %s %s/%d, %d/%d %s, %.1f s\n", info_.label.c_str(), info_.round_word.c_str(), rounds.c_str(),
                    R_, k, n, info_.item_word.c_str(), now);
        std::fflush(stdout);
      }
    };
    farm(comm_, items, [&](const std::string& b) { return plan_.compute(b); }, fo);
    tp = std::chrono::steady_clock::now();  // farm() keeps its own time (FarmClock::farm_s)
    if (rank_ == 0) {
      if (together)
        for (int k = 0; k < m; ++k) end_round(r + k);
      else
        end_round(step);
    }
    lap(clock_.writes_s);
  }
  return n_items;
}

void PlanDrive::print_rounds(int r, int m, size_t n_items, std::chrono::steady_clock::time_point t0) const {
  if (rank_ != 0) return;
  const double dt = since(t0), el = since(t_stage_);
  for (int k = 0; k < m; ++k)
    std::printf("%s: %s %d/%d: %s; %.0f %s/s, %.0f s, ETA %.0f s\n", info_.label.c_str(), info_.round_word.c_str(),
                r + k + 1, R_, plan_.summary(r + k).c_str(), n_items / dt, info_.item_word.c_str(), el,
                (R_ - r - m) * dt / m);
  std::fflush(stdout);
}

void PlanDrive::run() {
  const int done = start();
  // rank 0 asks for a copy (which writes what waits) once it holds more than this
  constexpr size_t kDeferredMaxBytes = size_t{256} << 20;
  DeferredWrites defer([this] { flush(); }, [this] { return deferred_.bytes() > kDeferredMaxBytes; });
  t_stage_ = std::chrono::steady_clock::now();
  const int end = R_ + (plan_.closing_round() ? 1 : 0);
  DIVCOLL_DEMAND(!info_.independent_rounds || passes_ == 1);
  for (int r = done; r < end;) {
    // the closing round changes the plan's state: a commit still waiting is written with its own state first
    if (r >= R_) timed([this] { flush(); });
    const auto t0 = std::chrono::steady_clock::now();
    int m = 1;
    const size_t n_items = farm_rounds(r, m);
    clock_.rounds += m;
    if (r >= R_) {  // the closing round: recorded, not counted
      timed([this] { flush(); });
      ++r;
      continue;
    }
    // a commit after the last round of this farm if a commit point (every `every` rounds, the last round) lies
    // among its rounds: the state is the state after all of them
    const int every = info_.commit_every > 0 ? info_.commit_every : cfg_.output.checkpoint_every;
    if ((r + m) / every > r / every || r + m == R_) timed([&] { commit(r + m); });
    print_rounds(r, m, n_items, t0);
    r += m;
  }
  timed([this] { flush(); });  // what still waits is written before the stage goes on (its later steps and stages read it)
  write_records(comm_, file_, rank_ == 0 ? plan_.finish() : Records{});
  if (rank_ == 0) {
    const std::string s = plan_.finish_summary();
    if (!s.empty()) std::printf("%s: %s\n", info_.label.c_str(), s.c_str());
    std::fflush(stdout);
  }
}

}  // namespace

void drive(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file, Plan& plan,
           const std::function<void()>& checkpoint) {
  PlanDrive(comm, cfg, file, plan, checkpoint).run();
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
