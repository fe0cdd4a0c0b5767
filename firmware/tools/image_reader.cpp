#include "firmware/tools/image_reader.hpp"

#include <dirent.h>
#include <jpeglib.h>
#include <png.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace qnav::tools {
namespace {

struct File {
  std::FILE* f = nullptr;
  explicit File(const char* path, const char* mode) : f(std::fopen(path, mode)) {}
  ~File() {
    if (f != nullptr) std::fclose(f);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
};

inline std::uint8_t luma601(int r, int g, int b) noexcept {
  // 0.299 R + 0.587 G + 0.114 B in 16-bit fixed point, rounded.
  return static_cast<std::uint8_t>((19595 * r + 38470 * g + 7471 * b + 32768) >> 16);
}

Status check_size(long w, long h) noexcept {
  if (w <= 0 || h <= 0) return Status(StatusCode::kInvalidArgument, "image: zero size");
  if (w > kMaxImageSide || h > kMaxImageSide) return Status(StatusCode::kInvalidArgument, "image: side too large");
  return Status::ok();
}

// ---- PNG ----
struct PngJump {
  std::jmp_buf jump;
};
void png_fail(png_structp png, png_const_charp) { std::longjmp(static_cast<PngJump*>(png_get_error_ptr(png))->jump, 1); }
void png_warn(png_structp, png_const_charp) {}

// Decodes into `rows` (8-bit, 1 or 3 channels after transforms). Only POD state crosses setjmp.
Status decode_png(std::FILE* f, std::vector<std::uint8_t>& pixels, std::vector<png_bytep>& row_ptrs, int& width, int& height,
                  int& channels) {
  PngJump jmp;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &jmp, png_fail, png_warn);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status(StatusCode::kIoError, "png: cannot create reader");
  }
  if (setjmp(jmp.jump)) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status(StatusCode::kCorrupt, "png: decode error");
  }
  png_init_io(png, f);
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  const Status s = check_size(static_cast<long>(w), static_cast<long>(h));
  if (!s) {
    png_destroy_read_struct(&png, &info, nullptr);
    return s;
  }
  const int ct = png_get_color_type(png, info);
  if (ct == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (ct == PNG_COLOR_TYPE_GRAY && png_get_bit_depth(png, info) < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_bit_depth(png, info) == 16) png_set_strip_16(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  png_set_strip_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const int ch = png_get_channels(png, info);
  if (ch != 1 && ch != 3) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status(StatusCode::kUnsupported, "png: unexpected channel count");
  }
  const std::size_t rowbytes = png_get_rowbytes(png, info);
  pixels.resize(rowbytes * h);
  row_ptrs.resize(h);
  for (png_uint_32 y = 0; y < h; ++y) row_ptrs[y] = pixels.data() + y * rowbytes;
  png_read_image(png, row_ptrs.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  channels = ch;
  return Status::ok();
}

// ---- JPEG ----
struct JpegErr {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
};
// cinfo->err is &JpegErr::mgr, the first member of a standard-layout JpegErr, so the JpegErr is at the
// same address and aligned for it; through void* because a direct cast warns on armhf (-Wcast-align).
void jpeg_fail(j_common_ptr cinfo) { std::longjmp(static_cast<JpegErr*>(static_cast<void*>(cinfo->err))->jump, 1); }
// Silent, but counted: a warning (msg_level -1) is damaged data; trace messages (>= 0) are not.
void jpeg_silent(j_common_ptr cinfo, int msg_level) {
  if (msg_level < 0) ++cinfo->err->num_warnings;
}

// libjpeg's own words for what went wrong (a truncated file is only a warning to libjpeg, which then
// fills the rest of the image with grey: here any warning makes the image corrupt).
Status jpeg_status(j_decompress_ptr cinfo, const char* what) {
  static char msg[JMSG_LENGTH_MAX + 64];
  char text[JMSG_LENGTH_MAX];
  cinfo->err->format_message(reinterpret_cast<j_common_ptr>(cinfo), text);
  std::snprintf(msg, sizeof msg, "jpeg: %s: %s", what, text);
  return Status(StatusCode::kCorrupt, msg);
}

Status decode_jpeg(std::FILE* f, std::vector<std::uint8_t>& pixels, int& width, int& height) {
  jpeg_decompress_struct cinfo;
  JpegErr err;
  cinfo.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = jpeg_fail;
  err.mgr.emit_message = jpeg_silent;
  if (setjmp(err.jump)) {
    const Status e = jpeg_status(&cinfo, "decode error");
    jpeg_destroy_decompress(&cinfo);
    return e;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_stdio_src(&cinfo, f);
  jpeg_read_header(&cinfo, TRUE);
  // libjpeg's YCbCr -> grey keeps Y (BT.601 luma); RGB JPEGs use the same weights.
  cinfo.out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(&cinfo);
  const Status s = check_size(static_cast<long>(cinfo.output_width), static_cast<long>(cinfo.output_height));
  if (!s || cinfo.output_components != 1) {
    jpeg_destroy_decompress(&cinfo);
    return s ? Status(StatusCode::kUnsupported, "jpeg: not convertible to grey") : s;
  }
  const std::size_t w = cinfo.output_width, h = cinfo.output_height;
  pixels.resize(w * h);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = pixels.data() + static_cast<std::size_t>(cinfo.output_scanline) * w;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  if (cinfo.err->num_warnings > 0) {  // e.g. "Premature end of JPEG file": the rest would be grey
    const Status e = jpeg_status(&cinfo, "damaged or truncated data");
    jpeg_destroy_decompress(&cinfo);
    pixels.clear();
    return e;
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  return Status::ok();
}

Result<ImageU8> to_image(const std::vector<std::uint8_t>& px, int w, int h, int channels) noexcept {
  Result<ImageU8> r = ImageU8::allocate(w, h);
  if (!r) return r.status();
  ImageU8& img = r.value();
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* s = px.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w) * static_cast<std::size_t>(channels);
    std::uint8_t* d = img.view().row(y);
    if (channels == 1) {
      std::memcpy(d, s, static_cast<std::size_t>(w));
    } else {
      for (int x = 0; x < w; ++x) d[x] = luma601(s[3 * x], s[3 * x + 1], s[3 * x + 2]);
    }
  }
  return r;
}

// ---- PGM ----
// Reads one header token (skipping whitespace and # comments). Returns false at EOF / overlong token.
bool pgm_token(std::FILE* f, char* buf, std::size_t cap) noexcept {
  int c = std::fgetc(f);
  for (;;) {
    while (c == ' ' || c == '\t' || c == '\r' || c == '\n') c = std::fgetc(f);
    if (c != '#') break;
    while (c != '\n' && c != EOF) c = std::fgetc(f);
  }
  std::size_t n = 0;
  while (c != EOF && c != ' ' && c != '\t' && c != '\r' && c != '\n' && c != '#') {
    if (n + 1 >= cap) return false;
    buf[n++] = static_cast<char>(c);
    c = std::fgetc(f);
  }
  buf[n] = '\0';
  return n > 0;  // the single whitespace after the last token (maxval) is consumed here
}

bool parse_long(const char* s, long& v) noexcept {
  char* end = nullptr;
  v = std::strtol(s, &end, 10);
  return end != s && *end == '\0';
}

}  // namespace

