#include "mpi/scheduler.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <deque>
#include <exception>
#include <iterator>
#include <memory>
#include <mutex>
#include <numeric>
#include <thread>

#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "common/check.hpp"
#include "mpi/node_cores.hpp"
#include "mpi/protocol.hpp"
#include "mpi/wait.hpp"

namespace divcoll::mpi {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// DIVCOLL_FARM_TRACE=PREFIX: every rank appends its farm's events to PREFIX.RANK when a farm() returns, one
// "KIND T A B" line each, T on the machine's monotonic clock (s): F farm() entered (A: items), C an item
// computed (T its end, A its start), E farm() left; the master's G (a block handed out, A its first item) and
// R (a result taken in); a worker's S (its result sent, A its first item) and T (a block received).
// divcoll_post.farm_trace tells where the time went. Off (not even a clock read) without the variable
struct Trace {
  std::mutex mu;
  std::vector<std::string> lines;
  bool on = std::getenv("DIVCOLL_FARM_TRACE") != nullptr;
  static double now() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }
  // an event now
  void add(char kind, double a) {
    if (!on) return;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%c %.6f %.6f 0", kind, now(), a);
    std::lock_guard lk(mu);
    lines.emplace_back(buf);
  }
  void flush(int rank) {
    if (!on) return;
    std::lock_guard lk(mu);
    const std::string path = std::string(std::getenv("DIVCOLL_FARM_TRACE")) + "." + std::to_string(rank);
    if (FILE* f = std::fopen(path.c_str(), "a")) {
      for (const auto& l : lines) std::fprintf(f, "%s\n", l.c_str());
      std::fclose(f);
    }
    lines.clear();
  }
};
Trace& trace() {
  static Trace t;
  return t;
}

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// how long a thread with nothing to do sleeps before it looks again: 20 µs after something happened,
// doubling up to 2 ms, so a waiting rank costs its core under 1% and answers within 2 ms (a worker is
// woken at once by its own computing thread; it holds queued blocks, so a slow answer costs no work).
// A serving thread whose own computing thread has work, with no message of its own in flight, skips the ramp
// and naps at once (the master: half its mean item time, 2 to 10 ms; a worker: 10 ms), woken when its item
// finishes (see `calm` in Master::nap and Worker::nap): each wake-up takes the core from that computing
// thread, and the ramp from 20 µs after every message had cost it 2-3% of its time
class Backoff {
 public:
  static constexpr int kMinUs = 20, kMaxUs = 2000;
  // the master's longest look-away in a round's tail, where a worker waits for its next item: at least
  // kTailUs; when the master computes items too, sqrt(2 × kWakeCostUs × its mean item time), at most kMaxUs.
  // Each look takes the master's core from its computing thread for about kWakeCostUs, and a worker waits half
  // a look on average for each item of the tail; that interval balances the two losses. kWakeCostUs: looking
  // every 200 µs made the master's 19 ms items 15% slower (2-core VM, 2026-11), i.e. 30 µs a look. Measured
  // again with the engine's buffers on cache lines (16d869b), the quick agents stage at 2 ranks (17 ms items,
  // calm naps of 8 ms): 30 µs, 1.537 s (median of 7); 60 µs, 1.518 s (median of 4), the master's computing
  // thread 1.42 s against its worker's 1.40 s
  static constexpr int kTailUs = 200, kWakeCostUs = 60;
  static int tail_us(double mean_item_s) {
    if (!(mean_item_s > 0)) return kTailUs;
    return static_cast<int>(std::clamp(std::sqrt(2.0 * kWakeCostUs * mean_item_s * 1e6), double{kTailUs}, double{kMaxUs}));
  }
  // a calm worker's look-away: its computing thread has a block and wakes it when it finishes
  static constexpr int kCalmWorkerUs = 10000;
  // a calm master's look-away: every worker holds a queued block behind the one it computes, so a result
  // taken half an item later still comes before that worker runs dry; 2 ms when no item has finished yet.
  // (the quick agents stage at 2 ranks, 5 rounds alternating: 2 ms calm naps and kWakeCostUs = 30, the stage
  // 1.545-1.554 s, the master's computing thread 1.448-1.456 s, its serving thread 0.033 s of CPU; half an
  // item and 60: 1.516-1.524 s, 1.419-1.424 s, 0.023 s; the worker's computing thread 1.39 s in both)
  static int calm_master_us(double mean_item_s) {
    if (!(mean_item_s > 0)) return kMaxUs;
    return static_cast<int>(std::clamp(0.5 * mean_item_s * 1e6, double{kMaxUs}, double{kCalmWorkerUs}));
  }

