#pragma once
// The stop signals of navd and navtool survey: SIGTERM (systemd's stop) and SIGINT (Ctrl-C) are
// blocked in every thread and waited for with sigtimedwait by the run modes, so no thread is
// interrupted inside a device call or a filter update.
#include <pthread.h>
#include <signal.h>

namespace nav::daemon {

/// Blocks SIGTERM and SIGINT in this thread and every thread started after it (threads inherit
/// the mask); returns the set to wait for.
inline sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

}  // namespace nav::daemon
