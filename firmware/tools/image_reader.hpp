// Image file readers for the tool and the tests (host-side only; libpng, libjpeg). Reads 8-bit PNG,
// baseline/progressive JPEG and binary PGM (P5, maxval <= 255) as 8-bit grey: colour images are
// converted with the ITU-R BT.601 luma weights (0.299 R + 0.587 G + 0.114 B, rounded); grey+alpha
// drops alpha; 16-bit PNG is reduced to its high byte; palette PNG is expanded. The format is chosen
// by the file's magic bytes, not its name. One heap allocation per image (the returned ImageU8):
// never used in nav/ or the daemon's hot path.
// Errors: kIoError (cannot open/read), kCorrupt (decoder error, bad header), kUnsupported (format
// not handled: e.g. PGM maxval > 255, unknown magic), kInvalidArgument (null path, zero size, side >
// kMaxImageSide).
#pragma once

#include <string>
#include <vector>

#include "nav/core/image.hpp"
#include "nav/core/status.hpp"

namespace qnav::tools {

Result<ImageU8> read_image_gray8(const char* path) noexcept;
Result<ImageU8> read_png_gray8(const char* path) noexcept;
Result<ImageU8> read_jpeg_gray8(const char* path) noexcept;
Result<ImageU8> read_pgm_gray8(const char* path) noexcept;

// The frames of a directory: every regular .png/.jpg/.jpeg/.pgm file (extension case-insensitive, no
// dot files), full paths in name order. False with a message (the directory, and why) when it
// cannot be read or holds none. `qnav map --images` and qnavd's map passes (sim.pass.images).
bool list_image_files(const char* dir, std::vector<std::string>& out, std::string& err);

// Writes binary PGM (P5) atomically (temporary file + rename). For tests and debug output.
Status write_pgm_gray8(const char* path, ConstImageViewU8 image) noexcept;

}  // namespace qnav::tools
