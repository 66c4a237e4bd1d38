// navd configuration errors end to end: the real navd binary (NAVD_PATH) started on
// config/sim.yaml with one defect each — unknown key, wrong type, out-of-range value, missing
// file, YAML syntax error, bad or missing CAN signal table — must exit with status 2 before
// starting anything, and stderr must name the file, the key path and the reason. The unmodified
// config is the control: navd refuses it (all its sensors are simulated) with the command that
// runs it, and that command (`navtool survey`, NAVTOOL_PATH) runs a 2-image survey on it and
// exits 0. A config with neither devices nor a `sim` section is "nothing to run". Runs from the
// source directory (CTest WORKING_DIRECTORY).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct NavdRun {
  int exit_code = -1;
  std::string out, err;
};

class NavdConfigErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("navd_config_errors_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    sim_yaml_ = slurp("config/sim.yaml");
    ASSERT_FALSE(sim_yaml_.empty()) << "config/sim.yaml not found (run from the source dir)";
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  /// config/sim.yaml with the first `from` replaced by `to`, written as `name` in the temp dir.
  fs::path edited(const std::string& name, const std::string& from, const std::string& to) {
    std::string yaml = sim_yaml_;
    const auto at = yaml.find(from);
    EXPECT_NE(at, std::string::npos) << "config/sim.yaml changed: no '" << from << "'";
    if (at != std::string::npos) yaml.replace(at, from.size(), to);
    return write(name, yaml);
  }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }

  /// navd --config <config> (or `navtool survey --config <config>` on a 2-image survey as
  /// fast as possible) in the temp dir.
  NavdRun run(const fs::path& config, bool survey = false) {
    const std::string program =
        survey ? std::string("'") + NAVTOOL_PATH + "' survey" : std::string("'") + NAVD_PATH + "'";
    const std::string command =
        "cd '" + dir_.string() + "' && " + program + " --config '" + config.string() + "'" +
        (survey ? " --images 2 --as-fast-as-possible" : "") + " >stdout.txt 2>stderr.txt";
    const int status = std::system(command.c_str());
    return NavdRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir_ / "stdout.txt"),
                   slurp(dir_ / "stderr.txt")};
  }

  /// Exit status 2 and stderr "<file>: <key path>: <reason...>".
  void expect_config_error(const fs::path& config, const std::string& key_path,
                           const std::string& reason) {
    const NavdRun r = run(config);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const std::string where = config.filename().string() + ": " + key_path + ": ";
    EXPECT_NE(r.err.find(where), std::string::npos) << "stderr lacks '" << where << "':\n" << r.err;
    EXPECT_NE(r.err.find(reason), std::string::npos) << "stderr lacks '" << reason << "':\n"
                                                     << r.err;
    EXPECT_EQ(r.out.find("\"images\""), std::string::npos) << "navd ran: " << r.out;
  }

  fs::path dir_;
  std::string sim_yaml_;
};

TEST_F(NavdConfigErrors, UnmodifiedSimConfigIsRefusedByNavdAndRunByNavtoolSurvey) {
  const fs::path good = write("good.yaml", sim_yaml_);
  const NavdRun navd = run(good);
  EXPECT_EQ(navd.exit_code, 2) << navd.err;
  EXPECT_NE(navd.err.find("good.yaml: sensors: every sensor's transport is `sim`"),
            std::string::npos)
      << navd.err;
  EXPECT_NE(navd.err.find("`navtool survey --config " + good.string() + "`"), std::string::npos)
      << navd.err;
  EXPECT_TRUE(navd.out.empty()) << "navd ran: " << navd.out;
  const NavdRun survey = run(good, true);
  EXPECT_EQ(survey.exit_code, 0) << survey.err;
  EXPECT_NE(survey.out.find("\"images\":2"), std::string::npos) << survey.out;
}

TEST_F(NavdConfigErrors, NoDeviceAndNoSimSectionIsNothingToRun) {
  const NavdRun r = run(write("nosim.yaml", sim_yaml_.substr(0, sim_yaml_.find("\nsim:") + 1)));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("nosim.yaml: sim: no --replay, no sensor with a hardware transport and "
                       "no `sim` section: nothing to run"),
            std::string::npos)
      << r.err;
}

TEST_F(NavdConfigErrors, UnknownKey) {
  expect_config_error(edited("unknown.yaml", "filter:\n", "filter:\n  latency_windw_ms: 3\n"),
                      "filter.latency_windw_ms", "unknown key (allowed: ");
  expect_config_error(edited("unknown_top.yaml", "checkpoint:\n", "checkpont:\n"), "checkpont",
                      "unknown key");
}

TEST_F(NavdConfigErrors, WrongType) {
  expect_config_error(
      edited("type.yaml", "cg_iterations_per_step: 5", "cg_iterations_per_step: 2.5"),
      "filter.cg_iterations_per_step", "expected an integer, got '2.5'");
  expect_config_error(
      edited("type_seq.yaml", "url: \"udpm://239.255.76.67:7667?ttl=0\"", "url: [memq]"), "lcm.url",
      "expected a string, got a sequence");
}

TEST_F(NavdConfigErrors, OutOfRange) {
  expect_config_error(edited("range.yaml", "latency_window_ms: 200", "latency_window_ms: -1"),
                      "filter.latency_window_ms", "-1 is not in [0, 60000]");
  expect_config_error(edited("range_period.yaml", "period_s: 30", "period_s: 0"),
                      "checkpoint.period_s", "is not in");
  expect_config_error(
      edited("range_mount.yaml", "lever_arm_m: [0.5, 0.0, 0.3]", "lever_arm_m: [0.5, 0.0, 300]"),
      "sensors[0].mount.lever_arm_m[2]", "300");
}

TEST_F(NavdConfigErrors, MissingFileAndSyntaxError) {
  expect_config_error(dir_ / "does_not_exist.yaml", "<root>", "cannot open file");
  expect_config_error(write("syntax.yaml", "filter: [\n"), "<root>", "YAML syntax error at line 2");
}

TEST_F(NavdConfigErrors, BadCanSignalsFile) {
  const std::string can_sensor =
      "sensors:\n  - {name: dvl_can, type: dvl_can, transport: {type: can, interface: can0, "
      "signals_file: signals.yaml}}\n";
  const fs::path config = edited("can.yaml", "sensors:\n", can_sensor);
  // Missing table.
  expect_config_error(config, "sensors[0].transport.signals_file",
                      "cannot open the CAN config file");
  // A signal of zero bits: the table's own key path follows the sensor's.
  write("signals.yaml",
        "messages:\n  - name: m\n    id: 0x200\n    dlc: 8\n    signals:\n"
        "      - {name: a, start_bit: 0, length: 0, byte_order: intel}\n");
  expect_config_error(config, "sensors[0].transport.signals_file",
                      "messages[0].signals[0].length: 0 is not in 1..64");
}

}  // namespace
