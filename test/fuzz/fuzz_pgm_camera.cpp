// hal/sim's PgmSequenceCamera (the camera replay backend): a sequence of three PGM files cut from the
// input (bytes 0-1 and 2-3, little-endian: the lengths of the first two), replayed frame by frame into a view of the format the first
// file fixed, with a stamp list (byte 4 bit 0). Frames of another size must be refused (kCorrupt),
// never copied past the view; after the last frame capture() reports the end.
#include <cstddef>
#include <cstdint>
#include <string>

#include "hal/sim/pgm_sequence_camera.hpp"
#include "nav/core/image.hpp"
#include "test/fuzz/fuzz_support.hpp"

int qnav_fuzz_pgm_camera(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  fuzz::Cursor in(data, size);
  const std::size_t len1 = in.u16(), len2 = in.u16();
  const bool stamped = (in.u8() & 1) != 0;
  const std::uint8_t* p = in.here();
  const std::size_t n = in.remaining();
  const std::size_t a = len1 < n ? len1 : n, b = a + (len2 < n - a ? len2 : n - a);
  fuzz::write_scratch("cam_0.pgm", p, a);
  fuzz::write_scratch("cam_1.pgm", p + a, b - a);
  fuzz::write_scratch("cam_2.pgm", p + b, n - b);
  const std::string pattern = fuzz::scratch_dir() + "/cam_%d.pgm";
  const std::int64_t stamps[3] = {5, 3, 9};  // not increasing: the camera passes them on as given
  hal::PgmSequenceConfig c;
  c.pattern = pattern.c_str();
  c.count = 3;
  if (stamped) c.stamps = Span<const std::int64_t>(stamps, 3);
  hal::PgmSequenceCamera camera;
  if (!camera.open(c)) return 0;
  const hal::CameraFormat f = camera.format();
  if (f.width <= 0 || f.height <= 0) __builtin_trap();
  if (static_cast<long>(f.width) * f.height > (1l << 22)) return 0;
  Result<ImageU8> img = ImageU8::allocate(f.width, f.height);
  if (!img) return 0;
  int frames = 0;
  for (int k = 0; k < 4; ++k) {
    if (camera.capture(img->view(), 0)) ++frames;
  }
  if (frames > 3 || camera.remaining() != 0) __builtin_trap();
  return 0;
}

static void seeds_pgm_camera(qnav::fuzz::Seeds& out) {
  std::string frame = "P5\n# frame\n6 4\n255\n";
  for (int i = 0; i < 24; ++i) frame += static_cast<char>(i * 10);
  const std::string three = frame + frame + frame;
  const char l = static_cast<char>(frame.size());
  out.push_back(qnav::fuzz::Seed{"three-frames", std::string{l, 0, l, 0, 1} + three});
  std::string other = "P5 3 2 255\n";
  other += std::string(6, '\x40');
  out.push_back(qnav::fuzz::Seed{"size-change", std::string{l, 0, static_cast<char>(other.size()), 0, 0} + frame + other + frame});
}
QNAV_FUZZ_TARGET(pgm_camera, 200)
