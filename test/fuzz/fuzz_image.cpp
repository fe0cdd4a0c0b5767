// The tools' image reader (firmware/tools/image_reader: PGM, PNG via libpng, JPEG via libjpeg, told
// apart by magic bytes): any bytes as an image file. A decoded image has a valid size and every pixel
// row readable; anything else is a clear error. Host only (libpng/libjpeg).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "firmware/tools/image_reader.hpp"
#include "firmware/tools/png_writer.hpp"
#include "test/fuzz/fuzz_support.hpp"

int qnav_fuzz_image(const std::uint8_t* data, std::size_t size) {
  using namespace qnav;
  const std::string path = fuzz::write_scratch("image", data, size);
  Result<ImageU8> img = tools::read_image_gray8(path.c_str());
  if (!img) return 0;
  const ImageU8& im = img.value();
  if (im.width() <= 0 || im.height() <= 0 || im.width() > kMaxImageSide || im.height() > kMaxImageSide) __builtin_trap();
  unsigned sum = 0;
  for (int y = 0; y < im.height(); y += 1 + im.height() / 16) sum += im.view().row(y)[im.width() - 1];
  return static_cast<int>(sum & 0);
}

static void seeds_image(qnav::fuzz::Seeds& out) {
  using namespace qnav;
  const std::string d = fuzz::shared_dir() + "/data/stereo/";
  fuzz::add_file_seed(out, "chessboard-right04.jpg", d + "opencv_chessboard_stereo/right04.jpg");
  out.push_back(fuzz::Seed{"tiny.pgm", std::string("P5\n# c\n4 3\n255\n", 15) + std::string("\x00\x10\x20\x30\x40\x50\x60\x70\x80\x90\xa0\xb0", 12)});
  // A small PNG written by the tools' own writer.
  Result<ImageU8> im = ImageU8::allocate(8, 6);
  if (im) {
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 8; ++x) im->view().row(y)[x] = static_cast<std::uint8_t>(30 * x + 7 * y);
    const std::string p = fuzz::scratch_dir() + "/seed.png";
    if (tools::write_png_gray8(p.c_str(), im->view())) fuzz::add_file_seed(out, "tiny.png", p);
    std::remove(p.c_str());
  }
}
QNAV_FUZZ_TARGET(image, 100)
