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
#include "stages/schedule.hpp"

namespace divcoll::mpi {

using stages::FarmCall;
using stages::FarmHead;
using stages::Schedule;

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

// writes the plan's attributes and the rows it draws once, reads the rounds done and the state committed with
// them, and starts the master's plan from there; returns the rounds done
int start_plan(MPI_Comm comm, io::h5::File& file, const io::h5::Node& group, Plan& plan, const Plan::Info& info,
               int rank) {
  for (const Attribute& a : plan.attributes()) write_attribute(file, info.group, a.name, a.value);
  write_records(comm, file, rank == 0 ? plan.setup() : Records{});
  const int R = plan.rounds();
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
      std::printf("%s: all %d %ss were already done\n", info.label.c_str(), R, info.round_word.c_str());
    else if (done > 0)
      std::printf("%s: resuming after %s %d\n", info.label.c_str(), info.round_word.c_str(), done);
  }
  return done;
}

// A plan's rows and commits. A round's rows and the state of its commit wait on the master until a commit copies
// the run file to its checkpoint (or the drive ends): --resume only ever starts from a copy, so rows and state
// written between copies were never used, and writing them every round made the workers wait for each write.
// Rows of one dataset from many rounds then go out in one write. With output.checkpoint_interval_s = 0 every
// commit copies, and every round is written at its commit. Every rank holds one and calls it at the same points.
class Writes {
 public:
  Writes(MPI_Comm comm, io::h5::File& file, const io::h5::Node& group, Plan& plan, const Plan::Info& info,
         const std::function<void()>& checkpoint)
      : comm_(comm), file_(file), group_(group), plan_(plan), info_(info), checkpoint_(checkpoint),
        defer_([this] { write(); }, [this] { return waiting_.bytes() > kDeferredMaxBytes; }) {
    MPI_Comm_rank(comm, &rank_);
  }
  // master: rows to write
  void add(Records records) { waiting_.add(std::move(records)); }
  // writes what waits, and the commit not yet written
  void flush() { timed([&] { write(); }); }
  // commits `done` rounds: its state and counter are written with the rows before the next copy
  void commit(int done) {
    timed([&] {
      pending_done_ = done;
      // the debug exit sits between this commit's state and counter: they are written now, copy or not
      if (debug_exit_wanted(info_.group, info_.counter, done)) write();
      checkpoint_();
    });
  }

 private:
  void write() {
    const auto tr = std::chrono::steady_clock::now();
    write_records(comm_, file_, rank_ == 0 ? waiting_.take() : Records{});
    records_s_ += since(tr);
    const int done = broadcast(comm_, pending_done_);
    if (done < 0) return;
    write_records(comm_, file_, rank_ == 0 ? plan_.state() : Records{});
    using Counts = std::vector<std::pair<std::string, int64_t>>;
    for (const auto& [name, value] : broadcast(comm_, rank_ == 0 ? plan_.state_attributes() : Counts{}))
      write_attribute(file_, info_.group, name, value);
    debug_exit_in_commit(comm_, file_, info_.group, info_.counter, done);
    group_.write_int(info_.counter, done);
    pending_done_ = -1;
  }
  // runs a flush or a commit (which may flush): the time writing rows counts as writes, the rest as commits
  template <class F>
  void timed(const F& f) {
    DriverClock& clock = driver_clock();
    const auto tc = std::chrono::steady_clock::now();
    records_s_ = 0;
    f();
    clock.writes_s += records_s_;
    clock.commits_s += since(tc) - records_s_;
  }

  // rank 0 asks for a copy (which writes what waits) once it holds more than this
  static constexpr size_t kDeferredMaxBytes = size_t{256} << 20;
  MPI_Comm comm_;
  io::h5::File& file_;
  const io::h5::Node& group_;
  Plan& plan_;
  const Plan::Info& info_;
  const std::function<void()>& checkpoint_;
  int rank_ = 0;
  RecordQueue waiting_;
  int pending_done_ = -1;  // the rounds done of the commit not yet written, -1: none
  double records_s_ = 0;   // time in write() writing rows (reset by timed())
  DeferredWrites defer_;   // last: a copy may flush once the rest is ready
};

