#pragma once
// Real-time scheduling and memory locking of navd's live threads (the `realtime` config
// section, config/README.md).
//
// Why: a serial or CAN device thread dates each record by its arrival on the host
// (drivers/time/clock_mapping.h). If that thread waits for a core behind image registration or
// the recovery, the record is dated late by the wait and the filter fuses it at the wrong time
// (0.5 m/s of heave over 100 ms is 5 cm of depth). Under SCHED_FIFO the device threads, which
// block on their devices and use little CPU, preempt every normal thread the moment a byte
// arrives; the filter thread runs below them and above the rest.
//
// Permission: SCHED_FIFO at priority p needs CAP_SYS_NICE or RLIMIT_RTPRIO >= p
// (sched(7)); navd.service grants the limit (LimitRTPRIO=50), not the capability. mlockall
// needs CAP_IPC_LOCK or an RLIMIT_MEMLOCK above what is locked (LimitMEMLOCK=infinity). A
// refusal is logged with its reason and navd runs on under normal scheduling: navigating late
// is better than not navigating.
//
// Threads: every function acts on the calling thread (or the whole process for
// lock_all_memory) and may be called from any thread; RealtimeTally is thread-safe.

#include <atomic>
#include <string>
#include <string_view>

namespace nav::daemon {

/// Names the calling thread (Linux keeps at most 15 bytes: longer names are cut), as `top -H`,
/// `ps -L` and /proc/<pid>/task/<tid>/comm show it.
void name_this_thread(std::string_view name);

/// Runs the calling thread under SCHED_FIFO at `priority` in [1, 99]; 0 changes nothing.
/// Returns "" on success, else why not: the system's error text and, when refused for want of
/// permission, the RLIMIT_RTPRIO that would allow it.
std::string request_fifo_priority(int priority);

/// The calling thread's policy and priority, e.g. "SCHED_FIFO 40" or "SCHED_OTHER".
std::string thread_policy_text();

/// mlockall(MCL_CURRENT | MCL_FUTURE): every page the process has or will map stays in RAM,
/// so no page fault of a swapped-out or not-yet-touched page stalls a thread. "" on success,
/// else why not (with RLIMIT_MEMLOCK when that is the cause).
std::string lock_all_memory();

/// glibc malloc keeps what is freed: every block comes from the heap (M_MMAP_MAX 0) and the heap
/// is never trimmed (M_TRIM_THRESHOLD -1), so a large block freed and allocated again (the
/// recovery's and the renewals' buffers, CHOLMOD's columns) reuses pages already faulted in,
/// and locked, instead of fresh mmaps the kernel must zero and fault page by page. The process
/// keeps its high-water mark of heap (docs/performance.md "Freed memory kept"). Call once at
/// start, before other threads; false if glibc refused a setting.
bool keep_freed_memory();

/// What the live threads got: each thread that asks calls enter() once; the counts go into
/// navd's summary.
class RealtimeTally {
 public:
  /// request_fifo_priority(priority) for the calling thread, named `thread` in the log line:
  /// info when granted, warning with the reason when refused. Nothing when priority is 0.
  void enter(std::string_view thread, int priority);
  int granted() const { return granted_.load(); }
  int refused() const { return refused_.load(); }

 private:
  std::atomic<int> granted_{0};
  std::atomic<int> refused_{0};
};

}  // namespace nav::daemon
