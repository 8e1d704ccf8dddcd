#pragma once
// Pyramidal Lucas-Kanade, the algorithm of OpenCV's cv::calcOpticalFlowPyrLK (window, Scharr gradients, the minimum
// eigenvalue test, the stopping rules, the half step back when an iteration oscillates) in floating point on float
// copies of the pyramid. OpenCV walks a window row 8 pixels at a time in 16-bit fixed point and leaves the rest of
// the row to scalar code: with the 21 px window 5 of every 21 columns, which made its LK 28-41 % of a run
// (docs/benchmarks.md). Here each row is whole vectors of 8 floats (24 lanes for 21 px, the last three weighted 0),
// and the gradients are computed only where a window needs them. It agrees with OpenCV to 1e-4 px on real images
// (test LkFlow.AgreesWithOpenCvOnRealFlightImages): OpenCV rounds the window to 1/32 grey level and the bilinear
// weights to 1/16384.
#include <opencv2/core.hpp>

#include <vector>

namespace ovton::core {

/// One image's pyramid as lk_flow reads it: per level the grey values as a float plane with a border wide enough for
/// any window that starts inside the level. (The Scharr derivatives of a window, OpenCV's calcSharrDeriv: [3 10 3]
/// smoothing, central difference, reflected at the image border, 0 outside it, are computed per window.)
class LkPyramid {
public:
  /// From the levels of cv::buildOpticalFlowPyramid(img, levels, Size(win, win), max_level) built without
  /// derivatives (views into buffers padded by `win` with BORDER_REFLECT_101, which the planes keep).
  void build(const std::vector<cv::Mat> &levels, int win);
  int num_levels() const { return static_cast<int>(levels_.size()); }
  /// The window the planes' border was made for: lk_flow refuses a larger one (it would read past the border).
  int window() const { return win_; }
  bool empty() const { return levels_.empty(); }

  struct Level {
    int cols = 0, rows = 0;
    int stride = 0; ///< floats from one row to the next
    int origin = 0; ///< index of pixel (0, 0) in img
    std::vector<float> img;
    const float *at(int x, int y) const { return img.data() + origin + static_cast<ptrdiff_t>(y) * stride + x; }
    float *at(int x, int y) { return img.data() + origin + static_cast<ptrdiff_t>(y) * stride + x; }
  };
  const Level &level(int i) const { return levels_[static_cast<size_t>(i)]; }

private:
  std::vector<Level> levels_;
  int win_ = 0;
};

struct LkParams {
  int win = 21;             ///< window side [px]
  int max_level = 3;        ///< coarsest level used (capped by the pyramids)
  int max_iter = 30;        ///< iterations per level
  double eps = 0.01;        ///< an update shorter than this ends the level [px]
  float min_eig = 1e-4f;    ///< OpenCV's minEigThreshold, in its units
  bool use_initial = false; ///< next_pts holds a starting guess (OpenCV's OPTFLOW_USE_INITIAL_FLOW)
};

/// Tracks `pts` from `prev` into `next`; `next_pts` gets the result and `status` 1 where it was found (0: the window
/// left the image or the gradient matrix was near singular at the finest level), as cv::calcOpticalFlowPyrLK without
/// an error output. Both pyramids must be built with the same window. Points are split over OpenCV's thread pool.
void lk_flow(const LkPyramid &prev, const LkPyramid &next, const std::vector<cv::Point2f> &pts,
             std::vector<cv::Point2f> &next_pts, std::vector<unsigned char> &status, const LkParams &p);

} // namespace ovton::core
