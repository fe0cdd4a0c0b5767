#include "firmware/tools/sequence_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "firmware/tools/text_file.hpp"

namespace qnav::tools {
namespace {

namespace fs = std::filesystem;

bool read_text(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return static_cast<bool>(in) || in.eof();
}

bool parse_double(const std::string& s, double& v) {
  const char* b = s.c_str();
  char* end = nullptr;
  v = std::strtod(b, &end);
  if (end == b) return false;
  while (*end == ' ' || *end == '\t' || *end == '\r') ++end;
  return *end == '\0';
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return std::string();
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string strip_comment(const std::string& line) {
  const auto h = line.find('#');
  return h == std::string::npos ? line : line.substr(0, h);
}

// Numbers of the first "[ ... ]" list after `pos` in text (may span lines; # comments removed).
bool parse_list(const std::string& text, std::size_t pos, std::vector<double>& out) {
  const auto b = text.find('[', pos);
  if (b == std::string::npos) return false;
  const auto e = text.find(']', b);
  if (e == std::string::npos) return false;
  std::string body = text.substr(b + 1, e - b - 1);
  std::string clean;
  std::istringstream lines(body);
  for (std::string l; std::getline(lines, l);) clean += strip_comment(l) + " ";
  out.clear();
  std::istringstream items(clean);
  for (std::string it; std::getline(items, it, ',');) {
    const std::string t = trim(it);
    if (t.empty()) return false;
    double v = 0.0;
    if (!parse_double(t, v)) return false;
    out.push_back(v);
  }
  return true;
}

// Position just after "key:" at the start of a line (top level); npos when missing.
std::size_t find_key(const std::string& text, const std::string& key, std::size_t from = 0) {
  std::size_t p = from;
  while ((p = text.find(key + ":", p)) != std::string::npos) {
    if (p == 0 || text[p - 1] == '\n' || text[p - 1] == ' ') return p + key.size() + 1;
    p += key.size();
  }
  return std::string::npos;
}

std::string scalar_after(const std::string& text, std::size_t pos) {
  const auto e = text.find('\n', pos);
  return trim(strip_comment(text.substr(pos, e == std::string::npos ? std::string::npos : e - pos)));
}

Status read_data_csv(const std::string& cam_dir, std::map<std::int64_t, std::string>& rows) {
  std::ifstream in(cam_dir + "/data.csv");
  if (!in) return Status(StatusCode::kIoError, "euroc: cannot open data.csv");
  for (std::string line; std::getline(in, line);) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    const auto c = line.find(',');
    if (c == std::string::npos) return Status(StatusCode::kCorrupt, "euroc: data.csv line without a comma");
    const std::string ts = trim(line.substr(0, c)), name = trim(line.substr(c + 1));
    char* end = nullptr;
    const long long t = std::strtoll(ts.c_str(), &end, 10);
    if (end == ts.c_str() || *end != '\0' || name.empty() || t < 0)
      return Status(StatusCode::kCorrupt, "euroc: bad data.csv line");
    rows[static_cast<std::int64_t>(t)] = cam_dir + "/data/" + name;
  }
  return Status::ok();
}

}  // namespace

Status read_kitti_sequence(const std::string& dir, std::vector<StereoFrame>& frames) noexcept {
  try {
    frames.clear();
    std::error_code ec;
    std::set<std::string> left, right;
    for (const auto& e : fs::directory_iterator(dir + "/left", ec))
      if (e.is_regular_file()) left.insert(e.path().filename().string());
    if (ec) return Status(StatusCode::kIoError, "kitti: cannot list left/");
    for (const auto& e : fs::directory_iterator(dir + "/right", ec))
      if (e.is_regular_file()) right.insert(e.path().filename().string());
    if (ec) return Status(StatusCode::kIoError, "kitti: cannot list right/");
    std::int64_t i = 0;
    for (const std::string& n : left) {
      if (right.count(n) == 0) continue;
      frames.push_back(StereoFrame{i++ * 100000000LL, dir + "/left/" + n, dir + "/right/" + n});
    }
    if (frames.empty()) return Status(StatusCode::kNotFound, "kitti: no frame present in both left/ and right/");
    return Status::ok();
  } catch (...) {
    return Status(StatusCode::kIoError, "kitti: filesystem error");
  }
}

Result<KittiCalib> read_kitti_calib(const std::string& path) noexcept {
  try {
    std::ifstream in(path);
    if (!in) return Status(StatusCode::kIoError, "kitti: cannot open calib.txt");
    std::map<std::string, double> kv;
    for (std::string line; std::getline(in, line);) {
      line = trim(strip_comment(line));
      if (line.empty()) continue;
      std::istringstream ss(line);
      std::string k, v;
      ss >> k >> v;
      double d = 0.0;
      if (v.empty() || !parse_double(v, d)) return Status(StatusCode::kCorrupt, "kitti: calib line is not 'key number'");
      kv[k] = d;
    }
    for (const char* k : {"width", "height", "f", "cu", "cv", "baseline_m"})
      if (kv.count(k) == 0) return Status(StatusCode::kCorrupt, "kitti: calib.txt misses a key");
    // The size is range-checked as a double before the conversion (3.3e55 cast to int is undefined
    // behaviour; found by test/fuzz fuzz_calib, input in test/fuzz/regressions/calib/).
    const double w = kv["width"], h = kv["height"];
    if (!(w >= 1 && w <= kMaxImageSide && h >= 1 && h <= kMaxImageSide))
      return Status(StatusCode::kInvalidArgument, "kitti: calib width/height out of range");
    KittiCalib c;
    c.width = static_cast<int>(w);
    c.height = static_cast<int>(h);
    c.f_px = kv["f"];
    c.cu_px = kv["cu"];
    c.cv_px = kv["cv"];
    c.baseline_m = kv["baseline_m"];
    if (!(c.f_px > 0.0) || !(c.baseline_m > 0.0) || !std::isfinite(c.f_px) || !std::isfinite(c.baseline_m) ||
        !std::isfinite(c.cu_px) || !std::isfinite(c.cv_px) || c.width <= 0 || c.height <= 0 || c.width > kMaxImageSide ||
        c.height > kMaxImageSide)
      return Status(StatusCode::kInvalidArgument, "kitti: calib values out of range");
    return c;
  } catch (...) {
    return Status(StatusCode::kIoError, "kitti: error reading calib.txt");
  }
}

Status read_euroc_sequence(const std::string& dir, std::vector<StereoFrame>& frames) noexcept {
  try {
    frames.clear();
    std::map<std::int64_t, std::string> c0, c1;
    QNAV_RETURN_IF_ERROR(read_data_csv(dir + "/cam0", c0));
    QNAV_RETURN_IF_ERROR(read_data_csv(dir + "/cam1", c1));
    for (const auto& kv : c0) {
      const auto it = c1.find(kv.first);
      if (it != c1.end()) frames.push_back(StereoFrame{kv.first, kv.second, it->second});
    }
    if (frames.empty()) return Status(StatusCode::kNotFound, "euroc: no timestamp present in both cameras");
    return Status::ok();
  } catch (...) {
    return Status(StatusCode::kIoError, "euroc: error reading the sequence");
  }
}

Result<EurocCamera> read_euroc_camera(const std::string& path) noexcept {
  try {
    std::string text;
    if (!read_text(path, text)) return Status(StatusCode::kIoError, "euroc: cannot read sensor.yaml");
    EurocCamera cam;
    std::vector<double> v;
    const std::size_t pm = find_key(text, "camera_model");
    if (pm != std::string::npos && scalar_after(text, pm) != "pinhole")
      return Status(StatusCode::kUnsupported, "euroc: camera_model is not pinhole");
    const std::size_t pd = find_key(text, "distortion_model");
    if (pd != std::string::npos && scalar_after(text, pd) != "radial-tangential")
      return Status(StatusCode::kUnsupported, "euroc: distortion_model is not radial-tangential");
    const std::size_t pi = find_key(text, "intrinsics");
    if (pi == std::string::npos || !parse_list(text, pi, v) || v.size() != 4)
      return Status(StatusCode::kCorrupt, "euroc: intrinsics must be [fu, fv, cu, cv]");
    cam.model.fx = v[0];
    cam.model.fy = v[1];
    cam.model.cx = v[2];
    cam.model.cy = v[3];
    const std::size_t pk = find_key(text, "distortion_coefficients");
    if (pk == std::string::npos || !parse_list(text, pk, v) || v.size() != 4)
      return Status(StatusCode::kCorrupt, "euroc: distortion_coefficients must be [k1, k2, p1, p2]");
    cam.model.k1 = v[0];
    cam.model.k2 = v[1];
    cam.model.p1 = v[2];
    cam.model.p2 = v[3];
    const std::size_t pr = find_key(text, "resolution");
    if (pr == std::string::npos || !parse_list(text, pr, v) || v.size() != 2)
      return Status(StatusCode::kCorrupt, "euroc: resolution must be [w, h]");
    if (!(v[0] >= 1 && v[0] <= kMaxImageSide && v[1] >= 1 && v[1] <= kMaxImageSide))
      return Status(StatusCode::kInvalidArgument, "euroc: resolution out of range");
    cam.model.width = static_cast<int>(v[0]);
    cam.model.height = static_cast<int>(v[1]);
    const std::size_t prate = find_key(text, "rate_hz");
    if (prate != std::string::npos) {
      double r = 0.0;
      if (!parse_double(scalar_after(text, prate), r)) return Status(StatusCode::kCorrupt, "euroc: bad rate_hz");
      cam.rate_hz = r;
    }
    const std::size_t pt = find_key(text, "T_BS");
    if (pt == std::string::npos) return Status(StatusCode::kCorrupt, "euroc: missing T_BS");
    const std::size_t pdata = find_key(text, "data", pt);
    if (pdata == std::string::npos || !parse_list(text, pdata, v) || v.size() != 16)
      return Status(StatusCode::kCorrupt, "euroc: T_BS data must have 16 numbers");
    for (double d : v)
      if (!std::isfinite(d)) return Status(StatusCode::kInvalidArgument, "euroc: T_BS has a non-finite value");
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) cam.T_BS.R(r, c) = v[static_cast<std::size_t>(4 * r + c)];
      cam.T_BS.t(r) = v[static_cast<std::size_t>(4 * r + 3)];
    }
    if ((cam.T_BS.R * cam.T_BS.R.transpose() - Mat3d::Identity()).cwiseAbs().maxCoeff() > 1e-4 ||
        std::fabs(cam.T_BS.R.determinant() - 1.0) > 1e-4)
      return Status(StatusCode::kInvalidArgument, "euroc: T_BS rotation is not orthonormal");
    const vision::PinholeRadTan& m = cam.model;
    for (double d : {m.fx, m.fy, m.cx, m.cy, m.k1, m.k2, m.p1, m.p2})
      if (!std::isfinite(d)) return Status(StatusCode::kInvalidArgument, "euroc: non-finite intrinsics or distortion");
    if (!(m.fx > 0.0) || !(m.fy > 0.0)) return Status(StatusCode::kInvalidArgument, "euroc: focal length must be > 0");
    return cam;
  } catch (...) {
    return Status(StatusCode::kIoError, "euroc: error reading sensor.yaml");
  }
}

