#include "firmware/tools/sequence_reader.hpp"
#include "firmware/tools/shared_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

const std::string kStereo = qnav::tools::shared_dir() + "/data/stereo/";

std::string write_tmp(const char* name, const std::string& text) {
  const std::string p = ::testing::TempDir() + "/qnav_seq_" + name;
  std::FILE* f = std::fopen(p.c_str(), "wb");
  if (f != nullptr) {
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  return p;
}

const char* kYaml = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.1,
         0.0, 1.0, 0.0, 0.2,
         0.0, 0.0, 1.0, 0.3,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  if (p != std::string::npos) s.replace(p, from.size(), to);
  return s;
}

TEST(SequenceReader, ParsesAnEurocSensorYaml) {
  Result<EurocCamera> c = read_euroc_camera(write_tmp("ok.yaml", kYaml));
  ASSERT_TRUE(c.is_ok()) << c.status().message();
  EXPECT_DOUBLE_EQ(c->model.fx, 458.654);
  EXPECT_DOUBLE_EQ(c->model.cy, 248.375);
  EXPECT_DOUBLE_EQ(c->model.k1, -0.28340811);
  EXPECT_DOUBLE_EQ(c->model.p2, 1.76187114e-05);
  EXPECT_EQ(c->model.width, 752);
  EXPECT_EQ(c->model.height, 480);
  EXPECT_DOUBLE_EQ(c->rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(c->T_BS.t.z(), 0.3);
}

TEST(SequenceReader, RejectsBadSensorYaml) {
  EXPECT_EQ(read_euroc_camera("/nonexistent/sensor.yaml").status(), StatusCode::kIoError);
  EXPECT_EQ(read_euroc_camera(write_tmp("nan.yaml", replace(kYaml, "458.654", "nan"))).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(read_euroc_camera(write_tmp("f0.yaml", replace(kYaml, "458.654", "0.0"))).status(), StatusCode::kInvalidArgument);
  EXPECT_EQ(read_euroc_camera(write_tmp("rot.yaml", replace(kYaml, "data: [1.0", "data: [2.0"))).status(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(read_euroc_camera(write_tmp("short.yaml", replace(kYaml, "367.215, ", ""))).status(), StatusCode::kCorrupt);
  EXPECT_EQ(read_euroc_camera(write_tmp("text.yaml", replace(kYaml, "367.215", "abc"))).status(), StatusCode::kCorrupt);
  EXPECT_EQ(read_euroc_camera(write_tmp("model.yaml", replace(kYaml, "radial-tangential", "equidistant"))).status(),
            StatusCode::kUnsupported);
  EXPECT_EQ(read_euroc_camera(write_tmp("notbs.yaml", replace(kYaml, "T_BS:", "T_XX:"))).status(), StatusCode::kCorrupt);
}

TEST(SequenceReader, ReadsTheRealEurocFolderAndItsStereoExtrinsics) {
  const std::string dir = kStereo + "euroc_v1_01_hover40";
  std::vector<StereoFrame> frames;
  const Status s = read_euroc_sequence(dir, frames);
  if (s == StatusCode::kIoError) GTEST_SKIP() << "sample data missing: " << dir;
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(frames.size(), 40u);
  EXPECT_EQ(frames[0].stamp_ns, 1403715273262142976LL);
  EXPECT_EQ(frames[39].stamp_ns, 1403715275212143104LL);
  for (std::size_t i = 1; i < frames.size(); ++i) EXPECT_NEAR(frames[i].stamp_ns - frames[i - 1].stamp_ns, 50000000, 1000);
  EXPECT_NE(frames[0].left_path.find("cam0/data/1403715273262142976.png"), std::string::npos);
  Result<EurocCamera> c0 = read_euroc_camera(dir + "/cam0/sensor.yaml");
  Result<EurocCamera> c1 = read_euroc_camera(dir + "/cam1/sensor.yaml");
  ASSERT_TRUE(c0.is_ok() && c1.is_ok());
  const Pose3 T = euroc_stereo_extrinsics(*c0, *c1);
  // The VI-sensor: ~11 cm baseline along +x of cam0, cameras nearly parallel.
  EXPECT_NEAR(T.t.norm(), 0.110, 0.002);
  EXPECT_GT(T.t.x(), 0.109);
  EXPECT_LT(rotation_angle_rad(T.R), deg_to_rad(1.0));
}

TEST(SequenceReader, ReadsTheRealKittiFolderAndCalib) {
  const std::string dir = kStereo + "kitti_raw_2011_09_26_0013_city100";
  std::vector<StereoFrame> frames;
  const Status s = read_kitti_sequence(dir, frames);
  if (s == StatusCode::kIoError) GTEST_SKIP() << "sample data missing: " << dir;
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(frames.size(), 100u);
  EXPECT_NE(frames[7].right_path.find("right/0000000007.png"), std::string::npos);
  Result<KittiCalib> c = read_kitti_calib(dir + "/calib.txt");
  ASSERT_TRUE(c.is_ok()) << c.status().message();
  EXPECT_DOUBLE_EQ(c->f_px, 721.5377);
  EXPECT_DOUBLE_EQ(c->baseline_m, 0.537150);
  EXPECT_EQ(c->width, 1242);
  EXPECT_EQ(read_kitti_calib(write_tmp("calib_bad.txt", "width 10\nf abc\n")).status(), StatusCode::kCorrupt);
  EXPECT_EQ(read_kitti_calib(write_tmp("calib_miss.txt", "width 10\n")).status(), StatusCode::kCorrupt);
  EXPECT_EQ(read_kitti_sequence("/nonexistent", frames), StatusCode::kIoError);
}

}  // namespace
}  // namespace qnav::tools
