// mpi/stop: a second signal ends the process at once, also when two threads handle two signals together
#include "mpi/stop.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <thread>

namespace divcoll::mpi {
namespace {

bool ended_by_a_second_signal(int status) {
  return WIFEXITED(status) && (WEXITSTATUS(status) == 128 + SIGTERM || WEXITSTATUS(status) == 128 + SIGINT);
}

// two threads raise SIGTERM and SIGINT at the same moment, each in itself; when both handlers have run (a
// signal a thread raises in itself is handled before pthread_kill returns), one of them must have ended the
// process. Before the handler took the first signal atomically, both could see "no signal yet", and the run
// went on to its next checkpoint.
[[noreturn]] void two_signals_at_once() {
  arm_stop_signals(/*rank=*/1, /*grace_s=*/60.0);  // rank 1: silent
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  auto raise_in_self = [&](int sig) {
    ready.fetch_add(1);
    while (!go.load()) {
    }
    pthread_kill(pthread_self(), sig);
  };
  std::thread a(raise_in_self, SIGTERM);
  std::thread b(raise_in_self, SIGINT);
  while (ready.load() < 2) {
  }
  go.store(true);
  a.join();
  b.join();
  ::_exit(kStoppedExit);  // both signals handled and the process still runs: the second did not stop it
}

TEST(StopDeathTest, TwoSignalsHandledTogetherStopAtOnce) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  for (int i = 0; i < 20; ++i) EXPECT_EXIT(two_signals_at_once(), ended_by_a_second_signal, "") << "attempt " << i;
}

TEST(StopDeathTest, OneSignalWaitsForTheCheckpoint) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        arm_stop_signals(/*rank=*/1, /*grace_s=*/60.0);
        raise(SIGUSR1);
        ::_exit(stop_signal() == SIGUSR1 ? kStoppedExit : 1);
      },
      testing::ExitedWithCode(kStoppedExit), "");
}

}  // namespace
}  // namespace divcoll::mpi