Result<ImageU8> read_png_gray8(const char* path) noexcept {
  if (path == nullptr) return Status(StatusCode::kInvalidArgument, "image: null path");
  File f(path, "rb");
  if (f.f == nullptr) return Status(StatusCode::kIoError, "image: cannot open file");
  try {
    std::vector<std::uint8_t> px;
    std::vector<png_bytep> rows;
    int w = 0, h = 0, ch = 0;
    const Status s = decode_png(f.f, px, rows, w, h, ch);
    if (!s) return s;
    return to_image(px, w, h, ch);
  } catch (...) {
    return Status(StatusCode::kCapacityExceeded, "image: out of memory");
  }
}

Result<ImageU8> read_jpeg_gray8(const char* path) noexcept {
  if (path == nullptr) return Status(StatusCode::kInvalidArgument, "image: null path");
  File f(path, "rb");
  if (f.f == nullptr) return Status(StatusCode::kIoError, "image: cannot open file");
  try {
    std::vector<std::uint8_t> px;
    int w = 0, h = 0;
    const Status s = decode_jpeg(f.f, px, w, h);
    if (!s) return s;
    return to_image(px, w, h, 1);
  } catch (...) {
    return Status(StatusCode::kCapacityExceeded, "image: out of memory");
  }
}

Result<ImageU8> read_pgm_gray8(const char* path) noexcept {
  if (path == nullptr) return Status(StatusCode::kInvalidArgument, "image: null path");
  File f(path, "rb");
  if (f.f == nullptr) return Status(StatusCode::kIoError, "image: cannot open file");
  char tok[32];
  long w = 0, h = 0, maxval = 0;
  if (!pgm_token(f.f, tok, sizeof tok)) return Status(StatusCode::kCorrupt, "pgm: missing magic");
  if (std::strcmp(tok, "P5") != 0) return Status(StatusCode::kUnsupported, "pgm: only binary P5 is supported");
  if (!pgm_token(f.f, tok, sizeof tok) || !parse_long(tok, w) || !pgm_token(f.f, tok, sizeof tok) || !parse_long(tok, h) ||
      !pgm_token(f.f, tok, sizeof tok) || !parse_long(tok, maxval))
    return Status(StatusCode::kCorrupt, "pgm: bad header");
  const Status s = check_size(w, h);
  if (!s) return s;
  if (maxval <= 0 || maxval > 65535) return Status(StatusCode::kCorrupt, "pgm: bad maxval");
  if (maxval > 255) return Status(StatusCode::kUnsupported, "pgm: 16-bit PGM is not supported");
  Result<ImageU8> r = ImageU8::allocate(static_cast<int>(w), static_cast<int>(h));
  if (!r) return r.status();
  for (long y = 0; y < h; ++y) {
    std::uint8_t* row = r.value().view().row(static_cast<int>(y));
    if (std::fread(row, 1, static_cast<std::size_t>(w), f.f) != static_cast<std::size_t>(w))
      return Status(StatusCode::kTruncated, "pgm: file ends inside the pixel data");
    if (maxval != 255)
      for (long x = 0; x < w; ++x) row[x] = static_cast<std::uint8_t>((row[x] > maxval ? maxval : row[x]) * 255 / maxval);
  }
  return r;
}