  void reset() { us_ = kMinUs; }
  // the next sleep, at most max_us (the doubling goes on up to kMaxUs regardless)
  std::chrono::microseconds next(int max_us = kMaxUs) {
    const int us = std::min(us_, max_us);
    us_ = std::min(2 * us_, kMaxUs);
    return std::chrono::microseconds(us);
  }
  void sleep(int max_us = kMaxUs) { std::this_thread::sleep_for(next(max_us)); }

 private:
  int us_ = kMinUs;
};

// a block message (tasks or results): [count | count item indices | count sizes | payloads], all int64;
// payload(k) is the k-th item's bytes
template <class Payload>
std::string pack_block(const int64_t* index, int64_t count, Payload payload) {
  size_t total = (1 + 2 * count) * sizeof(int64_t);
  for (int64_t k = 0; k < count; ++k) total += payload(k).size();
  std::string buf(total, '\0');
  char* p = buf.data();
  auto put = [&](int64_t v) {
    std::memcpy(p, &v, sizeof v);
    p += sizeof v;
  };
  put(count);
  for (int64_t k = 0; k < count; ++k) put(index[k]);
  for (int64_t k = 0; k < count; ++k) put(static_cast<int64_t>(payload(k).size()));
  for (int64_t k = 0; k < count; ++k) {
    const std::string& x = payload(k);
    std::memcpy(p, x.data(), x.size());
    p += x.size();
  }
  return buf;
}

// a block message's item indices and payloads
struct Block {
  std::vector<int64_t> index;
  std::vector<std::string> data;
};
Block unpack_block(const char* buf) {
  auto get = [&](size_t at) {
    int64_t v = 0;
    std::memcpy(&v, buf + at * sizeof v, sizeof v);
    return v;
  };
  const int64_t count = get(0);
  Block out{std::vector<int64_t>(count), std::vector<std::string>(count)};
  size_t at = (1 + 2 * count) * sizeof(int64_t);
  for (int64_t k = 0; k < count; ++k) {
    out.index[k] = get(1 + k);
    const auto len = static_cast<size_t>(get(1 + count + k));
    out.data[k].assign(buf + at, len);
    at += len;
  }
  return out;
}

// requests in flight with the buffers they use: one MPI_Testsome looks at all of them
template <class Buffer>
class InFlight {
 public:
  ~InFlight() {
    if (!reqs_.empty()) new std::vector<Buffer>(std::move(bufs_));  // error path: the buffers are left to MPI
  }
  Buffer& add(MPI_Request*& req) {
    reqs_.push_back(MPI_REQUEST_NULL);
    bufs_.push_back(std::make_unique<typename Buffer::element_type>());
    req = &reqs_.back();
    return bufs_.back();
  }
  // the buffers of the requests that have completed, in the order they were added
  std::vector<Buffer> take() {
    std::vector<Buffer> out;
    if (reqs_.empty()) return out;
    int k = 0;
    idx_.resize(reqs_.size());
    MPI_Testsome(static_cast<int>(reqs_.size()), reqs_.data(), &k, idx_.data(), MPI_STATUSES_IGNORE);
    if (k <= 0) return out;  // none, or MPI_UNDEFINED (every request is null)
    std::sort(idx_.begin(), idx_.begin() + k);
    size_t keep = 0;
    for (size_t i = 0, d = 0; i < reqs_.size(); ++i) {
      if (d < static_cast<size_t>(k) && idx_[d] == static_cast<int>(i)) {
        out.push_back(std::move(bufs_[i]));
        ++d;
      } else {
        reqs_[keep] = reqs_[i];
        bufs_[keep] = std::move(bufs_[i]);
        ++keep;
      }
    }
    reqs_.resize(keep);
    bufs_.resize(keep);
    return out;
  }
  bool empty() const { return reqs_.empty(); }

