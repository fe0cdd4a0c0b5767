// The stereo sequence inputs of `qnav vo` / `qnav stereo` (firmware/tools/sequence_reader): byte 0
// picks the reader, the rest is the file: 0 KITTI calib.txt, 1 EuRoC sensor.yaml (both cameras: the
// extrinsics are computed from two reads), 2 EuRoC data.csv (the same text as cam0 and cam1 of a
// sequence folder). Host only.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/tools/sequence_reader.hpp"
#include "test/fuzz/fuzz_support.hpp"

int qnav_fuzz_calib(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  if (size < 1) return 0;
  const int kind = data[0] % 3;
  const std::uint8_t* body = data + 1;
  const std::size_t n = size - 1;
  if (kind == 0) {
    Result<tools::KittiCalib> c = tools::read_kitti_calib(fuzz::write_scratch("calib.txt", body, n));
    if (c && (!(c->f_px > 0.0) || !(c->baseline_m > 0.0) || c->width <= 0 || c->height <= 0)) __builtin_trap();
  } else if (kind == 1) {
    Result<tools::EurocCamera> c = tools::read_euroc_camera(fuzz::write_scratch("sensor.yaml", body, n));
    if (c) {
      if (!std::isfinite(c->model.fx) || !(c->model.fx > 0.0)) __builtin_trap();
      const Pose3 lr = tools::euroc_stereo_extrinsics(c.value(), c.value());
      if (!std::isfinite(lr.t.norm())) __builtin_trap();
    }
  } else {
    std::string dir;
    for (const char* d : {"euroc", "euroc/cam0", "euroc/cam1", "euroc/cam0/data", "euroc/cam1/data"}) dir = fuzz::scratch_subdir(d);
    dir = fuzz::scratch_dir() + "/euroc";
    fuzz::write_scratch("euroc/cam0/data.csv", body, n);
    fuzz::write_scratch("euroc/cam1/data.csv", body, n);
    std::vector<tools::StereoFrame> frames;
    (void)tools::read_euroc_sequence(dir, frames);
  }
  return 0;
}

static void seeds_calib(qnav::fuzz::Seeds& out) {
  const std::string d = qnav::fuzz::shared_dir() + "/data/stereo/";
  const std::string kitti = qnav::fuzz::read_prefix(d + "kitti_raw_2011_09_26_0013_city100/calib.txt", 4096);
  if (!kitti.empty()) out.push_back(qnav::fuzz::Seed{"kitti-calib.txt", std::string(1, '\0') + kitti});
  const std::string yaml = qnav::fuzz::read_prefix(d + "euroc_v1_01_hover40/cam0/sensor.yaml", 8192);
  if (!yaml.empty()) out.push_back(qnav::fuzz::Seed{"euroc-cam0-sensor.yaml", std::string(1, '\1') + yaml});
  std::string csv = qnav::fuzz::read_prefix(d + "euroc_v1_01_hover40/cam0/data.csv", 400);
  csv = csv.substr(0, csv.rfind('\n') + 1);  // whole lines only
  if (!csv.empty()) out.push_back(qnav::fuzz::Seed{"euroc-data.csv", std::string(1, '\2') + csv});
}
QNAV_FUZZ_TARGET(calib, 100)