Result<ImageU8> read_image_gray8(const char* path) noexcept {
  if (path == nullptr) return Status(StatusCode::kInvalidArgument, "image: null path");
  unsigned char magic[8] = {};
  std::size_t n = 0;
  {
    File f(path, "rb");
    if (f.f == nullptr) return Status(StatusCode::kIoError, "image: cannot open file");
    n = std::fread(magic, 1, sizeof magic, f.f);
  }
  if (n >= 8 && png_sig_cmp(magic, 0, 8) == 0) return read_png_gray8(path);
  if (n >= 3 && magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF) return read_jpeg_gray8(path);
  if (n >= 2 && magic[0] == 'P' && magic[1] == '5') return read_pgm_gray8(path);
  if (n == 0) return Status(StatusCode::kTruncated, "image: empty file");
  return Status(StatusCode::kUnsupported, "image: unknown format (PNG, JPEG and binary PGM are read)");
}

Status write_pgm_gray8(const char* path, ConstImageViewU8 image) noexcept {
  if (path == nullptr || image.empty()) return Status(StatusCode::kInvalidArgument, "pgm: bad arguments");
  std::string tmp;
  try {
    tmp = std::string(path) + ".tmp";
  } catch (...) {
    return Status(StatusCode::kCapacityExceeded, "pgm: out of memory");
  }
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) return Status(StatusCode::kIoError, "pgm: cannot open output file");
  bool ok = std::fprintf(f, "P5\n%d %d\n255\n", image.width(), image.height()) > 0;
  for (int y = 0; ok && y < image.height(); ++y)
    ok = std::fwrite(image.row(y), 1, static_cast<std::size_t>(image.width()), f) == static_cast<std::size_t>(image.width());
  ok = (std::fclose(f) == 0) && ok;
  if (!ok || std::rename(tmp.c_str(), path) != 0) {
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "pgm: write failed");
  }
  return Status::ok();
}

namespace {
bool has_image_ext(const std::string& n) {
  const std::size_t d = n.find_last_of('.');
  if (d == std::string::npos) return false;
  std::string e = n.substr(d + 1);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e == "png" || e == "jpg" || e == "jpeg" || e == "pgm";
}
}  // namespace

bool list_image_files(const char* dir, std::vector<std::string>& out, std::string& err) {
  DIR* d = opendir(dir);
  if (d == nullptr) {
    err = std::string("cannot open directory ") + dir + ": " + std::strerror(errno);
    return false;
  }
  while (dirent* e = readdir(d)) {
    const std::string n = e->d_name;
    if (n.empty() || n[0] == '.' || !has_image_ext(n)) continue;
    const std::string p = std::string(dir) + "/" + n;
    struct stat st {};
    if (stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode)) out.push_back(p);
  }
  closedir(d);
  std::sort(out.begin(), out.end());
  if (out.empty()) err = std::string("no .png/.jpg/.pgm frames in ") + dir;
  return !out.empty();
}

}  // namespace qnav::tools
