// systemd/navd.service: the directives a vehicle relies on (Type=notify,
// WatchdogSec, Restart=on-failure, an unprivileged user, capabilities limited to what raw CAN
// and real-time scheduling could need, hardening), ExecStart options navd really accepts,
// the `realtime` settings of config/rov.yaml inside the unit's limits,
// `systemd-analyze verify` on a copy whose ExecStart is the built navd, and the exposure of
// `systemd-analyze security --offline=true` (not worse than the value in systemd/README.md).
// Tests that need systemd-analyze skip with the reason when it is missing. Runs from the source
// directory (CTest WORKING_DIRECTORY).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "nav/daemon/config/config.h"

namespace {

namespace fs = std::filesystem;

constexpr const char* kUnitPath = "systemd/navd.service";
/// systemd-analyze security --offline=true of systemd/navd.service, as in systemd/README.md.
constexpr double kMaxExposure = 1.8;

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// key -> every value it was given, per section ("Service" -> "DeviceAllow" -> [...]).
using Unit = std::map<std::string, std::map<std::string, std::vector<std::string>>>;

Unit parse_unit(const std::string& text) {
  Unit unit;
  std::string section;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[' && line.back() == ']') {
      section = line.substr(1, line.size() - 2);
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    unit[section][line.substr(0, eq)].push_back(line.substr(eq + 1));
  }
  return unit;
}

std::vector<std::string> words(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

struct ShellRun {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr
};

ShellRun run_shell(const std::string& command, const fs::path& dir) {
  const fs::path out = dir / "output.txt";
  const std::string line =
      "cd '" + dir.string() + "' && " + command + " >'" + out.string() + "' 2>&1";
  const int status = std::system(line.c_str());
  return ShellRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out)};
}

