#include "mpi/scheduler.hpp"

#include <chrono>
#include <cstring>
#include <iterator>
#include <list>

#include "mpi/protocol.hpp"

namespace divcoll::mpi {
namespace {

void send_bytes(MPI_Comm comm, int dest, int tag, int64_t index, const std::string& bytes) {
  std::string buf(sizeof(int64_t) + bytes.size(), '\0');
  std::memcpy(buf.data(), &index, sizeof index);
  std::memcpy(buf.data() + sizeof index, bytes.data(), bytes.size());
  MPI_Send(buf.data(), static_cast<int>(buf.size()), MPI_BYTE, dest, tag, comm);
}

// receives a message already probed: (index, payload)
std::pair<int64_t, std::string> recv_bytes(MPI_Comm comm, const MPI_Status& st) {
  int count = 0;
  MPI_Get_count(&st, MPI_BYTE, &count);
  std::string buf(count, '\0');
  MPI_Recv(buf.data(), count, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, comm, MPI_STATUS_IGNORE);
  int64_t index = -1;
  if (count >= static_cast<int>(sizeof index)) std::memcpy(&index, buf.data(), sizeof index);
  return {index, count >= static_cast<int>(sizeof index) ? buf.substr(sizeof index) : std::string()};
}

// requests each worker keeps open: with 2 a worker has its next item queued when it sends a result, so it
// does not wait for the master to finish an item of its own before it gets more work (with 1 a worker was
// busy only about 35% of the time at 2 ranks on small items)
constexpr int kPrefetch = 2;

// the master's non-blocking task sends, whose buffers live until they complete: a queued task for a busy
// worker must not hold the master up (a large task is only taken when the worker posts its receive)
class Sender {
 public:
  explicit Sender(MPI_Comm comm) : comm_(comm) {}
  ~Sender() { wait_all(); }
  void send(int dest, int tag, int64_t index, const std::string& bytes) {
    reap();
    Pending& p = pending_.emplace_back();
    p.buf.resize(sizeof(int64_t) + bytes.size());
    std::memcpy(p.buf.data(), &index, sizeof index);
    std::memcpy(p.buf.data() + sizeof index, bytes.data(), bytes.size());
    MPI_Isend(p.buf.data(), static_cast<int>(p.buf.size()), MPI_BYTE, dest, tag, comm_, &p.req);
  }
  void wait_all() {
    for (Pending& p : pending_) MPI_Wait(&p.req, MPI_STATUS_IGNORE);
    pending_.clear();
  }

 private:
  struct Pending {
    MPI_Request req = MPI_REQUEST_NULL;
    std::string buf;
  };
  void reap() {  // frees the buffers of the sends that have completed
    for (auto it = pending_.begin(); it != pending_.end();) {
      int done = 0;
      MPI_Test(&it->req, &done, MPI_STATUS_IGNORE);
      it = done ? pending_.erase(it) : std::next(it);
    }
  }
  MPI_Comm comm_;
  std::list<Pending> pending_;  // a list: buffers must not move while their send is in flight
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

FarmClock& farm_clock() {
  static FarmClock clock;
  return clock;
}

FarmResult farm(MPI_Comm comm, const std::vector<std::string>& items,
                const std::function<std::string(const std::string&)>& compute, const FarmOptions& opt) {
  const auto t_farm = std::chrono::steady_clock::now();
  FarmClock& clock = farm_clock();
  auto timed = [&](const std::string& item) {
    const auto t0 = std::chrono::steady_clock::now();
    std::string r = compute(item);
    clock.compute_s += seconds_since(t0);
    ++clock.items;
    return r;
  };
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int64_t n = static_cast<int64_t>(items.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, comm);
  FarmResult out;
  out.results.assign(n, std::string());
  out.owner.assign(n, 0);

  if (rank == 0) {
    Sender sender(comm);
    int64_t next = 0, done = 0;
    int workers_open = kPrefetch * (size - 1);  // requests not yet answered with kRoundEnd
    auto hand_out = [&](int worker) {
      if (next < n) {
        out.owner[next] = worker;
        sender.send(worker, kTask, next, items[next]);
        ++next;
      } else {
        sender.send(worker, kRoundEnd, -1, std::string());
        --workers_open;
      }
    };
    auto handle = [&](const MPI_Status& st) {
      auto [index, payload] = recv_bytes(comm, st);
      if (st.MPI_TAG == kResult) {
        out.results[index] = std::move(payload);
        ++done;
        if (opt.progress) opt.progress(static_cast<int>(done), static_cast<int>(n));
      }
      hand_out(st.MPI_SOURCE);
    };
    while (done < n || workers_open > 0) {
      MPI_Status st;
      int flag = 0;
      MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, comm, &flag, &st);
      if (flag) {
        handle(st);
      } else if (next < n && (opt.master_works || size == 1)) {
        // the master computes an item itself
        const int64_t i = next++;
        out.owner[i] = 0;
        out.results[i] = timed(items[i]);
        ++done;
        if (opt.progress) opt.progress(static_cast<int>(done), static_cast<int>(n));
      } else {
        MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, comm, &st);
        handle(st);
      }
    }
    sender.wait_all();
  } else {
    // kPrefetch requests up front; every result is a new request. Each request is answered with a task or,
    // once the items are out, with kRoundEnd; messages from the master arrive in the order it sent them, so
    // no task follows the first kRoundEnd, and the round ends when every request has been answered.
    for (int k = 0; k < kPrefetch; ++k) send_bytes(comm, 0, kReady, -1, std::string());
    for (int ends = 0; ends < kPrefetch;) {
      MPI_Status st;
      MPI_Probe(0, MPI_ANY_TAG, comm, &st);
      auto [index, payload] = recv_bytes(comm, st);
      if (st.MPI_TAG == kRoundEnd) {
        ++ends;
        continue;
      }
      out.results[index] = timed(payload);
      send_bytes(comm, 0, kResult, index, out.results[index]);
    }
  }
  MPI_Bcast(out.owner.data(), static_cast<int>(n), MPI_INT, 0, comm);
  clock.farm_s += seconds_since(t_farm);
  return out;
}

}  // namespace divcoll::mpi