 private:
  std::vector<MPI_Request> reqs_;  // MPI writes into these: a request moves only while it is not being tested
  std::vector<Buffer> bufs_;       // heap blocks: they do not move when the vector grows
  std::vector<int> idx_;
};

// a message as received: where it came from, its tag, its bytes (not zeroed first)
struct Message {
  int source = 0, tag = 0;
  size_t size = 0;
  std::unique_ptr<char[]> bytes;
};

// non-blocking receives of messages already matched by MPI_Improbe: neither side waits in MPI while the
// other is busy (a large message needs both sides to call MPI when the shared-memory transport has no
// single-copy mechanism)
class Receiver {
 public:
  void receive(MPI_Message& msg, const MPI_Status& st) {
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    MPI_Request* req = nullptr;
    Message& m = *inflight_.add(req);
    m = {st.MPI_SOURCE, st.MPI_TAG, static_cast<size_t>(count), std::unique_ptr<char[]>(new char[std::max(count, 1)])};
    MPI_Imrecv(m.bytes.get(), count, MPI_BYTE, &msg, req);
  }
  std::vector<std::unique_ptr<Message>> take() { return inflight_.take(); }
  bool empty() const { return inflight_.empty(); }

 private:
  InFlight<std::unique_ptr<Message>> inflight_;
};

// non-blocking sends whose buffers live until they complete
class Sender {
 public:
  explicit Sender(MPI_Comm comm) : comm_(comm) {}
  void send(int dest, int tag, std::string bytes) {
    MPI_Request* req = nullptr;
    std::string& buf = *inflight_.add(req);
    buf = std::move(bytes);
    MPI_Isend(buf.data(), static_cast<int>(buf.size()), MPI_BYTE, dest, tag, comm_, req);
  }
  // frees the buffers of the sends that have completed (and lets MPI progress the others)
  void reap() { inflight_.take(); }
  void wait_all() {
    for (Backoff b; reap(), !inflight_.empty();) b.sleep();
  }
  bool empty() const { return inflight_.empty(); }

 private:
  MPI_Comm comm_;
  InFlight<std::unique_ptr<std::string>> inflight_;
};

// does the master's node have a core for every rank on it? (Open MPI and MPICH say how many ranks share
// the node; without either, every rank is assumed to be on the master's node. The cores are those the node
// gives the job: mpi/node_cores.hpp)
bool node_has_core_per_rank(int size) {
  int local = size;
  for (const char* var : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"})
    if (const char* v = std::getenv(var)) {
      local = std::atoi(v);
      break;
    }
  static const int cores = node_cores();
  return local <= cores;
}

// how long a rank with a core of its own and nothing to compute looks again without sleeping: a worker for
// its next block, any rank in a collective's wait between rounds
constexpr double kSpinS = 0.005;

// whether every rank on this node has a core of its own (set by the first farm(); until then, no)
bool g_own_core = false;

// the calling thread's sleeps end when asked, not up to 50 µs later (Linux's default timer slack for a
// normal thread), and whether ranks have cores of their own is known from then on
void precise_naps(int size) {
  static thread_local bool done = false;
  if (done) return;
  done = true;
  g_own_core = node_has_core_per_rank(size);
#ifdef __linux__
  prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL);
#endif
}

using Compute = std::function<std::string(const std::string&)>;

// the thread that computes items on one rank, and what it shares with the serving thread
struct Shared {
  std::mutex mu;
  std::condition_variable to_server;  // something finished (or failed)
  std::condition_variable to_worker;  // a block was queued (or the round is over)
  std::exception_ptr error;
  double compute_s = 0, compute_cpu_s = 0;
  long items = 0;
  double own_s = 0;     // the master: wall seconds of the items its computing thread finished in this farm()
  long own_items = 0;   // and how many
  // adds the computing thread's totals to this rank's clock
  void add_to(FarmClock& clock) const {
    clock.compute_s += compute_s;
    clock.compute_cpu_s += compute_cpu_s;
    clock.items += items;
  }
};

