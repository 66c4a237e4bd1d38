// Images and oracle registrations of a simulated dive: images.csv and NAV_IMAGE agree, the
// camera-off transit has no images, imaging resumes with a loop closure to the first leg,
// measured registration errors are consistent with the stated covariance (NEES ~ 5), and the
// outlier rate is as asked.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <map>
#include <variant>

#include "nav/core/geometry/rotation.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

struct Dive {
  SimSummary summary;
  std::vector<std::vector<double>> images;  // images.csv rows
  std::vector<navlcm::image_metadata_t> nav_images;
  std::vector<navlcm::registration_t> registrations;
  std::filesystem::path dir;
};

Dive simulate(const std::string& name, double outlier_rate, int images) {
  Dive d;
  d.dir = scratch_dir(name);
  SimOptions o = sim_options(d.dir, 5, images);
  o.oracle.outlier_rate = outlier_rate;
  d.summary = simulate_dive(o, sim_config_path().string());
  std::string header;
  d.images = read_csv(d.dir / "images.csv", &header);
  EXPECT_EQ(header,
            "frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,altitude_m,camera_on");
  for (daemon::DiveLogEvent& e : read_log(d.dir)) {
    if (auto* m = std::get_if<navlcm::image_metadata_t>(&e)) d.nav_images.push_back(*m);
    if (auto* r = std::get_if<navlcm::registration_t>(&e)) d.registrations.push_back(*r);
  }
  return d;
}

const Dive& dive() {
  static const Dive d = simulate("oracle", 0.05, 150);
  return d;
}

core::Vec12 pose_of(const std::vector<double>& row) {
  core::Vec12 x = core::Vec12::Zero();
  for (int i = 0; i < 6; ++i) x[i] = row[static_cast<std::size_t>(i + 2)];
  return x;
}

core::CameraRelativePoseModel camera_model() {
  const daemon::NavdConfig cfg = daemon::load_config_file(sim_config_path().string());
  return RegistrationOracle(CameraGeometry::from_config(cfg.sensors[4]), {}, 1).model();
}

double nees(const navlcm::registration_t& r, const Dive& d,
            const core::CameraRelativePoseModel& m) {
  const core::Vec12 xi = pose_of(d.images[static_cast<std::size_t>(r.frame_id_i)]);
  const core::Vec12 xj = pose_of(d.images[static_cast<std::size_t>(r.frame_id_j)]);
  const core::MeasVec z_true = m.predict(xi, xj);
  Vec5 e;
  Mat5 C;
  for (int a = 0; a < 5; ++a) {
    e[a] = core::wrap_angle(r.measurement[a] - z_true[a]);
    for (int b = 0; b < 5; ++b) C(a, b) = r.covariance[a * 5 + b];
  }
  return e.dot(C.ldlt().solve(e));
}

TEST(SimOracle, ImagesCsvAndNavImageAgree) {
  const Dive& d = dive();
  ASSERT_EQ(d.images.size(), 150u);
  ASSERT_EQ(d.nav_images.size(), d.images.size());
  EXPECT_EQ(d.summary.images, 150);
  for (std::size_t k = 0; k < d.images.size(); ++k) {
    const navlcm::image_metadata_t& m = d.nav_images[k];
    EXPECT_EQ(m.frame_id, static_cast<std::int64_t>(k));
    EXPECT_EQ(d.images[k][0], static_cast<double>(k));
    EXPECT_EQ(m.time_of_validity_us, static_cast<std::int64_t>(d.images[k][1]));
    EXPECT_GE(m.utime, realtime_of(m.time_of_validity_us));
    EXPECT_LE(m.utime, realtime_of(m.time_of_validity_us) + 5000);
    EXPECT_EQ(m.state_id, -1);
    EXPECT_EQ(m.width, 1280);
    EXPECT_EQ(m.height, 1024);
    EXPECT_EQ(d.images[k][9], 1.0);  // camera_on
  }
}

