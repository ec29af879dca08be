#include "commands/serve_signals.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <unistd.h>

#include <cerrno>
#include <initializer_list>
#include <stdexcept>
#include <string>

namespace pintag::cli {
namespace {

// Read end, write end. Written only by the handler and wake(); read only by the waiter.
int g_pipe[2] = {-1, -1};

// Runs in whichever thread the kernel chose: write(2) alone, which is async-signal-safe; the
// write end does not block, so a flood of signals cannot stall the thread it lands on.
extern "C" void PassToWaiter(int signal) {
  const int saved = errno;
  const auto byte = static_cast<unsigned char>(signal);
  [[maybe_unused]] const ssize_t written = ::write(g_pipe[1], &byte, 1);
  errno = saved;
}

// SIGINT or SIGTERM while the server is still starting (seeding, waiting for a first snapshot):
// end as the default action ends a process. A process that is PID 1 (a container run without an
// init) ignores a signal left at its default action, so `docker stop` would wait out its grace
// period; handled, it ends there too. signal, sigprocmask, raise and _exit are async-signal-safe.
extern "C" void EndWhileStarting(int signal) {
  ::signal(signal, SIG_DFL);
  sigset_t only;
  sigemptyset(&only);
  sigaddset(&only, signal);
  ::sigprocmask(SIG_UNBLOCK, &only, nullptr);
  ::raise(signal);
  ::_exit(128 + signal);  // the raise was ignored: PID 1
}

sigset_t Only(std::initializer_list<int> signals) {
  sigset_t set;
  sigemptyset(&set);
  for (const int s : signals) sigaddset(&set, s);
  return set;
}

// The three signals the server answers.
sigset_t Served() {
  return Only({SIGINT, SIGTERM, SIGHUP});
}

void Handle(int signal) {
  struct sigaction action {};
  action.sa_handler = PassToWaiter;
  action.sa_mask = Served();
  action.sa_flags = SA_RESTART;  // a library thread's sleep resumes where the signal found it
  if (sigaction(signal, &action, nullptr) != 0) {
    throw std::runtime_error("pintag serve: cannot handle signal " + std::to_string(signal));
  }
}

}  // namespace

ServeSignals::ServeSignals() {
  if (g_pipe[0] < 0) {
    if (::pipe2(g_pipe, O_CLOEXEC) != 0 ||
        ::fcntl(g_pipe[1], F_SETFL, ::fcntl(g_pipe[1], F_GETFL) | O_NONBLOCK) != 0) {
      throw std::runtime_error("pintag serve: cannot make the signal pipe");
    }
  }
  const sigset_t hangup = Only({SIGHUP});
  pthread_sigmask(SIG_BLOCK, &hangup, nullptr);
  Handle(SIGHUP);
  for (const int stop : {SIGINT, SIGTERM}) {
    struct sigaction action {};
    action.sa_handler = EndWhileStarting;
    sigemptyset(&action.sa_mask);
    sigaction(stop, &action, nullptr);
  }
}

void ServeSignals::takeStopSignals() {
  // Handled before blocked: a signal between the two reaches the pipe either way.
  Handle(SIGINT);
  Handle(SIGTERM);
  const sigset_t served = Served();
  pthread_sigmask(SIG_BLOCK, &served, nullptr);
}

int ServeSignals::wait() {
  // Where no library thread takes a signal, it waits, pending, for a thread that lets it through.
  const sigset_t served = Served();
  pthread_sigmask(SIG_UNBLOCK, &served, nullptr);
  for (;;) {
    unsigned char byte = 0;
    const ssize_t n = ::read(g_pipe[0], &byte, 1);
    if (n == 1) return byte;
    if (n < 0 && errno == EINTR) continue;  // the handler ran in this thread; its byte is next
    return 0;  // the pipe failed (it is never closed): nothing more will arrive
  }
}

int ServeSignals::waitFor(std::chrono::milliseconds timeout) {
  const sigset_t served = Served();
  pthread_sigmask(SIG_UNBLOCK, &served, nullptr);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return -1;
    pollfd readable{g_pipe[0], POLLIN, 0};
    const int ready = ::poll(&readable, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;  // the handler ran in this thread
    if (ready < 0) return 0;
    if (ready == 0) return -1;
    unsigned char byte = 0;
    const ssize_t n = ::read(g_pipe[0], &byte, 1);
    if (n == 1) return byte;
    if (n < 0 && errno == EINTR) continue;
    return 0;
  }
}

void ServeSignals::wake() {
  PassToWaiter(0);
}

}  // namespace pintag::cli
