// Preloaded into `pintag serve` by serve_signals_test.cpp (LD_PRELOAD): starts, before main()
// runs, one thread that lets every signal through and sleeps, as OpenBLAS starts its workers when
// it is loaded. The kernel may hand a process-directed signal to any thread that does not block
// it; this one is first in line.

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

namespace {

void* SleepForever(void* /*unused*/) {
  for (;;) pause();
}

__attribute__((constructor)) void StartUnblockedThread() {
  sigset_t none;
  sigset_t before;
  sigemptyset(&none);
  pthread_sigmask(SIG_SETMASK, &none, &before);  // the new thread inherits the empty mask
  pthread_t thread;
  if (pthread_create(&thread, nullptr, SleepForever, nullptr) == 0) {
    pthread_setname_np(thread, "unblocked");
    pthread_detach(thread);
  }
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
}

}  // namespace