TEST(SimOracle, CameraOffTransitHasNoImagesAndImagingResumesWithALoopClosure) {
  const Dive& d = dive();
  const std::int64_t f0 = d.summary.first_frame_after_transit;
  ASSERT_GT(f0, 10);
  int long_gaps = 0;
  for (std::size_t k = 1; k < d.images.size(); ++k) {
    const double gap_s = (d.images[k][1] - d.images[k - 1][1]) * 1e-6;
    if (static_cast<std::int64_t>(k) == f0) {
      EXPECT_GT(gap_s, 3 * 8.0) << "the transit takes several image periods";
      // The vehicle moved from the stern leg's last line back past midship meanwhile.
      EXPECT_GT(d.images[k][2] - d.images[k - 1][2], 5.0);
      ++long_gaps;
    } else {
      EXPECT_NEAR(gap_s, 8.0, 1e-9) << "frame " << k;
    }
  }
  EXPECT_EQ(long_gaps, 1);
  // A successful registration of an image after the transit with one of the first line's.
  const double first_leg_s = (d.images[static_cast<std::size_t>(f0)][1] - d.images[0][1]) * 1e-6;
  int loop_closures = 0;
  for (const navlcm::registration_t& r : d.registrations) {
    if (!r.success || r.frame_id_j < f0 || r.frame_id_j > f0 + 12) continue;
    const double gap_s = (d.images[static_cast<std::size_t>(r.frame_id_j)][1] -
                          d.images[static_cast<std::size_t>(r.frame_id_i)][1]) *
                         1e-6;
    if (r.frame_id_i < 15 && gap_s > 0.8 * first_leg_s) ++loop_closures;
  }
  std::printf("frame %lld resumes imaging; %d loop closures to the first line\n",
              static_cast<long long>(f0), loop_closures);
  EXPECT_GE(loop_closures, 3);
}

TEST(SimOracle, RegistrationsAreWellFormedAndCounted) {
  const Dive& d = dive();
  ASSERT_FALSE(d.registrations.empty());
  EXPECT_EQ(static_cast<std::int64_t>(d.registrations.size()), d.summary.registrations);
  std::int64_t ok = 0, outliers = 0;
  for (const navlcm::registration_t& r : d.registrations) {
    EXPECT_LT(r.frame_id_i, r.frame_id_j);
    EXPECT_EQ(r.utime, d.nav_images[static_cast<std::size_t>(r.frame_id_j)].utime)
        << "written at the later image's time";
    EXPECT_GT(r.overlap_fraction, 0.0);
    EXPECT_LE(r.overlap_fraction, 1.0 + 1e-9);
    ok += r.success;
    outliers += r.is_outlier;
    EXPECT_TRUE(r.success || !r.is_outlier);
  }
  EXPECT_EQ(ok, d.summary.registrations_succeeded);
  EXPECT_EQ(outliers, d.summary.outliers_injected);
  EXPECT_GT(ok, 2 * d.summary.images) << "several links per image, as in the paper";
  EXPECT_LT(ok, d.summary.registrations) << "some registrations fail";
}

TEST(SimOracle, GoodRegistrationsAreConsistentWithTheirCovariance) {
  const Dive& d = dive();
  const core::CameraRelativePoseModel m = camera_model();
  double sum = 0.0;
  long n = 0, far_outliers = 0, outliers = 0;
  for (const navlcm::registration_t& r : d.registrations) {
    if (!r.success) continue;
    const double q = nees(r, d, m);
    if (r.is_outlier) {
      ++outliers;
      far_outliers += q > 100.0;
    } else {
      sum += q;
      ++n;
    }
  }
  ASSERT_GT(n, 500);
  std::printf("mean NEES %.3f over %ld good links; %ld outliers\n", sum / n, n, outliers);
  // Mean of n chi2(5) draws: 5 +- 4.4 sigma of sqrt(10 / n).
  EXPECT_NEAR(sum / n, 5.0, 4.4 * std::sqrt(10.0 / n)) << n << " good links";
  EXPECT_EQ(far_outliers, outliers) << "every outlier is far off";
}

TEST(SimOracle, OutlierRateIsAsAsked) {
  const Dive d = simulate("outliers", 0.2, 100);
  const double n = static_cast<double>(d.summary.registrations_succeeded);
  ASSERT_GT(n, 300);
  const double rate = d.summary.outliers_injected / n;
  EXPECT_NEAR(rate, 0.2, 4.0 * std::sqrt(0.2 * 0.8 / n));
  const Dive none = simulate("no_outliers", 0.0, 40);
  EXPECT_EQ(none.summary.outliers_injected, 0);
}

}  // namespace
}  // namespace nav::sim::test
