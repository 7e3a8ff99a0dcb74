#include "vo/dense/box_filter.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include "core/error.hpp"

namespace driftlab::vo::dense {

namespace {

// Sums of `k` consecutive values of N padded rows p[n] (W + k - 1 values each) into d[n][0..W):
// for k = 3 and 5 plain sums, left to right; otherwise a running sum, s += p[i + k] - p[i]. The N
// running sums are independent chains, interleaved.
template <int N>
void row_sums(const float* const* p, int W, int k, double* const* d) {
  if (k == 3 || k == 5) {
    for (int n = 0; n < N; ++n)
      for (int i = 0; i < W; ++i) {
        const float* s = p[n] + i;
        double sum =
            static_cast<double>(s[0]) + static_cast<double>(s[1]) + static_cast<double>(s[2]);
        if (k == 5) sum = sum + static_cast<double>(s[3]) + static_cast<double>(s[4]);
        d[n][i] = sum;
      }
    return;
  }
  double s[N] = {};
  for (int i = 0; i < k; ++i)
    for (int n = 0; n < N; ++n) s[n] += static_cast<double>(p[n][i]);
  for (int n = 0; n < N; ++n) d[n][0] = s[n];
  for (int i = 0; i + 1 < W; ++i)
    for (int n = 0; n < N; ++n) {
      s[n] += static_cast<double>(p[n][i + k]) - static_cast<double>(p[n][i]);
      d[n][i + 1] = s[n];
    }
}

// The row sums of image rows [y0, y1) (zeros outside [0, rows)) into sums (one row of W doubles
// per image row, from y0), four rows at a time.
void sum_rows(const cv::Mat& src, int y0, int y1, int k, std::vector<float>* padded,
              std::vector<double>* sums) {
  const int W = src.cols, r = k / 2, P = W + k - 1;
  padded->assign(static_cast<std::size_t>(4 * P), 0.0f);
  sums->resize(static_cast<std::size_t>(y1 - y0) * static_cast<std::size_t>(W));
  for (int y = y0; y < y1; y += 4) {
    const int n = std::min(4, y1 - y);
    const float* p[4];
    double* d[4];
    for (int j = 0; j < n; ++j) {
      float* row = padded->data() + static_cast<std::size_t>(j * P);
      const int yy = y + j;
      if (yy >= 0 && yy < src.rows)
        std::memcpy(row + r, src.ptr<float>(yy), sizeof(float) * static_cast<std::size_t>(W));
      else
        std::fill(row + r, row + r + W, 0.0f);
      p[j] = row;
      d[j] = sums->data() + static_cast<std::size_t>(yy - y0) * static_cast<std::size_t>(W);
    }
    if (n == 4)
      row_sums<4>(p, W, k, d);
    else
      for (int j = 0; j < n; ++j) row_sums<1>(p + j, W, k, d + j);
  }
}

}  // namespace

void box_filter_rows(const cv::Mat& src, int v0, int v1, int window, bool normalize, cv::Mat* dst) {
  DRIFTLAB_DEMAND(src.type() == CV_32FC1 && dst->type() == CV_32FC1 && dst->size() == src.size());
  DRIFTLAB_DEMAND(window >= 1 && window % 2 == 1 && 0 <= v0 && v0 <= v1 && v1 <= src.rows);
  if (v0 == v1) return;
  const int W = src.cols, r = window / 2;
  thread_local std::vector<float> padded;
  thread_local std::vector<double> sums, column;
  sum_rows(src, v0 - r, v1 + r, window, &padded, &sums);
  const auto row = [&](int y) {  // the row sums of image row y
    return sums.data() + static_cast<std::size_t>(y - (v0 - r)) * static_cast<std::size_t>(W);
  };
  // The running column sums: the first window - 1 rows, then per output row add the row below
  // the window's bottom, write, and take off the window's top row.
  column.assign(static_cast<std::size_t>(W), 0.0);
  double* S = column.data();
  for (int y = v0 - r; y < v0 + r; ++y) {
    const double* add = row(y);
    for (int u = 0; u < W; ++u) S[u] += add[u];
  }
  const double scale = normalize ? 1.0 / (static_cast<double>(window) * window) : 1.0;
  for (int v = v0; v < v1; ++v) {
    const double* add = row(v + r);
    const double* take = row(v - r);
    float* out = dst->ptr<float>(v);
    for (int u = 0; u < W; ++u) {
      const double s = S[u] + add[u];
      out[u] = static_cast<float>(normalize ? s * scale : s);
      S[u] = s - take[u];
    }
  }
}

}  // namespace driftlab::vo::dense
