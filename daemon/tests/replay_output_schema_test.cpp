// Every replay output file written by its writer (nav/daemon/replay/output_files.h) and read back
// by the report's reader (nav/report/replay_data.h) through the one schema of
// nav/daemon/replay/output_schema.h; the ReplaySummary's JSON read back field by field; the link
// outcome counting rule shared by the summary and the report.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "nav/daemon/replay/output_files.h"
#include "nav/daemon/replay/output_schema.h"
#include "nav/daemon/replay/replay_summary.h"
#include "nav/report/csv_table.h"
#include "nav/report/metrics.h"
#include "nav/report/replay_data.h"

namespace nav::daemon {
namespace {

namespace fs = std::filesystem;
namespace schema = output_schema;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("nav_replay_output_schema_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string first_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

LinkRecord link(std::int64_t t_us, std::uint64_t frame_i, std::uint64_t frame_j, int state_i,
               int state_j, LinkOutcome outcome, double mahalanobis_sq, bool is_outlier) {
  LinkRecord l;
  l.t_us = t_us;
  l.frame_i = frame_i;
  l.frame_j = frame_j;
  l.state_i = state_i;
  l.state_j = state_j;
  l.outcome = outcome;
  l.mahalanobis_sq = mahalanobis_sq;
  l.is_outlier = is_outlier;
  return l;
}

/// A value that needs all 17 significant digits to survive the text round trip.
double awkward(int k) { return (k + 1) * (1.0 / 3.0) + 1e-13 * k; }

TEST(OutputSchema, EnumsCountTheColumnsAndNamesAreUnique) {
  EXPECT_EQ(schema::TrajectoryCsv::slam().size(), std::size_t{schema::TrajectoryCsv::kCount});
  EXPECT_EQ(schema::TrajectoryCsv::dead_reckoning().header(),
            schema::TrajectoryCsv::slam().header());
  EXPECT_EQ(schema::StatesCsv::schema().size(), std::size_t{schema::StatesCsv::kCount});
  EXPECT_EQ(schema::StatesCsv::schema().size(), 9u + 3u * 36u);
  EXPECT_EQ(schema::LinksCsv::schema().size(), std::size_t{schema::LinksCsv::kCount});
  EXPECT_EQ(schema::ProposalsCsv::schema().size(), std::size_t{schema::ProposalsCsv::kCount});
  EXPECT_EQ(schema::InformationBlocksCsv::schema().size(),
            std::size_t{schema::InformationBlocksCsv::kCount});
  EXPECT_EQ(schema::LogdetCsv::schema().size(), std::size_t{schema::LogdetCsv::kCount});
  // The documented headers (hil-tests/README.md "Replay output directory").
  EXPECT_EQ(schema::TrajectoryCsv::slam().header(),
            "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,var_x,var_y,var_z,var_heading");
  EXPECT_EQ(schema::LinksCsv::schema().header(),
            "t_us,frame_i,frame_j,state_i,state_j,outcome,mahalanobis_sq,is_outlier");
  const schema::CsvSchema& states = schema::StatesCsv::schema();
  EXPECT_EQ(states.name(schema::StatesCsv::cell(schema::StatesCsv::kBound, 0, 0)), "b00");
  EXPECT_EQ(states.name(schema::StatesCsv::cell(schema::StatesCsv::kExact, 2, 5)), "e25");
  EXPECT_EQ(states.name(schema::StatesCsv::cell(schema::StatesCsv::kInitialBound, 5, 5)), "i55");
  EXPECT_EQ(states.columns()[schema::StatesCsv::cell(schema::StatesCsv::kBound, 0, 3)].unit,
            "m*rad");
  EXPECT_THROW(states.name(states.size()), std::out_of_range);
  for (const schema::CsvSchema* csv : {&states, &schema::LinksCsv::schema()}) {
    std::set<std::string> names;
    for (const schema::Column& c : csv->columns()) {
      EXPECT_TRUE(names.insert(c.name).second) << csv->file() << ": " << c.name;
    }
  }
}

TEST(OutputSchema, EveryFileWrittenIsReadBackThroughTheSameSchema) {
  const fs::path dir = fresh_dir("round_trip");

  std::vector<ImageRecord> images(3);
  for (int k = 0; k < 3; ++k) {
    images[k].t_us = 1'000'000 + 250'000 * k;
    for (int d = 0; d < 12; ++d) images[k].robot_mean(d) = awkward(10 * k + d) - 2.0;
    images[k].robot_covariance = core::Mat12::Identity() * awkward(k);
    images[k].robot_covariance(5, 5) = 1e-5 * awkward(k + 7);
  }
  write_trajectory_csv(images, dir / schema::TrajectoryCsv::slam().file());
  write_trajectory_csv(images, dir / schema::TrajectoryCsv::dead_reckoning().file());

  std::vector<StateCheck> states(2);
  for (int k = 0; k < 2; ++k) {
    StateCheck& s = states[k];
    s.state = k + 1;
    s.image = &images[k];
    for (int d = 0; d < 12; ++d) s.mean(d) = awkward(d + k);
    for (int c = 0; c < 36; ++c) {
      s.bound(c / 6, c % 6) = awkward(c);
      s.exact(c / 6, c % 6) = -awkward(c + k);
      s.initial_bound(c / 6, c % 6) = 1e3 * awkward(c);
    }
  }
  states[1].image = nullptr;  // unknown image: frame_id and t_us -1
  write_states_csv(states, dir / schema::StatesCsv::schema().file());

  std::vector<LinkRecord> links = {
      link(5, 1, 4, 1, 3, LinkOutcome::kAccepted, awkward(3), false),
      link(6, 2, 4, 2, 3, LinkOutcome::kGated, awkward(9), true),
      link(7, 3, 5, 2, -1, LinkOutcome::kNotRegistered, -1.0, false)};  // empty mahalanobis_sq
  write_links_csv(links, dir / schema::LinksCsv::schema().file());

  std::vector<ProposalRecord> proposals(2);
  proposals[0].frame_id = 4;
  proposals[0].candidates = 3;
  proposals[1].frame_id = 5;
  write_proposals_csv(proposals, {{2, 1}}, dir / schema::ProposalsCsv::schema().file());

  core::InformationMatrix info(12);
  for (int b = 0; b < 3; ++b) info.add_block();
  info.add_to_block(0, 2, Eigen::MatrixXd::Ones(12, 12));
  write_information_blocks_csv(info, dir / schema::InformationBlocksCsv::schema().file());

  write_logdet_csv({{0, 1, awkward(4), -awkward(5)}, {0, 2, -1e-300, awkward(6)}},
                   dir / schema::LogdetCsv::schema().file());

  ReplaySummary summary;
  summary.wall_s = awkward(2);
  summary.realtime_factor = 421.5;
  summary.dive_dir = "dive";
  write_summary_json(summary.to_json(), dir / schema::kSummaryFile);

  // Headers are the schemas' (information_blocks.csv: after its comment line).
  for (const schema::CsvSchema* csv :
       {&schema::TrajectoryCsv::slam(), &schema::TrajectoryCsv::dead_reckoning(),
        &schema::StatesCsv::schema(), &schema::LinksCsv::schema(), &schema::ProposalsCsv::schema(),
        &schema::LogdetCsv::schema()}) {
    EXPECT_EQ(first_line(dir / csv->file()), csv->header()) << csv->file();
  }
  EXPECT_EQ(first_line(dir / schema::InformationBlocksCsv::schema().file()),
            "# block_dim 12 num_blocks 3");

  const report::ReplayOutput out = report::read_replay_output(dir);
  ASSERT_EQ(out.trajectory.size(), 3u);
  ASSERT_EQ(out.dead_reckoning.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(out.trajectory[k].t_us, images[k].t_us);
    EXPECT_EQ(out.trajectory[k].pose, images[k].robot_mean.head<6>()) << k;  // bit-exact
    EXPECT_EQ(out.dead_reckoning[k].pose, images[k].robot_mean.head<6>()) << k;
  }
  const report::CsvTable traj = report::CsvTable::read(dir / "trajectory.csv");
  EXPECT_EQ(traj.number(2, schema::TrajectoryCsv::kVarHeading), images[2].robot_covariance(5, 5));
  EXPECT_EQ(traj.number(1, schema::TrajectoryCsv::kVarZ), images[1].robot_covariance(2, 2));

  ASSERT_EQ(out.states.size(), 2u);
  EXPECT_EQ(out.states[0].state_id, 1);
  EXPECT_EQ(out.states[0].frame_id, static_cast<long long>(images[0].frame_id));
  EXPECT_EQ(out.states[0].t_us, images[0].t_us);
  EXPECT_EQ(out.states[1].frame_id, -1);
  EXPECT_EQ(out.states[1].t_us, -1);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(out.states[k].pose, states[k].mean.head<6>()) << k;
    EXPECT_EQ(out.states[k].bound, states[k].bound) << k;
    EXPECT_EQ(out.states[k].exact, states[k].exact) << k;
    ASSERT_TRUE(out.states[k].initial.has_value());
    EXPECT_EQ(*out.states[k].initial, states[k].initial_bound) << k;
  }

  ASSERT_EQ(out.links.size(), 3u);
  EXPECT_EQ(out.links[0].outcome, "accepted");
  EXPECT_EQ(out.links[0].mahalanobis_sq, awkward(3));
  EXPECT_EQ(out.links[1].outcome, "gated");
  EXPECT_TRUE(out.links[1].is_outlier);
  EXPECT_EQ(out.links[1].frame_i, 2);
  EXPECT_EQ(out.links[2].outcome, "not_registered");
  EXPECT_TRUE(std::isnan(out.links[2].mahalanobis_sq));
  EXPECT_EQ(out.links[2].state_j, -1);

  EXPECT_EQ(out.proposal_rows, 2);
  ASSERT_TRUE(out.blocks.has_value());
  EXPECT_EQ(out.blocks->block_dim, 12);
  EXPECT_EQ(out.blocks->num_blocks, 3);
  const std::vector<std::pair<long long, long long>> expected_blocks = {
      {0, 0}, {0, 2}, {1, 1}, {2, 2}};
  EXPECT_EQ(out.blocks->blocks, expected_blocks);

  ASSERT_EQ(out.logdet.size(), 2u);
  EXPECT_EQ(out.logdet[0].state_j, 1);
  EXPECT_EQ(out.logdet[0].ours, awkward(4));
  EXPECT_EQ(out.logdet[0].markov_blanket, -awkward(5));
  EXPECT_EQ(out.logdet[1].ours, -1e-300);

  EXPECT_EQ(out.summary.wall_s, awkward(2));
  EXPECT_EQ(out.summary.realtime_factor, 421.5);
  EXPECT_EQ(out.summary.dive_dir, std::optional<std::string>("dive"));
}

TEST(OutputSchema, LogdetNanRowIsRejectedWithFileLineAndColumn) {
  // NaN log-det ratios are written as "nan" (README: NaN where a log det is undefined); the
  // report's reader refuses them, naming where.
  const fs::path dir = fresh_dir("logdet_nan");
  write_logdet_csv({{0, 2, std::numeric_limits<double>::quiet_NaN(), 1.0}}, dir / "logdet.csv");
  try {
    report::read_logdet(dir / "logdet.csv");
    FAIL() << "no error";
  } catch (const report::ReportError& e) {
    EXPECT_NE(std::string(e.what()).find("logdet.csv:2: column 'ours'"), std::string::npos)
        << e.what();
  }
}

ReplaySummary full_summary() {
  ReplaySummary s;
  s.dive_dir = "/dives/a";
  s.log = "/dives/a/dive.lcmlog";
  s.config = "/dives/a/config.yaml";
  s.images = 866;
  s.delayed_states = 866;
  s.camera_links = 8195;
  s.wall_s = 19.75;
  s.log_span_s = 8321.5;
  s.realtime_factor = s.log_span_s / s.wall_s;
  s.analysis_s = awkward(1);
  s.final_pose << 1, 2, 3, 0.1, -0.2, awkward(5);
  s.final_pose_running = core::Vec6::Constant(awkward(8));
  s.has_dead_reckoning = true;  // dead_reckoning_final_pose: null (no state yet)
  s.max_cg_relative_residual = 1e-7;
  s.cg_iterations_per_image = 5;
  s.recovery = "synchronous at each image (deterministic)";
  s.candidates = 20000;
  s.links.proposed = 8633;
  s.links.accepted = 8195;
  s.links.gated = 438;
  s.links.outliers_rejected = 438;
  s.camera_gate_chi2_5dof = 20.515;
  s.registrations = 9000;
  s.registration_outliers = 438;
  s.time_of_use_checks = 109;
  s.time_of_use_s = awkward(2);
  s.time_of_use_conservative_fraction = 1.0;
  s.time_of_use_joint_conservative_fraction = 1.0;
  s.time_of_use_worst_min_eigenvalue = -awkward(6);
  s.logdet_ratio_relative_ours_median = awkward(3);
  s.logdet_ratio_relative_markov_blanket_median = -awkward(4);
  s.conservative_fraction = 1.0;
  s.states_checked = 866;
  s.measurements = 123456;
  s.late_dropped = 3;
  s.rejected_updates = {{"dvl", 4}, {"heading", 0}};
  s.dead_reckoning_rejected_updates = {{"dvl", 9}, {"depth", 1}};
  return s;
}

TEST(ReplaySummary, JsonRoundTripKeepsEveryField) {
  const ReplaySummary s = full_summary();
  const std::string text = s.to_json();
  EXPECT_EQ(text.find('\n'), std::string::npos) << "one line";
  const ReplaySummary r = ReplaySummary::from_json(text, "summary.json");
  EXPECT_EQ(r.to_json(), text);
  EXPECT_EQ(r.dive_dir, s.dive_dir);
  EXPECT_EQ(r.realtime_factor, s.realtime_factor);
  EXPECT_EQ(r.final_pose, s.final_pose);
  ASSERT_TRUE(r.final_pose_running.has_value());
  EXPECT_EQ(*r.final_pose_running, *s.final_pose_running);
  EXPECT_TRUE(r.has_dead_reckoning);
  EXPECT_FALSE(r.dead_reckoning_final_pose.has_value());
  EXPECT_EQ(r.links.proposed, 8633u);
  EXPECT_EQ(r.links.outliers_rejected, 438u);
  EXPECT_EQ(r.late_dropped, 3u);
  EXPECT_EQ(r.rejected_updates, s.rejected_updates);
  EXPECT_EQ(r.dead_reckoning_rejected_updates, s.dead_reckoning_rejected_updates);
  EXPECT_EQ(r.time_of_use_checks, 109u);
  EXPECT_EQ(r.time_of_use_s, s.time_of_use_s);
  EXPECT_EQ(r.time_of_use_worst_min_eigenvalue, s.time_of_use_worst_min_eigenvalue);
  EXPECT_EQ(r.logdet_ratio_relative_ours_median, s.logdet_ratio_relative_ours_median);
  EXPECT_EQ(r.logdet_ratio_relative_markov_blanket_median,
            s.logdet_ratio_relative_markov_blanket_median);

  // The keys scripts and tests read (README.md "navtool replay"), with their values.
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["images"], 866);
  EXPECT_EQ(j["camera_links"], 8195);
  EXPECT_EQ(j["links_gated"], 438);
  EXPECT_EQ(j["registration_failed"], 0);
  EXPECT_TRUE(j["dead_reckoning_final_pose"].is_null());
  EXPECT_EQ(j["final_pose"]["heading_rad"], awkward(5));
  EXPECT_EQ(j["error"], "");
  EXPECT_FALSE(j.contains("outliers_proposed"));
  for (const char* key : {"proposals_per_image_mean", "proposal_recall", "published_nees_mean",
                          "published_nees_exceed_99_fraction"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["rejected_updates"]["dvl"], 4);
  EXPECT_EQ(j["dead_reckoning_rejected_updates"]["dvl"], 9);
  EXPECT_EQ(j.size(), 52u);  // every key of today's summary.json
}

TEST(ReplaySummary, PartialOrOddSummariesKeepDefaults) {
  const ReplaySummary r =
      ReplaySummary::from_json(R"({"wall_s": 2, "images": 40, "error": 7})", "s.json");
  EXPECT_EQ(r.wall_s, 2.0);
  EXPECT_EQ(r.images, 40u);
  EXPECT_TRUE(std::isnan(r.realtime_factor));
  EXPECT_FALSE(r.dive_dir.has_value());
  EXPECT_FALSE(r.has_dead_reckoning);
  EXPECT_EQ(r.error, "");  // wrong type: default kept
  const nlohmann::json j = nlohmann::json::parse(ReplaySummary().to_json());
  EXPECT_TRUE(j["wall_s"].is_null());
  EXPECT_FALSE(j.contains("dive_dir"));
  EXPECT_FALSE(j.contains("dead_reckoning_final_pose"));
  EXPECT_FALSE(j.contains("dead_reckoning_rejected_updates"));
  EXPECT_THROW(ReplaySummary::from_json("[1, 2]", "s.json"), std::invalid_argument);
  try {
    ReplaySummary::from_json("{\"wall_s\": ", "out/summary.json");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("out/summary.json: not valid JSON", 0), 0u) << e.what();
  }
}

TEST(ReplaySummary, BriefReportIsOneLineWithTheHeadlineNumbers) {
  ReplaySummary s = full_summary();
  EXPECT_EQ(s.brief_report(),
            "replay: 866 images, 866 delayed states, 8195 of 8633 proposed links accepted, 438 "
            "of 438 outliers rejected, conservative 1, 19.8 s wall (421x real time), ok");
  s.error = "filter: recovery failed at image 12";
  const std::string brief = s.brief_report();
  EXPECT_EQ(brief.substr(brief.size() - 42), "error: filter: recovery failed at image 12");
}

TEST(LinkOutcomeCounts, OneRuleForTheSummaryAndTheReport) {
  LinkOutcomeCounts c;
  c.add("accepted", false);
  c.add("accepted", true);
  c.add("gated", true);
  c.add("registration_failed", false);
  c.add("not_registered", true);
  EXPECT_EQ(c.proposed, 5u);
  EXPECT_EQ(c.accepted, 2u);
  EXPECT_EQ(c.gated, 1u);
  EXPECT_EQ(c.registration_failed, 1u);
  EXPECT_EQ(c.not_registered, 1u);
  EXPECT_EQ(c.outliers_proposed, 3u);
  EXPECT_EQ(c.outliers_accepted, 1u);
  EXPECT_EQ(c.outliers_rejected, 2u);
  EXPECT_THROW(c.add("rejected", false), std::invalid_argument);
  EXPECT_EQ(c.proposed, 5u) << "a refused outcome is not counted";

  // The report's count_links goes through the same rule and adds the distinct accepted pairs.
  std::vector<report::ProposedLink> links(3);
  links[0].outcome = links[1].outcome = "accepted";
  links[0].state_i = links[1].state_j = 1;
  links[0].state_j = links[1].state_i = 4;  // the same pair twice
  links[2].outcome = "gated";
  links[2].is_outlier = true;
  const report::LinkCounts r = report::count_links(links);
  EXPECT_EQ(r.proposed, 3u);
  EXPECT_EQ(r.accepted, 2u);
  EXPECT_EQ(r.camera_links, 1u);
  EXPECT_EQ(r.outliers_rejected, 1u);
}

}  // namespace
}  // namespace nav::daemon
