#include "mpi/stop.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>

namespace divcoll::mpi {
namespace {

// a lock-free atomic, so that two signals handled at once by two threads (both pending when the process
// runs again: each thread takes one) cannot both see "no signal yet": exchange gives exactly one of them
// the first signal, and the other stops at once
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free atomic");
int g_rank = 0;
unsigned g_grace_s = 0;
bool g_under_mpirun = false;

void say(const char* a, const char* b = "", const char* c = "") {
  for (const char* s : {a, b, c}) {
    size_t n = std::strlen(s);
    while (n > 0) {
      const ssize_t w = ::write(2, s, n);
      if (w <= 0) return;
      s += w, n -= static_cast<size_t>(w);
    }
  }
}

void on_alarm(int) {
  if (g_rank == 0)
    say("divcoll: no checkpoint within run.stop_grace_s of the signal: stopping now; the last checkpoint is kept, "
        "--resume continues from it\n");
  ::_exit(128 + g_signal.load());
}

void on_signal(int sig) {
  if (g_signal.exchange(sig) != 0) {
    if (g_rank == 0) say("divcoll: ", signal_name(sig), " again: stopping now; the last checkpoint is kept, --resume continues from it\n");
    ::_exit(128 + sig);
  }
  if (g_rank == 0 && g_grace_s > 0) {
    if (g_under_mpirun && sig != SIGUSR1)
      say("divcoll: ", signal_name(sig), " from the launcher (mpirun ends the ranks within seconds); the last checkpoint is "
          "kept (for a stop after the next checkpoint, send SIGUSR1 to mpirun)\n");
    else
      say("divcoll: ", signal_name(sig), ": stopping after the next checkpoint (a second signal stops at once)\n");
  }
  if (g_grace_s > 0) {
    ::alarm(g_grace_s);
  } else {
    if (g_rank == 0) say("divcoll: run.stop_grace_s = 0: stopping now; the last checkpoint is kept, --resume continues from it\n");
    ::_exit(128 + sig);
  }
}

void install(void (*h)(int)) {
  struct sigaction sa {};
  sa.sa_handler = h;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int s : {SIGTERM, SIGINT, SIGUSR1}) sigaction(s, &sa, nullptr);
  struct sigaction al {};
  al.sa_handler = h == SIG_DFL ? SIG_DFL : on_alarm;
  sigemptyset(&al.sa_mask);
  al.sa_flags = SA_RESTART;
  sigaction(SIGALRM, &al, nullptr);
}

}  // namespace

const char* signal_name(int sig) {
  switch (sig) {
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    case SIGUSR1: return "SIGUSR1";
    default: return "a signal";
  }
}

void arm_stop_signals(int rank, double grace_s) {
  g_rank = rank;
  g_grace_s = static_cast<unsigned>(std::ceil(grace_s));
  g_under_mpirun = std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr;
  install(on_signal);
}

void disarm_stop_signals() {
  ::alarm(0);
  install(SIG_DFL);
}

int stop_signal() { return g_signal.load(); }

}  // namespace divcoll::mpi
