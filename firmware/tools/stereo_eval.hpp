// Host-side stereo evaluation helpers shared by `qnav stereo` and the real-data tests.
#pragma once

#include <cstddef>
#include <vector>

#include "nav/core/image.hpp"
#include "nav/core/span.hpp"
#include "nav/vision/corner.hpp"

namespace qnav::tools {

// Epipolar row agreement of a stereo pair: for each left corner, a 2D ZNCC search (11x11 patch) in the
// right image over disparity 1..80 px and rows -4..+4; strong (ZNCC >= 0.9) unique matches get a
// sub-pixel row by a parabola. Returns |row offset| in pixels per accepted corner. For a well rectified
// pair the offsets are well below a pixel. An independent reference measurement (not nav/vision's
// matcher, which searches along the row only): O(corners * 9 * 80 * 121).
std::vector<double> epipolar_row_offsets(ConstImageViewU8 left, ConstImageViewU8 right,
                                         Span<const vision::Corner> corners);

}  // namespace qnav::tools
