// Window sums over a float image for the disparity refinement: cv::boxFilter's (zeros beyond
// the image), computed in its order of operations but faster.
#pragma once

#include <opencv2/core/mat.hpp>

namespace driftlab::vo::dense {

/// Rows [v0, v1) of the sums (normalize: means) of `src` (CV_32FC1) over window x window pixels
/// centred on each pixel, zeros beyond the image, into the same rows of *dst (CV_32FC1, src's
/// size, allocated by the caller); rows outside [v0, v1) are read, not written. The arithmetic is
/// OpenCV 4.6's for cv::boxFilter(src(rows), ..., BORDER_CONSTANT) on those rows of a larger
/// image: in double, a running sum along each padded row (a plain sum of the 3 or 5 values for
/// those windows), then a running sum down each column starting at row v0 - window / 2, each
/// output rounded to float. OpenCV runs each row's sum as one serial chain of additions; here
/// four rows run side by side, so the same bytes in about a third of the time.
void box_filter_rows(const cv::Mat& src, int v0, int v1, int window, bool normalize, cv::Mat* dst);

}  // namespace driftlab::vo::dense