// records one compute() call's time: wall seconds, and CPU seconds of the calling thread (less than the wall
// when the thread was descheduled: by its rank's serving thread, another process or the host)
std::string timed_compute(const std::function<std::string(const std::string&)>& compute, const std::string& task,
                          double& seconds, double& cpu_seconds) {
  const auto t0 = Clock::now();
  const double c0 = thread_cpu_s();
  const double start = trace().on ? Trace::now() : 0;
  std::string r = compute(task);
  trace().add('C', start);
  cpu_seconds += thread_cpu_s() - c0;
  seconds += seconds_since(t0);
  return r;
}

// the master's side of a farm(): hands the items out to the workers in blocks, takes their results in and, when
// its node has a core per rank, computes items of its own in a thread beside its messages, from the same queue
class Master {
 public:
  Master(MPI_Comm comm, int size, int64_t n, const std::vector<std::string>& items, const Compute& compute,
         const FarmOptions& opt, FarmResult& out, FarmClock& clock);
  // if serving fails (an exception from MPI, progress or on_result), the computing thread stops after its item
  ~Master();
  Master(const Master&) = delete;
  Master& operator=(const Master&) = delete;
  // the whole round: every item handed out or computed here, every result in, every worker told the round is over
  void serve();

 private:
  int64_t at(int64_t pos) const { return order_.empty() ? pos : order_[pos]; }
  // the round's tail: items are left, no more than 4 per computing rank (automatic blocks are then one item)
  bool in_tail(int64_t left) const { return left > 0 && left <= 4 * computing_; }
  void give(int w);
  void compute_own();
  bool take_results();
  bool take_own(bool& running);
  void finished(int64_t k);
  void nap(bool active, bool running);

  MPI_Comm comm_;
  int size_;
  int64_t n_;
  const std::vector<std::string>& items_;
  const Compute& compute_;
  const FarmOptions& opt_;
  FarmResult& out_;
  FarmClock& clock_;
  const bool master_computes_;
  const int computing_;
  Shared sh_;
  // with costs, items go out dearest first (equal costs in index order): position p is item order_[p], and
  // cum_[p] the cost of the items before it
  std::vector<int64_t> order_;
  std::vector<double> cum_;
  int64_t next_ = 0;          // first position not yet handed out (guarded by sh_.mu)
  std::vector<char> have_;    // item has its result on the master (guarded by sh_.mu)
  int64_t local_new_ = 0;     // items the master's thread finished since the server last looked (guarded by sh_.mu)
  bool local_running_ = false;
  Sender sender_;
  std::vector<char> ended_;
  std::vector<int> held_;  // blocks handed to each worker whose results have not come back
  int open_workers_;
  std::thread local_;
  int64_t done_ = 0, folded_ = 0;
  Receiver receiver_;
  Backoff backoff_;
};

Master::Master(MPI_Comm comm, int size, int64_t n, const std::vector<std::string>& items, const Compute& compute,
               const FarmOptions& opt, FarmResult& out, FarmClock& clock)
    : comm_(comm), size_(size), n_(n), items_(items), compute_(compute), opt_(opt), out_(out), clock_(clock),
      master_computes_(opt.master_works && node_has_core_per_rank(size)),
      computing_(size - 1 + (master_computes_ ? 1 : 0)), have_(n, 0), sender_(comm), ended_(size, 0),
      held_(size, 0), open_workers_(size - 1) {
  if (!opt.costs.empty()) {
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), int64_t{0});
    std::stable_sort(order_.begin(), order_.end(), [&](int64_t a, int64_t b) { return opt.costs[a] > opt.costs[b]; });
    cum_.assign(n + 1, 0.0);
    for (int64_t p = 0; p < n; ++p) cum_[p + 1] = cum_[p] + opt.costs[order_[p]];
  }
}

Master::~Master() {
  if (!local_.joinable()) return;
  {
    std::lock_guard lk(sh_.mu);
    next_ = n_;
  }
  local_.join();
}

