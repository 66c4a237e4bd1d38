// navtool fault-campaign: the fault campaign of docs/faults.md (library hil-tests/campaign,
// nav::campaign::run_campaign): every scenario plays a simulated dive at real time through the
// HIL player to the real navd in live mode with one fault (sensor faults in the played bytes,
// host faults: CPU saturation, multicast route removed, checkpoint filesystem full, SIGKILL and
// restart) and measures detection in health, errors and NEES against the truth, the map's RMS.
// Writes OUT/faults.md (the table) and OUT/faults.json; prints the JSON on stdout.
// Exit status 0 when every scenario passed, 1 otherwise. Needs root for the private network and
// mount namespaces (else the host network, no camera, and the disk-full scenario cannot mount).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "nav/campaign/fault_campaign.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {
namespace fs = std::filesystem;

struct FaultCampaignArgs {
  std::string out;
  std::string navd;
  std::string config = "config/sim.yaml";
  bool short_version = false;
  std::vector<std::string> only;
  std::uint64_t seed = 7;
};

/// navd beside this navtool (both in <build>/bin), else "navd" must be given.
fs::path default_navd() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self.parent_path() / "navd";
}

void run_fault_campaign(const FaultCampaignArgs& args) {
  campaign::CampaignOptions o;
  o.out_dir = args.out;
  o.navd_path = args.navd.empty() ? default_navd() : fs::path(args.navd);
  o.sim_config = args.config;
  o.short_version = args.short_version;
  o.only = args.only;
  o.seed = args.seed;
  if (!fs::exists(o.navd_path)) {
    throw CommandError(
        "fault-campaign: navd not found at " + o.navd_path.string() + " (give --navd)", 2);
  }
  if (!fs::exists(o.sim_config)) {
    throw CommandError("fault-campaign: " + o.sim_config.string() + ": no such config", 2);
  }
  std::vector<campaign::ScenarioResult> results;
  try {
    results = campaign::run_campaign(o);
  } catch (const std::exception& e) {
    throw CommandError(std::string("fault-campaign: ") + e.what());
  }
  std::cout << campaign::campaign_json(results).dump(2) << std::endl;
  std::fprintf(stderr, "fault-campaign: table in %s\n", (o.out_dir / "faults.md").c_str());
  for (const campaign::ScenarioResult& r : results) {
    if (!r.pass) throw CommandExit{1};
  }
}

void add_fault_campaign(CLI::App& app) {
  auto args = std::make_shared<FaultCampaignArgs>();
  CLI::App* cmd = app.add_subcommand(
      "fault-campaign",
      "Fault campaign against navd live (docs/faults.md): each scenario plays a simulated dive "
      "at real time through the HIL player with one fault and measures detection, errors, NEES "
      "and the map; writes OUT/faults.md and OUT/faults.json.");
  cmd->add_option("--out", args->out, "output directory")->required();
  cmd->add_option("--navd", args->navd, "navd binary (default: beside navtool)");
  cmd->add_option("--config", args->config, "simulator config (default config/sim.yaml)");
  cmd->add_flag("--short", args->short_version, "the CI's 3 scenarios on a 43-s dive");
  cmd->add_option("--only", args->only, "run only these scenarios (names as in the table)");
  cmd->add_option("--seed", args->seed, "seed of the dives and of the kill moment (default 7)");
  cmd->callback([args] { run_fault_campaign(*args); });
}

const CommandRegistration kRegister{"fault-campaign", add_fault_campaign};

}  // namespace
}  // namespace nav::tool
