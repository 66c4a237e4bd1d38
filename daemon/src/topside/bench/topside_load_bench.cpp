// Load benchmark of `navtool topside`: N WebSocket clients on /ws (one of them stalled: it never
// reads and has a 4 kB receive buffer), nav_solution_t published on LCM udpm at a fixed rate
// with utime = the publish time (CLOCK_REALTIME us). Reports the latency LCM publish ->
// WebSocket frame received by the reading clients (p50, p99, max; an upper bound of the
// bridge's receive -> send), the bridge process's CPU (utime + stime over the run) and RSS.
// A 5th argument 0 runs the same readers without the stalled client (the baseline).
// Needs multicast on loopback; run inside its own network namespace, e.g.
//   unshare -rn sh -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo &&
//     build/bin/nav_topside_load_bench build/bin/navtool [clients] [rate_hz] [seconds]'
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <navlcm/nav_solution_t.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/ws_raw_client.h"

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr int kPort = 18090;

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// utime + stime of `pid` in seconds (/proc/PID/stat fields 14 and 15).
double cpu_s(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::istringstream rest(text.substr(text.rfind(')') + 2));
  std::string field;
  double ticks = 0.0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i >= 14) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// VmRSS or VmHWM of `pid` in MiB.
double memory_mib(pid_t pid, const std::string& key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + ":", 0) == 0) return std::stod(line.substr(key.size() + 1)) / 1024.0;
  }
  return -1.0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s NAVTOOL [clients=20] [rate_hz=50] [seconds=10] [stalled=1]\n",
                 argv[0]);
    return 2;
  }
  const int clients = argc > 2 ? std::atoi(argv[2]) : 20;
  const double rate_hz = argc > 3 ? std::atof(argv[3]) : 50.0;
  const double seconds = argc > 4 ? std::atof(argv[4]) : 10.0;
  const bool stall =
      argc > 5 ? std::atoi(argv[5]) != 0 : true;  // 0: the baseline, no stalled client

  const pid_t bridge = fork();
  if (bridge == 0) {
    std::freopen("/dev/null", "w", stdout);
    execl(argv[1], argv[1], "topside", "--lcm-url", kUrl, "--listen",
          ("127.0.0.1:" + std::to_string(kPort)).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));

  std::optional<nav::tool::test::RawWsClient> stalled;
  stalled.emplace(kPort, 4096);
  if (!stalled->handshake("/ws")) {
    std::fprintf(stderr, "bench: navtool topside is not serving on port %d\n", kPort);
    kill(bridge, SIGTERM);
    return 1;
  }
  if (!stall) stalled.reset();  // the probe connection closes: readers only
  std::mutex mutex;
  std::vector<double> latencies_ms;
  std::atomic<bool> running{true};
  std::vector<std::thread> readers;
  for (int c = 1; c < clients; ++c) {
    readers.emplace_back([&] {
      nav::tool::test::RawWsClient ws(kPort);
      if (!ws.handshake("/ws")) return;
      std::vector<double> mine;
      while (running) {
        const auto f = ws.read_frame(200);
        if (!f) continue;
        const auto at = f->payload.find("\"utime\":");
        if (f->payload.find("NAVD_SOLUTION") == std::string::npos || at == std::string::npos)
          continue;
        const std::int64_t sent = std::stoll(f->payload.substr(at + 8));
        if (sent > 0) mine.push_back((now_us() - sent) / 1000.0);
      }
      std::lock_guard lock(mutex);
      latencies_ms.insert(latencies_ms.end(), mine.begin(), mine.end());
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));

  lcm::LCM lcm(kUrl);
  navlcm::nav_solution_t sol{};
  const double cpu0 = cpu_s(bridge);
  const auto t0 = std::chrono::steady_clock::now();
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  int published = 0;
  for (; std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(seconds);
       ++published) {
    sol.utime = now_us();
    sol.p_world_m[0] = published * 0.01;
    lcm.publish("NAVD_SOLUTION", &sol);
    std::this_thread::sleep_until(
        t0 +
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(period * (published + 1)));
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = cpu_s(bridge) - cpu0;
  const double rss = memory_mib(bridge, "VmRSS"), hwm = memory_mib(bridge, "VmHWM");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  running = false;
  for (auto& t : readers) t.join();
  kill(bridge, SIGTERM);
  waitpid(bridge, nullptr, 0);

  std::sort(latencies_ms.begin(), latencies_ms.end());
  const auto pct = [&](double p) {
    return latencies_ms.empty()
               ? -1.0
               : latencies_ms[static_cast<std::size_t>(p * (latencies_ms.size() - 1))];
  };
  const double expected = static_cast<double>(published) * (clients - 1);
  std::printf(
      "{\"clients\": %d, \"stalled\": %d, \"rate_hz\": %.0f, \"published\": %d, "
      "\"frames_received\": %zu, \"received_fraction\": %.4f, \"latency_ms\": {\"p50\": %.3f, "
      "\"p99\": %.3f, \"max\": %.3f}, \"bridge_cpu_percent\": %.1f, \"bridge_rss_mib\": %.1f, "
      "\"bridge_peak_rss_mib\": %.1f}\n",
      clients, stall ? 1 : 0, rate_hz, published, latencies_ms.size(),
      latencies_ms.size() / expected, pct(0.5), pct(0.99),
      latencies_ms.empty() ? -1.0 : latencies_ms.back(), 100.0 * cpu / wall_s, rss, hwm);
  return 0;
}
