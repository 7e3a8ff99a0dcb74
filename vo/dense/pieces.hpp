// The dense VO's loops over rows and points, split into a fixed number of pieces that OpenCV's
// thread pool runs (cv::parallel_for_). The split depends on the work alone, never on the thread
// count, and each piece writes apart: reductions keep a value per piece or per block and add them
// in order afterwards, so the bytes are those of the serial loop at any thread count.
#pragma once

#include <algorithm>
#include <cstddef>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/utility.hpp>

namespace driftlab::vo::dense {

/// Calls f(k, begin, end) for the pieces k < pieces of [0, n), [n k / pieces, n (k + 1) / pieces)
/// (at most n pieces), on OpenCV's threads.
template <class F>
void for_each_piece(std::size_t n, std::size_t pieces, const F& f) {
  pieces = std::min(pieces, n);
  if (pieces <= 1) {
    if (n > 0) f(std::size_t{0}, std::size_t{0}, n);
    return;
  }
  cv::parallel_for_(
      cv::Range(0, static_cast<int>(pieces)),
      [&](const cv::Range& r) {
        for (int k = r.start; k < r.end; ++k) {
          const std::size_t kk = static_cast<std::size_t>(k);
          f(kk, n * kk / pieces, n * (kk + 1) / pieces);
        }
      },
      static_cast<double>(pieces));
}

/// The pieces of rows of an image: 16, enough for 16 cores, a few dozen rows each at the twin's
/// resolutions.
constexpr std::size_t kRowPieces = 16;

/// Calls f(v) for each row v < rows, in kRowPieces pieces.
template <class F>
void for_each_row(int rows, const F& f) {
  for_each_piece(static_cast<std::size_t>(std::max(rows, 0)), kRowPieces,
                 [&](std::size_t, std::size_t v0, std::size_t v1) {
                   for (std::size_t v = v0; v < v1; ++v) f(static_cast<int>(v));
                 });
}

/// An OpenCV filter, filter(src_rows, dst_rows), run on fixed pieces of rows of `src` into *dst
/// (made of src's size and `type`). Each piece is a region of interest, not isolated: the filter
/// reads the rows around it from the whole image, so a filter whose outputs are each computed
/// from their own window gives the bytes of one call on the whole image.
template <class Filter>
void filter_in_row_pieces(const cv::Mat& src, cv::Mat* dst, int type, const Filter& filter) {
  dst->create(src.size(), type);
  for_each_piece(static_cast<std::size_t>(src.rows), kRowPieces,
                 [&](std::size_t, std::size_t v0, std::size_t v1) {
                   const cv::Rect rows(0, static_cast<int>(v0), src.cols,
                                       static_cast<int>(v1 - v0));
                   cv::Mat out = (*dst)(rows);
                   filter(src(rows), out);
                 });
}

/// Calls f(b, begin, end) for the blocks b of n points, [b * block, min(n, (b + 1) * block)), in
/// pieces of whole blocks (about 64 pieces: enough to balance 16 cores).
template <class F>
void for_each_block(std::size_t n, std::size_t block, const F& f) {
  const std::size_t blocks = (n + block - 1) / block;
  for_each_piece(blocks, 64, [&](std::size_t, std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) f(b, b * block, std::min(n, (b + 1) * block));
  });
}

}  // namespace driftlab::vo::dense
