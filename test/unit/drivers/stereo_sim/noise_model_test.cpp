#include "drivers/stereo_sim/noise_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace qnav::sim {
namespace {

Vec3d error_of(const Mat3d& measured, const Mat3d& truth) {
  const Eigen::AngleAxisd aa(truth.transpose() * measured);
  return aa.axis() * aa.angle();
}

TEST(NoiseModel, NoneIsExact) {
  NoiseModel n(NoiseConfig::none(), 1);
  const Mat3d R = rotation_from_rpy(0.1, 0.2, 0.3);
  n.advance_to(1000.0);
  EXPECT_LT((n.measure_attitude(R) - R).norm(), 1e-12);
  EXPECT_EQ(n.measure_translation(Vec3d(0.2, 0, 0)), Vec3d(0.2, 0, 0));
}

TEST(NoiseModel, InstantaneousErrorHasSigmaM) {
  NoiseConfig c = NoiseConfig::small();
  c.sigma_b_rad = c.sigma_s_rad = 0.0;
  NoiseModel n(c, 2);
  double s2 = 0.0;
  const int k = 4000;
  for (int i = 0; i < k; ++i) s2 += error_of(n.measure_attitude(Mat3d::Identity()), Mat3d::Identity()).squaredNorm();
  EXPECT_NEAR(std::sqrt(s2 / (3.0 * k)), deg_to_rad(0.1), deg_to_rad(0.005));
  EXPECT_NEAR(n.measure_translation(Vec3d(0.2, 0, 0)).x(), 0.22, 1e-12);
}

TEST(NoiseModel, DriftGrowsWithTimeAndCalibrationZeroesIt) {
  // One 100 s block adds 10 b + sum_k (11 - k) s_k per axis: variance 100 sigma_b^2 + 385 sigma_s^2.
  // Blocks are independent, so over 1000 s the RMS grows by sqrt(10).
  NoiseConfig c = NoiseConfig::small();
  double rms100 = 0.0, rms1000 = 0.0;
  const int seeds = 200;
  for (int s = 0; s < seeds; ++s) {
    NoiseModel n(c, 100 + s);
    n.advance_to(100.0);
    rms100 += n.drift_rad().squaredNorm();
    n.advance_to(1000.0);
    rms1000 += n.drift_rad().squaredNorm();
  }
  rms100 = std::sqrt(rms100 / seeds);
  rms1000 = std::sqrt(rms1000 / seeds);
  const double expected100 = std::sqrt(3.0 * (100.0 * c.sigma_b_rad * c.sigma_b_rad + 385.0 * c.sigma_s_rad * c.sigma_s_rad));
  EXPECT_NEAR(rms100 / expected100, 1.0, 0.15);
  EXPECT_NEAR(rms1000 / rms100, std::sqrt(10.0), 0.6);
  NoiseModel n(c, 5);
  n.advance_to(500.0);
  EXPECT_GT(n.drift_rad().norm(), 0.0);
  n.calibrate();
  EXPECT_EQ(n.drift_rad().norm(), 0.0);
  NoiseModel m(NoiseConfig::moderate(), 5);
  EXPECT_NEAR(m.config().sigma_m_rad, 2.0 * c.sigma_m_rad, 1e-15);
}

TEST(Pcg32, IsDeterministic) {
  Pcg32 a(42), b(42);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next(), b.next());
  // The same stream on every target (the leon3 run is big-endian, 32-bit): first values pinned.
  Pcg32 c(42);
  EXPECT_EQ(c.next(), 0xC2F57BD6u);
  EXPECT_EQ(c.next(), 0x6B07C4A9u);
}

}  // namespace
}  // namespace qnav::sim