// hands worker w its next block, or tells it the round is over (once)
void Master::give(int w) {
  const auto t0 = Clock::now();
  int64_t first = 0, count = 0;
  {
    std::lock_guard lk(sh_.mu);
    const int64_t left = n_ - next_;
    // the round's tail (blocks of one item): a worker gets its next item only once it has none left, so
    // that no item waits in one worker's queue while another rank, the master too, has nothing to do
    if (in_tail(left) && held_[w] > 0 && opt_.block <= 0) return;
    if (left > 0) {
      int64_t guided = (left + 4 * computing_ - 1) / (4 * computing_);
      if (!cum_.empty()) {  // by cost: the dearest items left, as few as make 1/(4 × computing) of the cost left
        const double target = (cum_[n_] - cum_[next_]) / (4.0 * computing_);
        guided = std::lower_bound(cum_.begin() + next_ + 1, cum_.end(), cum_[next_] + target) - (cum_.begin() + next_);
      }
      count = std::min(left, opt_.block > 0 ? int64_t{opt_.block} : std::clamp<int64_t>(guided, 1, std::max(1, opt_.max_block)));
      first = next_;
      next_ += count;
    }
  }
  if (count > 0) {
    ++held_[w];
    std::vector<int64_t> index(count);
    for (int64_t k = 0; k < count; ++k) out_.owner[index[k] = at(first + k)] = w;
    std::string buf = pack_block(index.data(), count, [&](int64_t k) -> const std::string& { return items_[index[k]]; });
    clock_.task_bytes += static_cast<double>(buf.size());
    ++clock_.task_msgs;
    trace().add('G', static_cast<double>(index[0]));
    sender_.send(w, kTask, std::move(buf));
  } else if (!ended_[w]) {
    ended_[w] = 1;
    --open_workers_;
    sender_.send(w, kRoundEnd, std::string());
  }
  clock_.task_s += seconds_since(t0);
}

// the master's computing thread: its own items, one at a time, from the same queue
void Master::compute_own() {
  double secs = 0, cpu = 0;
  long count = 0;
  std::unique_lock lk(sh_.mu);
  while (next_ < n_ && !sh_.error) {
    const int64_t i = at(next_++);
    out_.owner[i] = 0;
    lk.unlock();
    std::string r;
    const double before = secs;
    try {
      r = timed_compute(compute_, items_[i], secs, cpu);
    } catch (...) {
      lk.lock();
      sh_.error = std::current_exception();
      break;
    }
    lk.lock();
    sh_.own_s += secs - before, ++sh_.own_items;
    out_.results[i] = std::move(r);
    have_[i] = 1;
    ++local_new_, ++count;
    sh_.to_server.notify_one();
  }
  sh_.compute_s += secs;
  sh_.compute_cpu_s += cpu;
  sh_.items += count;
  local_running_ = false;
  sh_.to_server.notify_one();
}

void Master::serve() {
  for (int k = 0; k < std::max(1, opt_.depth); ++k)
    for (int w = 1; w < size_; ++w) give(w);
  if (master_computes_ && n_ > 0) {
    local_running_ = true;
    local_ = std::thread([this] { compute_own(); });
  }
  for (;;) {
    bool active = take_results();
    bool running = false;
    if (take_own(running)) active = true;
    sender_.reap();
    if (done_ == n_ && open_workers_ == 0 && !running) break;
    nap(active, running);
  }
  if (local_.joinable()) local_.join();
  sender_.wait_all();
  sh_.add_to(clock_);
}

// the workers' results that have arrived; whether there were any
bool Master::take_results() {
  bool active = false;
  // Open MPI's probe (ob1) looks among the messages already matched in and only then advances its
  // transports, so a result that arrived during a nap would be seen one look later (measured: the master
  // took a tail result in 1.0-1.8 ms after it was sent, looking every 1.1 ms; 0.6 ms with this): advance
  // first with a probe whose answer is not used, then take everything in
  {
    int ignored = 0;
    MPI_Iprobe(MPI_ANY_SOURCE, kResult, comm_, &ignored, MPI_STATUS_IGNORE);
  }
  // every result that has arrived is answered at once with the worker's next block
  for (;;) {
    int flag = 0;
    MPI_Message msg;
    MPI_Status st;
    MPI_Improbe(MPI_ANY_SOURCE, kResult, comm_, &flag, &msg, &st);
    if (!flag) break;
    active = true;
    const auto t0 = Clock::now();
    trace().add('R', 0);
    receiver_.receive(msg, st);
    clock_.result_s += seconds_since(t0);
    --held_[st.MPI_SOURCE];
    give(st.MPI_SOURCE);
  }
  for (const auto& m : receiver_.take()) {
    active = true;
    const auto t0 = Clock::now();
    Block b = unpack_block(m->bytes.get());
    const auto count = static_cast<int64_t>(b.data.size());
    for (int64_t k = 0; k < count; ++k) out_.results[b.index[k]] = std::move(b.data[k]);
    {
      std::lock_guard lk(sh_.mu);
      for (int64_t i : b.index) have_[i] = 1;
    }
    clock_.result_bytes += static_cast<double>(m->size);
    ++clock_.result_msgs;
    clock_.results += count;
    clock_.result_s += seconds_since(t0);
    finished(count);
  }
  return active;
}

