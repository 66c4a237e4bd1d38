// "No allocation proportional to map size in predict/update" (docs/architecture.md: no allocation
// in the filter's hot path after start-up): after a warm-up, marginalising predicts, unary
// updates and camera-link updates perform no heap allocation at all. Counted by interposing
// malloc (glibc's __libc_malloc underneath), which also sees operator new and Eigen's
// dynamic allocations. Skipped under AddressSanitizer, which owns malloc.
#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <numbers>

#include "nav/core/filter/esdf.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/models/unary_models.h"

#if defined(__SANITIZE_ADDRESS__)
#define NAV_ALLOC_COUNTING 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NAV_ALLOC_COUNTING 0
#endif
#endif
#ifndef NAV_ALLOC_COUNTING
#define NAV_ALLOC_COUNTING 1
#endif

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
}  // namespace

#if NAV_ALLOC_COUNTING
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* malloc(size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_realloc(p, n);
}
}
#endif

namespace nav::core {
namespace {

TEST(EsdfAllocation, PredictAndUpdatesDoNotAllocateAfterWarmUp) {
  if (!NAV_ALLOC_COUNTING) GTEST_SKIP() << "malloc is owned by the sanitizer runtime";
  Esdf f(12);
  Vec12 x0 = Vec12::Zero();
  x0[kHeading] = std::numbers::pi / 2;
  x0[kU] = 1.0;
  x0[kZ] = 10.0;
  ASSERT_TRUE(f.initialize(x0, 0.01 * Mat12::Identity()).ok());
  const ConstantVelocityModel model;
  for (int k = 0; k < 200; ++k) ASSERT_TRUE(f.predict(model, 0.5, true).ok());
  CameraRelativePoseModel cam;
  cam.x_body_camera << 0, 0, 0, 0, 0, std::numbers::pi / 2;
  const MeasCov R5 = 1e-4 * MeasCov::Identity(5, 5);
  const MeasVec z5 = cam.predict(f.mean_block(50), f.mean_block(150));
  const DvlVelocityModel dvl;
  const MeasVec z3 = dvl.predict(f.mean_block(0));
  const MeasCov R3 = 1e-4 * MeasCov::Identity(3, 3);
  auto cycle = [&] {
    bool ok = f.predict(model, 0.5, false).ok();
    ok = ok && f.update(dvl, 0, z3, R3).ok();
    ok = ok && f.update(cam, 50, 150, z5, R5).ok();
    return ok;
  };
  ASSERT_TRUE(cycle());  // warm-up: scratch buffers, the (50, 150) block
  g_allocations = 0;
  g_counting = true;
  bool ok = true;
  for (int k = 0; k < 100; ++k) ok = ok && cycle();
  g_counting = false;
  ASSERT_TRUE(ok);
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations in 100 predict/update cycles";
}

}  // namespace
}  // namespace nav::core