bool have_systemd_analyze() {
  return std::system("command -v systemd-analyze >/dev/null 2>&1") == 0;
}

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("systemd_unit_test_" + std::to_string(::getpid()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// The value of a single-valued key ("" when absent); fails the test when given twice.
std::string single(const Unit& unit, const std::string& section, const std::string& key) {
  const auto s = unit.find(section);
  if (s == unit.end()) return "";
  const auto k = s->second.find(key);
  if (k == s->second.end()) return "";
  EXPECT_EQ(k->second.size(), 1u) << key << " given more than once";
  return k->second.back();
}

TEST(SystemdUnit, RequiredDirectives) {
  const Unit unit = parse_unit(slurp(kUnitPath));
  ASSERT_TRUE(unit.count("Service")) << kUnitPath << " has no [Service] section";
  EXPECT_EQ(single(unit, "Service", "Type"), "notify");
  EXPECT_EQ(single(unit, "Service", "NotifyAccess"), "main");
  EXPECT_TRUE(std::regex_match(single(unit, "Service", "WatchdogSec"), std::regex("[1-9][0-9]*s")))
      << "WatchdogSec=" << single(unit, "Service", "WatchdogSec");
  EXPECT_EQ(single(unit, "Service", "Restart"), "on-failure");
  EXPECT_EQ(single(unit, "Service", "RestartPreventExitStatus"), "2");  // config errors
  const std::string user = single(unit, "Service", "User");
  EXPECT_FALSE(user.empty() || user == "root" || user == "0") << "User=" << user;
  EXPECT_EQ(single(unit, "Service", "StateDirectory"), "navd");  // checkpoints
  for (const char* key : {"NoNewPrivileges", "ProtectHome", "PrivateTmp", "ProtectKernelTunables",
                          "ProtectKernelModules", "ProtectControlGroups", "RestrictSUIDSGID",
                          "LockPersonality", "MemoryDenyWriteExecute", "RestrictNamespaces"}) {
    EXPECT_EQ(single(unit, "Service", key), "yes") << key;
  }
  EXPECT_EQ(single(unit, "Service", "ProtectSystem"), "strict");
  EXPECT_EQ(single(unit, "Service", "DevicePolicy"), "closed");
  EXPECT_FALSE(unit.at("Service").count("SystemCallFilter") == 0) << "no SystemCallFilter";
}

TEST(SystemdUnit, CapabilitiesOnlyForRawCanAndRealtime) {
  const Unit unit = parse_unit(slurp(kUnitPath));
  ASSERT_TRUE(unit.count("Service"));
  const std::set<std::string> allowed = {"CAP_NET_RAW", "CAP_NET_ADMIN", "CAP_SYS_NICE"};
  // An absent CapabilityBoundingSet means "all capabilities": it must be given.
  ASSERT_TRUE(unit.at("Service").count("CapabilityBoundingSet"))
      << "CapabilityBoundingSet= missing (would keep every capability)";
  std::set<std::string> bounding;
  for (const std::string& v : unit.at("Service").at("CapabilityBoundingSet")) {
    for (const std::string& cap : words(v)) {
      EXPECT_TRUE(allowed.count(cap)) << "CapabilityBoundingSet has " << cap;
      bounding.insert(cap);
    }
  }
  if (unit.at("Service").count("AmbientCapabilities")) {
    for (const std::string& v : unit.at("Service").at("AmbientCapabilities")) {
      for (const std::string& cap : words(v)) {
        EXPECT_TRUE(bounding.count(cap)) << "AmbientCapabilities " << cap << " not in the bound";
      }
    }
  }
  // Real-time scheduling without CAP_SYS_NICE needs the RLIMIT_RTPRIO allowance.
  if (!bounding.count("CAP_SYS_NICE")) {
    EXPECT_NE(single(unit, "Service", "LimitRTPRIO"), "");
    EXPECT_EQ(single(unit, "Service", "RestrictRealtime"), "no");
  }
}

TEST(SystemdUnit, RovYamlsRealtimeSettingsAreWhatTheUnitAllows) {
  const Unit unit = parse_unit(slurp(kUnitPath));
  const nav::daemon::RealtimeConfig rt = nav::daemon::load_config_file("config/rov.yaml").realtime;
  const int limit = std::stoi(single(unit, "Service", "LimitRTPRIO"));
  EXPECT_LE(rt.device_priority, limit) << "navd would run its device threads unprioritised";
  EXPECT_LE(rt.filter_priority, limit) << "navd would run its filter thread unprioritised";
  if (rt.lock_memory) {
    EXPECT_EQ(single(unit, "Service", "LimitMEMLOCK"), "infinity");
  }
}

TEST(SystemdUnit, ExecStartUsesOptionsNavdAccepts) {
  const Unit unit = parse_unit(slurp(kUnitPath));
  const std::vector<std::string> argv = words(single(unit, "Service", "ExecStart"));
  ASSERT_FALSE(argv.empty());
  EXPECT_EQ(argv[0], "/usr/bin/navd");
  TempDir tmp;
  const ShellRun help = run_shell(std::string("'") + NAVD_PATH + "' --help", tmp.path());
  ASSERT_EQ(help.exit_code, 0) << help.output;
  for (size_t i = 1; i < argv.size(); ++i) {
    if (argv[i].rfind("--", 0) != 0) continue;
    EXPECT_NE(help.output.find(argv[i]), std::string::npos)
        << "ExecStart passes " << argv[i] << ", which navd --help does not list";
  }
}

TEST(SystemdUnit, SystemdAnalyzeVerifyPasses) {
  if (!have_systemd_analyze()) GTEST_SKIP() << "systemd-analyze not installed";
  TempDir tmp;
  std::string text = slurp(kUnitPath);
  const std::string exec = "ExecStart=/usr/bin/navd";
  const auto at = text.find(exec);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, exec.size(), std::string("ExecStart=") + NAVD_PATH);
  std::ofstream(tmp.path() / "navd.service") << text;
  const ShellRun verify = run_shell("systemd-analyze verify ./navd.service", tmp.path());
  EXPECT_EQ(verify.exit_code, 0) << verify.output;
  // verify prints warnings without failing for some mistakes: none may mention the unit.
  EXPECT_EQ(verify.output.find("navd.service:"), std::string::npos) << verify.output;
}

TEST(SystemdUnit, SecurityExposureNotWorseThanDocumented) {
  if (!have_systemd_analyze()) GTEST_SKIP() << "systemd-analyze not installed";
  TempDir tmp;
  fs::copy_file(kUnitPath, tmp.path() / "navd.service");
  const ShellRun security =
      run_shell("systemd-analyze security --offline=true --no-pager ./navd.service", tmp.path());
  std::smatch m;
  const std::regex overall("Overall exposure level for navd\\.service: ([0-9.]+)");
  ASSERT_TRUE(std::regex_search(security.output, m, overall)) << security.output;
  const double exposure = std::stod(m[1]);
  std::printf("systemd-analyze security --offline=true: exposure %.1f\n", exposure);
  EXPECT_LE(exposure, kMaxExposure) << security.output;
  // The documented value is current: the README quotes the same number.
  EXPECT_NE(slurp("systemd/README.md").find("exposure " + std::string(m[1])), std::string::npos)
      << "systemd/README.md does not quote exposure " << m[1];
}

}  // namespace