Result<vision::PinholeRadTan> read_opencv_camera(const std::string& path) noexcept {
  try {
    std::string text;
    QNAV_RETURN_IF_ERROR(read_text_file(path.c_str(), 1 << 20, text));
    vision::PinholeRadTan cam;
    std::vector<double> K, D;
    const std::size_t pw = find_key(text, "image_width"), ph = find_key(text, "image_height");
    double w = 0.0, h = 0.0;
    const std::size_t pk = find_key(text, "camera_matrix"), pd = find_key(text, "distortion_coefficients");
    if (pw == std::string::npos || ph == std::string::npos || !parse_double(scalar_after(text, pw), w) ||
        !parse_double(scalar_after(text, ph), h) || !(w >= 1.0 && w <= kMaxImageSide) || !(h >= 1.0 && h <= kMaxImageSide) ||
        pk == std::string::npos || !parse_list(text, pk, K) || K.size() != 9 || pd == std::string::npos || !parse_list(text, pd, D) ||
        D.size() < 4 || D.size() > 5)
      return Status(StatusCode::kCorrupt,
                    "camera YAML needs image_width, image_height, camera_matrix data (9) and distortion_coefficients (4-5)");
    const std::size_t pm = find_key(text, "distortion_model");
    if (pm != std::string::npos && scalar_after(text, pm) != "plumb_bob")
      return Status(StatusCode::kUnsupported, "camera YAML: distortion_model is not plumb_bob");
    if (D.size() == 5 && D[4] != 0.0) return Status(StatusCode::kUnsupported, "camera YAML: k3 != 0 is not supported by nav/vision's PinholeRadTan");
    cam.width = static_cast<int>(w);
    cam.height = static_cast<int>(h);
    cam.fx = K[0];
    cam.cx = K[2];
    cam.fy = K[4];
    cam.cy = K[5];
    cam.k1 = D[0];
    cam.k2 = D[1];
    cam.p1 = D[2];
    cam.p2 = D[3];
    QNAV_RETURN_IF_ERROR(vision::validate(cam));
    return cam;
  } catch (...) {
    return Status(StatusCode::kIoError, "camera YAML: cannot read");
  }
}

Pose3 euroc_stereo_extrinsics(const EurocCamera& left, const EurocCamera& right) noexcept {
  return left.T_BS.inverse().compose(right.T_BS);
}

}  // namespace qnav::tools