// the master's progress lines: during a farm every run.progress_every_s, and a line for each round it ends
class Progress {
 public:
  Progress(const config::RunConfig& cfg, const Plan::Info& info, int rounds) : cfg_(cfg), info_(info), R_(rounds) {}
  void farming(const FarmHead& call, int k, int n) {
    const double now = since(t_stage_);
    if (cfg_.run.progress_every_s <= 0 || now - last_print_ < cfg_.run.progress_every_s) return;
    last_print_ = now;
    const int r = call.round, m = call.rounds;
    const std::string rounds = m > 1 ? std::to_string(r + 1) + "-" + std::to_string(r + m) : std::to_string(r + 1);
    std::printf("%s: %s %s/%d, %d/%d %s, %.1f s\n", info_.label.c_str(), info_.round_word.c_str(), rounds.c_str(), R_,
                k, n, info_.item_word.c_str(), now);
    std::fflush(stdout);
  }
  // `call` ended its rounds, `items` computed in `dt` seconds since the first of its passes started
  void rounds_done(const Plan& plan, const FarmHead& call, size_t items, double dt) {
    const double el = since(t_stage_);
    const int r = call.round, m = call.rounds;
    for (int k = 0; k < m; ++k)
      std::printf("%s: %s %d/%d: %s; %.0f %s/s, %.0f s, ETA %.0f s\n", info_.label.c_str(), info_.round_word.c_str(),
                  r + k + 1, R_, plan.summary(r + k).c_str(), items / dt, info_.item_word.c_str(), el,
                  (R_ - r - m) * dt / m);
    std::fflush(stdout);
  }

 private:
  const config::RunConfig& cfg_;
  const Plan::Info& info_;
  const int R_;
  const std::chrono::steady_clock::time_point t_stage_ = std::chrono::steady_clock::now();
  double last_print_ = -1e9;
};

// the call's items over the ranks; the master hands each result to its step as it comes (in item order)
void farm_call(MPI_Comm comm, Plan& plan, Schedule& schedule, FarmCall& call, Progress& progress) {
  FarmOptions fo;
  fo.costs = std::move(call.costs);  // the farm hands out the dearest first
  fo.on_result = [&](int64_t i, const std::string& bytes) { schedule.reduce(call, i, bytes); };
  fo.progress = [&](int k, int n) { progress.farming(call, k, n); };
  farm(comm, call.items, [&](const std::string& b) { return plan.compute(b); }, fo);
}

}  // namespace

void drive(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, Plan& plan,
           const std::function<void()>& checkpoint) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const Plan::Info info = plan.info();
  if (!file.has(info.group)) file.create_group(info.group);
  const io::h5::Node group = file.group(info.group);
  const int done = start_plan(comm, file, group, plan, info, rank);
  Writes writes(comm, file, group, plan, info, checkpoint);
  Progress progress(cfg, info, plan.rounds());
  // the plan's farm calls (stages/schedule.hpp), made on the master and followed by the other ranks
  stages::ScheduleOptions so = stages::driver_schedule(done, size, cfg.output.checkpoint_every);
  // the debug exit's commit ends a farm of independent rounds: it stays one farm's commit
  so.ends_farm = [&](int d) { return debug_exit_wanted(info.group, info.counter, d); };
  Schedule schedule(plan, so);
  DriverClock& clock = driver_clock();
  auto t_round = std::chrono::steady_clock::now();
  size_t round_items = 0;  // the master's items of the round's passes so far
  while (!schedule.done()) {
    // the closing round changes the plan's state: a commit still waiting is written with its own state first
    if (schedule.closing_next()) writes.flush();
    if (schedule.pass() == 0) t_round = std::chrono::steady_clock::now(), round_items = 0;
    FarmCall call = rank == 0 ? schedule.next() : FarmCall{};
    const auto tb = std::chrono::steady_clock::now();
    const FarmHead head = broadcast(comm, static_cast<const FarmHead&>(call));
    if (rank != 0) schedule.follow(head), static_cast<FarmHead&>(call) = head;
    clock.input_s += since(tb);
    round_items += call.items.size();
    farm_call(comm, plan, schedule, call, progress);
    const auto tw = std::chrono::steady_clock::now();
    if (rank == 0) {
      writes.add(schedule.end(call));
      // what the plan has to say about the rounds just ended (numerical trouble), on stderr: plans print nothing
      for (const std::string& w : plan.take_warnings()) std::fprintf(stderr, "%s\n", w.c_str());
    }
    clock.writes_s += since(tw);
    if (!call.ends_rounds) continue;
    clock.rounds += call.rounds;
    if (call.closing) {  // the closing round: recorded, not counted
      writes.flush();
      continue;
    }
    if (call.commit) writes.commit(call.round + call.rounds);
    if (rank == 0) progress.rounds_done(plan, call, round_items, since(t_round));
  }
  clock.input_s += schedule.input_s();
  clock.items_s += schedule.items_s();
  writes.flush();  // what still waits is written before the stage goes on (its later steps and stages read it)
  write_records(comm, file, rank == 0 ? plan.finish() : Records{});
  if (rank == 0) {
    const std::string s = plan.finish_summary();
    if (!s.empty()) std::printf("%s: %s\n", info.label.c_str(), s.c_str());
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

MpiDriver::MpiDriver(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, const std::function<void()>& checkpoint)
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
