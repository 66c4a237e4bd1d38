#pragma once
// What the fault campaign does to navd's host (fault_scenarios.h HostFault) and the processes
// it runs: each call says what failed in its return value ("" on success) rather than
// throwing, so a scenario records the failure as a note and goes on.
//
// Threads: any; the namespace calls before any thread exists.

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace nav::campaign {

/// unshare(CLONE_NEWNET) with lo up and 224.0.0.0/4 routed to it, and unshare(CLONE_NEWNS)
/// with / made private (so a tmpfs mounted later is this process tree's only). "" or why not.
std::string enter_private_namespaces();

/// ioctl SIOCDELRT / SIOCADDRT of 224.0.0.0/4 dev lo (this network namespace).
std::string delete_multicast_route();
std::string add_multicast_route();

/// Mounts a `size_kib` tmpfs on `dir` (created); "" or why not.
std::string mount_small_tmpfs(const std::filesystem::path& dir, int size_kib);
std::string unmount(const std::filesystem::path& dir);
/// Writes `file` until the filesystem is full (ENOSPC); "" or the unexpected error.
std::string fill_until_full(const std::filesystem::path& file);

/// Forks `count` processes spinning on the CPU until killed; their pids.
std::vector<pid_t> start_cpu_burners(int count);
/// SIGKILL and reap each.
void stop_processes(const std::vector<pid_t>& pids);

/// Starts `program` with `args`, stdout and stderr appended to `dir`/navd.stdout / navd.stderr.
pid_t spawn_logged(const std::filesystem::path& program, const std::vector<std::string>& args,
                   const std::filesystem::path& dir);
/// Waits up to `timeout_ms` for `pid`: its exit code, -1 when still running or signalled
/// (`still_running` says which).
int wait_exit_ms(pid_t pid, int timeout_ms, bool* still_running = nullptr);

}  // namespace nav::campaign
