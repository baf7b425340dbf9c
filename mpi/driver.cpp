#include "mpi/driver.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

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

// DIVCOLL_DEBUG_EXIT_IN_COMMIT=<group>:<done>: every rank flushes the file and exits between the state and
// the counter of that commit (a kill placed by the program itself, for tests/mpi/commit_kill_test.sh)
void debug_exit_in_commit(MPI_Comm comm, const io::h5::File& file, const std::string& group, int done) {
  const char* e = std::getenv("DIVCOLL_DEBUG_EXIT_IN_COMMIT");
  if (!e || std::string(e) != group + ":" + std::to_string(done)) return;
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

void drive(MPI_Comm comm, const io::RunConfig& cfg, io::h5::File& file, Plan& plan,
           const std::function<void()>& checkpoint) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const Plan::Info info = plan.info();
  const std::string& label = info.label;
  if (!file.has(info.group)) file.create_group(info.group);
  io::h5::Node group = file.group(info.group);
  if (info.owns_stage) {
    group.write_string("status", "running");
    for (const Attribute& a : plan.attributes()) {
      if (const auto* text = std::get_if<std::string>(&a.value)) group.write_string(a.name, *text);
      else group.write_int(a.name, std::get<int64_t>(a.value));
    }
    write_records(comm, file, rank == 0 ? plan.setup() : Records{});
  }
  const int R = plan.rounds();
  const int done = group.has_attribute(info.counter) ? static_cast<int>(group.read_int(info.counter)) : 0;

  // where to start: the state committed with the counter (the master's plan holds it)
  // every rank reads the state (a read made by one rank alone unbalances the ranks' HDF5 metadata caches:
  // io/h5.hpp); the master's plan holds it
  StoredState stored;
  if (done > 0)
    for (const std::string& p : plan.state_paths()) stored[p] = file.read<double>(p);
  if (rank == 0) {
    plan.start(done, stored);
    if (done >= R)
      std::printf("%s: all %d %ss were already done\n", label.c_str(), R, info.round_word.c_str());
    else if (done > 0)
      std::printf("%s: resuming after %s %d\n", label.c_str(), info.round_word.c_str(), done);
  }
  auto commit = [&](int rounds_done) {
    write_records(comm, file, rank == 0 ? plan.state() : Records{});
    debug_exit_in_commit(comm, file, info.group, rounds_done);
    group.write_int(info.counter, rounds_done);
    checkpoint();
  };

  const auto t_stage = std::chrono::steady_clock::now();
  double last_print = -1e9;
  const int end = R + (plan.closing_round() ? 1 : 0);
  for (int r = done; r < end; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    plan.take_input(r, bcast_string(comm, rank == 0 ? plan.round_input(r) : std::string()));
    const std::vector<std::string> items = rank == 0 ? plan.items(r) : std::vector<std::string>{};
    FarmOptions fo;
    fo.on_result = [&](int64_t i, const std::string& bytes) { plan.reduce(r, i, bytes); };
    fo.progress = [&](int k, int n) {
      const double now = since(t_stage);
      if (cfg.run.progress_every_s > 0 && now - last_print >= cfg.run.progress_every_s) {
        last_print = now;
        std::printf("%s: %s %d/%d, %d/%d %s, %.1f s\n", label.c_str(), info.round_word.c_str(), r + 1, R, k, n,
                    info.item_word.c_str(), now);
        std::fflush(stdout);
      }
    };
    farm(comm, items, [&](const std::string& b) { return plan.compute(b); }, fo);
    write_records(comm, file, rank == 0 ? plan.end_round(r) : Records{});
    if (r >= R) continue;  // the closing round: recorded, not counted
    const int every = info.commit_every > 0 ? info.commit_every : cfg.output.checkpoint_every;
    if ((r + 1) % every == 0 || r + 1 == R) commit(r + 1);
    if (rank == 0) {
      const double dt = since(t0), el = since(t_stage);
      std::printf("%s: %s %d/%d: %s; %.0f %s/s, %.0f s, ETA %.0f s\n", label.c_str(), info.round_word.c_str(), r + 1, R,
                  plan.summary(r).c_str(), items.size() / dt, info.item_word.c_str(), el, (R - r - 1) * dt);
      std::fflush(stdout);
    }
  }
  write_records(comm, file, rank == 0 ? plan.finish() : Records{});
  if (info.owns_stage) {
    group.write_string("status", "complete");
    checkpoint();
  }
}

}  // namespace divcoll::mpi