// the items the master's computing thread finished since the last look, and the results now folded in item
// order; running: whether that thread is still at work. Whether it had finished any
bool Master::take_own(bool& running) {
  int64_t fresh = 0, fold_to = folded_;
  std::exception_ptr error;
  {
    std::lock_guard lk(sh_.mu);
    fresh = local_new_;
    local_new_ = 0;
    running = local_running_;
    error = sh_.error;
    if (opt_.on_result)
      while (fold_to < n_ && have_[fold_to]) ++fold_to;
  }
  if (error) {
    if (local_.joinable()) local_.join();
    std::rethrow_exception(error);
  }
  if (fresh > 0) finished(fresh);
  for (; folded_ < fold_to; ++folded_) opt_.on_result(folded_, out_.results[folded_]);
  return fresh > 0;
}

void Master::finished(int64_t k) {
  for (int64_t q = 0; q < k; ++q) {
    ++done_;
    if (opt_.progress) opt_.progress(static_cast<int>(done_), static_cast<int>(n_));
  }
}

// between two looks at the messages: nothing (after activity that wants an answer soon), or a nap
void Master::nap(bool active, bool running) {
  // calm: this core's computing thread is at work, nothing of ours is in flight and no worker waits for
  // its next item (the tail), so nothing here is urgent: the computing thread's next item wakes us, and a
  // worker's result can wait half an item (it holds its next block)
  const bool calm = running && sender_.empty() && receiver_.empty() && !in_tail(n_ - next_);
  if (active && !calm) {
    backoff_.reset();
    return;
  }
  std::unique_lock lk(sh_.mu);
  // in the round's tail a worker waits for its next item: look more often
  const double mean_item_s = sh_.own_items > 0 ? sh_.own_s / static_cast<double>(sh_.own_items) : 0.0;
  const auto how_long = calm ? std::chrono::microseconds(Backoff::calm_master_us(mean_item_s))
                             : backoff_.next(in_tail(n_ - next_) ? Backoff::tail_us(mean_item_s) : Backoff::kMaxUs);
  sh_.to_server.wait_for(lk, how_long, [&] { return local_new_ > 0 || sh_.error || (!local_running_ && running); });
}

// a worker's side of a farm(): takes the master's blocks in, computes them in a thread of their own and sends
// each block's results back as soon as it is done
class Worker {
 public:
  Worker(MPI_Comm comm, const Compute& compute, FarmResult& out, FarmClock& clock, bool own_core)
      : comm_(comm), compute_(compute), out_(out), clock_(clock), own_core_(own_core), sender_(comm) {}
  ~Worker() { finish_thread(); }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;
  // the whole round: every block taken in, computed and its results sent, up to the master's kRoundEnd
  void serve();

 private:
  void compute_blocks();
  void finish_thread();
  bool take_tasks();
  void send_results(std::deque<Block>& ready);
  void nap(bool active, bool idle);

  MPI_Comm comm_;
  const Compute& compute_;
  FarmResult& out_;
  FarmClock& clock_;
  const bool own_core_;
  Shared sh_;  // a Block's data: its tasks, then their results
  std::deque<Block> queued_, computed_;
  bool busy_ = false, stop_ = false;
  std::thread worker_;
  Sender sender_;
  Receiver receiver_;
  bool got_end_ = false;
  bool end_matched_ = false;  // this farm's kRoundEnd has been matched: what comes after it is the next farm's
  Backoff backoff_;
  Clock::time_point idle_since_{};
  bool was_idle_ = false;
};

