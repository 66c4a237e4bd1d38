// Real-time scheduling and memory locking (nav/daemon/system/realtime.h).
#include "nav/daemon/system/realtime.h"

#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace nav::daemon {
namespace {

std::string limit_text(int resource) {
  rlimit limit{};
  if (::getrlimit(resource, &limit) != 0) return "unknown";
  if (limit.rlim_cur == RLIM_INFINITY) return "unlimited";
  return std::to_string(static_cast<unsigned long long>(limit.rlim_cur));
}

}  // namespace

void name_this_thread(std::string_view name) {
  char cut[16] = {};
  name.copy(cut, sizeof(cut) - 1);
  ::pthread_setname_np(::pthread_self(), cut);
}

std::string request_fifo_priority(int priority) {
  if (priority == 0) return {};
  const int lo = ::sched_get_priority_min(SCHED_FIFO), hi = ::sched_get_priority_max(SCHED_FIFO);
  if (priority < lo || priority > hi) {
    return "SCHED_FIFO priority " + std::to_string(priority) + " is outside [" +
           std::to_string(lo) + ", " + std::to_string(hi) + "]";
  }
  sched_param param{};
  param.sched_priority = priority;
  const int error = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  if (error == 0) return {};
  std::string why = "SCHED_FIFO priority " + std::to_string(priority) + ": " + std::strerror(error);
  if (error == EPERM) {
    why += " (RLIMIT_RTPRIO is " + limit_text(RLIMIT_RTPRIO) +
           " and the process lacks CAP_SYS_NICE; navd.service's LimitRTPRIO= raises the limit)";
  }
  return why;
}

std::string thread_policy_text() {
  int policy = 0;
  sched_param param{};
  if (::pthread_getschedparam(::pthread_self(), &policy, &param) != 0) return "unknown";
  switch (policy) {
    case SCHED_FIFO:
      return "SCHED_FIFO " + std::to_string(param.sched_priority);
    case SCHED_RR:
      return "SCHED_RR " + std::to_string(param.sched_priority);
    case SCHED_OTHER:
      return "SCHED_OTHER";
    default:
      return "policy " + std::to_string(policy);
  }
}

std::string lock_all_memory() {
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return {};
  const int error = errno;
  std::string why = std::string("mlockall: ") + std::strerror(error);
  if (error == EPERM || error == ENOMEM) {
    why += " (RLIMIT_MEMLOCK is " + limit_text(RLIMIT_MEMLOCK) +
           " bytes; navd.service's LimitMEMLOCK=infinity lifts it)";
  }
  return why;
}

bool keep_freed_memory() {
  const bool no_mmap = ::mallopt(M_MMAP_MAX, 0) == 1;
  const bool no_trim = ::mallopt(M_TRIM_THRESHOLD, -1) == 1;
  return no_mmap && no_trim;
}

void RealtimeTally::enter(std::string_view thread, int priority) {
  if (priority == 0) return;
  const std::string why = request_fifo_priority(priority);
  if (why.empty()) {
    granted_.fetch_add(1);
    spdlog::info("navd: {} thread runs under SCHED_FIFO {}", thread, priority);
  } else {
    refused_.fetch_add(1);
    spdlog::warn("navd: {} thread keeps normal scheduling: {}", thread, why);
  }
}

}  // namespace nav::daemon
