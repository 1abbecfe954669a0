// Printing of LED calibration scores, shared by `train-led` and `calibrate-led`.
#pragma once

#include <cstdio>
#include <vector>

#include "restoration/led/detect_dataset.h"

namespace weathergs::cli {

inline void print_led_scores(const std::vector<restoration::led::LedScore>& scores) {
  for (const auto& s : scores)
    std::printf("  %-32s IoU %.3f  precision %.3f  recall %.3f  (drops on %.2f%% of pixels, masked %.2f%%)\n", s.dataset.c_str(),
                s.iou, s.precision, s.recall, 100 * s.gt_fraction, 100 * s.mask_fraction);
}

}  // namespace weathergs::cli