// the worker's computing thread: the queued blocks, one after the other
void Worker::compute_blocks() {
  double secs = 0, cpu = 0;
  long count = 0;
  std::unique_lock lk(sh_.mu);
  for (;;) {
    sh_.to_worker.wait(lk, [&] { return stop_ || !queued_.empty(); });
    if (queued_.empty() || sh_.error) break;
    Block b = std::move(queued_.front());
    queued_.pop_front();
    busy_ = true;
    lk.unlock();
    try {
      for (std::string& x : b.data) x = timed_compute(compute_, x, secs, cpu), ++count;
    } catch (...) {
      lk.lock();
      sh_.error = std::current_exception();
      busy_ = false;
      sh_.to_server.notify_one();
      break;
    }
    lk.lock();
    busy_ = false;
    computed_.push_back(std::move(b));
    sh_.to_server.notify_one();
  }
  sh_.compute_s += secs;
  sh_.compute_cpu_s += cpu;
  sh_.items += count;
}

void Worker::finish_thread() {
  {
    std::lock_guard lk(sh_.mu);
    stop_ = true;
    queued_.clear();
  }
  sh_.to_worker.notify_one();
  if (worker_.joinable()) worker_.join();
}

void Worker::serve() {
  worker_ = std::thread([this] { compute_blocks(); });
  for (;;) {
    bool active = take_tasks();
    std::deque<Block> ready;
    bool idle = false;
    std::exception_ptr error;
    {
      std::lock_guard lk(sh_.mu);
      ready.swap(computed_);
      idle = queued_.empty() && !busy_;
      error = sh_.error;
    }
    if (error) std::rethrow_exception(error);
    if (!ready.empty()) active = true;
    send_results(ready);
    sender_.reap();
    if (got_end_ && idle && ready.empty() && receiver_.empty()) break;
    nap(active, idle);
  }
  finish_thread();
  sender_.wait_all();
  sh_.add_to(clock_);
}

// the master's messages that have arrived, queued for the computing thread; whether there were any
bool Worker::take_tasks() {
  bool active = false;
  // tasks, matched in the order the master sent them, up to this farm's kRoundEnd and no further: the master
  // may already be in the next farm (its broadcast of the item count completes without us), and a message
  // matched here belongs to this farm (tests/mpi/scheduler_test.cpp, AWorkerLateForAFarmTakesOnlyThatFarmsMessages)
  while (!end_matched_) {
    int flag = 0;
    MPI_Message msg;
    MPI_Status st;
    MPI_Improbe(0, MPI_ANY_TAG, comm_, &flag, &msg, &st);
    if (!flag) break;
    active = true;
    trace().add('T', 0);
    end_matched_ = st.MPI_TAG == kRoundEnd;
    receiver_.receive(msg, st);
  }
  for (const auto& m : receiver_.take()) {
    active = true;
    if (m->tag == kRoundEnd) {
      got_end_ = true;
      continue;
    }
    Block b = unpack_block(m->bytes.get());
    {
      std::lock_guard lk(sh_.mu);
      queued_.push_back(std::move(b));
    }
    sh_.to_worker.notify_one();
  }
  return active;
}

// results go out at once, without waiting for the master to take them
void Worker::send_results(std::deque<Block>& ready) {
  for (Block& b : ready) {
    const auto count = static_cast<int64_t>(b.data.size());
    trace().add('S', static_cast<double>(b.index[0]));
    sender_.send(0, kResult, pack_block(b.index.data(), count, [&](int64_t k) -> const std::string& { return b.data[k]; }));
    for (int64_t k = 0; k < count; ++k) out_.results[b.index[k]] = std::move(b.data[k]);
  }
}

