// The per-measurement path must not allocate (docs/architecture.md "Conventions"): predicting every
// model with its Jacobian, SSC compounding and the process model are run with malloc instrumented.
// malloc is interposed in this executable (glibc's __libc_malloc does the work); under
// AddressSanitizer, which owns malloc itself, the test skips.

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>

#include "nav/core/geometry/pose.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/models/unary_models.h"

#if defined(__SANITIZE_ADDRESS__)
#define NAV_GEOM_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NAV_GEOM_ASAN 1
#endif
#endif

namespace {
bool g_counting = false;
std::size_t g_allocations = 0;
}  // namespace

#if !defined(NAV_GEOM_ASAN) && defined(__GLIBC__)
extern "C" void* __libc_malloc(std::size_t size);
extern "C" void* malloc(std::size_t size) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(size);
}
#define NAV_GEOM_COUNTS_MALLOC 1
#endif

namespace nav::core {
namespace {

/// Runs f with malloc counted; returns the number of allocations it made.
template <class F>
std::size_t count_allocations(F&& f) {
  g_allocations = 0;
  g_counting = true;
  f();
  g_counting = false;
  return g_allocations;
}

TEST(MeasurementModelsNoAlloc, CounterSeesAnAllocation) {
#ifndef NAV_GEOM_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not interposable here (sanitizer build or not glibc)";
#else
  // The instrument itself must work, or the test below would pass vacuously.
  const std::size_t n = count_allocations([] {
    Eigen::VectorXd v(100);
    v.setOnes();
    EXPECT_EQ(v.sum(), 100.0);
  });
  EXPECT_GE(n, 1u);
#endif
}

TEST(MeasurementModelsNoAlloc, PredictionsWithJacobiansDoNotAllocate) {
#ifndef NAV_GEOM_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not interposable here (sanitizer build or not glibc)";
#else
  DvlVelocityModel dvl;
  dvl.p_body_dvl_m << 1, 0.2, 0.3;
  DepthModel depth;
  depth.p_body_sensor_m << 0.5, 0, 0.1;
  CameraRelativePoseModel camera;
  camera.x_body_camera << 0.5, 0, 0.3, 0, 0, 1.5707963;
  const ConstantVelocityModel process;
  Vec12 x_a, x_b;
  x_a << 1, 2, 3, 0.1, 0.2, 0.3, 1, 0, 0, 0.01, 0.02, 0.03;
  x_b << 4, 2, 3, 0.1, 0.1, 0.4, 1, 0, 0, 0.01, 0.02, 0.03;
  Eigen::VectorXd state(24);  // blocks as segments of a dynamic state vector
  state << x_a, x_b;

  MeasJac H_a, H_b;
  Mat6x12 J;
  Mat12 F;
  double sink = 0.0;
  const std::size_t n = count_allocations([&] {
    for (int i = 0; i < 10; ++i) {
      sink += dvl.predict(state.segment(0, 12), &H_a)[0] + H_a(0, kU);
      sink += HeadingModel{}.predict(x_a, &H_a)[0];
      sink += AttitudeModel{}.predict(x_a.head<6>(), &H_a)[1];
      sink += depth.predict(x_a, &H_a)[0];
      sink +=
          RelativePose6Model{}.predict(state.segment(0, 12), state.segment(12, 12), &H_a, &H_b)[0];
      sink += camera.predict(x_a, x_b, &H_a, &H_b)[0] + H_b(4, kHeading);
      sink += head_to_tail(x_a.head<6>(), x_b.head<6>(), &J)[0];
      sink += tail_to_tail(x_a.head<6>(), x_b.head<6>(), &J)[0];
      sink += process.predict(x_a, 0.1, &F)[0] + process.process_noise(x_a, 0.1)(0, 0);
    }
  });
  EXPECT_EQ(n, 0u);
  EXPECT_TRUE(std::isfinite(sink));
#endif
}

}  // namespace
}  // namespace nav::core