// between two looks at the messages: nothing (after activity, or spinning for the next block), or a nap
void Worker::nap(bool active, bool idle) {
  // calm: the computing thread has a block, and nothing of ours is in flight: its finished block wakes
  // us, and the master's next block can wait until then (we look every 10 ms all the same)
  const bool calm = !idle && sender_.empty() && receiver_.empty();
  // waiting for the next block with a core of our own and nothing to compute: look again at once, for a
  // while (in a round's tail the master answers a result within about 0.5 ms; sleeping between looks
  // added as much again to every item of the tail)
  if (idle && !was_idle_) idle_since_ = Clock::now();
  was_idle_ = idle;
  const bool spin = own_core_ && idle && !got_end_ && seconds_since(idle_since_) < kSpinS;
  if (spin) return;
  if (active && !calm) {
    backoff_.reset();
    return;
  }
  std::unique_lock lk(sh_.mu);
  const auto how_long = calm ? std::chrono::microseconds(Backoff::kCalmWorkerUs) : backoff_.next();
  sh_.to_server.wait_for(lk, how_long, [&] { return !computed_.empty() || sh_.error; });
}

}  // namespace

// a collective's wait between rounds sleeps at most 500 µs at a time: there are several per round, each
// overshooting its wait by up to the sleep, and a round of the graded stage can be 0.1 s
constexpr int kWaitMaxUs = 500;

void wait_sleeping(MPI_Request& req) {
  Backoff b;
  const auto t0 = Clock::now();
  for (int done = 0;;) {
    MPI_Test(&req, &done, MPI_STATUS_IGNORE);
    if (done) return;
    // with a core of its own a rank looks again at once for a while: between rounds the others come within
    // a few hundred µs, and a sleep overshoots that
    if (g_own_core && seconds_since(t0) < kSpinS) continue;
    b.sleep(kWaitMaxUs);
  }
}

void barrier_sleeping(MPI_Comm comm) {
  MPI_Request req;
  MPI_Ibarrier(comm, &req);
  wait_sleeping(req);
}

void allreduce_int_sleeping(MPI_Comm comm, int& value, MPI_Op op) {
  MPI_Request req;
  MPI_Iallreduce(MPI_IN_PLACE, &value, 1, MPI_INT, op, comm, &req);
  wait_sleeping(req);
}

FarmClock& farm_clock() {
  static FarmClock clock;
  return clock;
}

FarmResult farm(MPI_Comm comm, const std::vector<std::string>& items,
                const std::function<std::string(const std::string&)>& compute, const FarmOptions& opt) {
  const auto t_farm = Clock::now();
  FarmClock& clock = farm_clock();
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const double cpu0 = thread_cpu_s();
  int64_t n = static_cast<int64_t>(items.size());
  trace().add('F', static_cast<double>(n));
  struct TraceEnd {
    int rank;
    ~TraceEnd() {
      trace().add('E', 0);
      trace().flush(rank);
    }
  } trace_end{rank};
  if (rank == 0 && !opt.costs.empty()) {
    bool good = static_cast<int64_t>(opt.costs.size()) == n;
    for (double c : opt.costs) good = good && std::isfinite(c) && c > 0;
    DIVCOLL_DEMAND(good);  // FarmOptions::costs: one positive cost per item
  }
  FarmResult out;
  if (size == 1) {
    out.results.resize(n);
    out.owner.assign(n, 0);
    for (int64_t i = 0; i < n; ++i) {
      out.results[i] = timed_compute(compute, items[i], clock.compute_s, clock.compute_cpu_s);
      ++clock.items;
      if (opt.progress) opt.progress(static_cast<int>(i + 1), static_cast<int>(n));
      if (opt.on_result) opt.on_result(i, out.results[i]);
    }
    clock.farm_s += seconds_since(t_farm);
    return out;
  }
  precise_naps(size);
  {  // workers wait here while the master prepares the round: sleeping, not spinning in MPI_Bcast
    MPI_Request req;
    MPI_Ibcast(&n, 1, MPI_INT64_T, 0, comm, &req);
    wait_sleeping(req);
  }
  out.results.assign(n, std::string());
  out.owner.assign(n, 0);
  if (rank == 0) Master(comm, size, n, items, compute, opt, out, clock).serve();
  else Worker(comm, compute, out, clock, g_own_core).serve();
  if (n > 0) {
    MPI_Request req;
    MPI_Ibcast(out.owner.data(), static_cast<int>(n), MPI_INT, 0, comm, &req);
    wait_sleeping(req);
  }
  clock.serve_cpu_s += thread_cpu_s() - cpu0;
  clock.farm_s += seconds_since(t_farm);
  return out;
}

}  // namespace divcoll::mpi
