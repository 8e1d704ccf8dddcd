#include "ov_msckf_ton/state/state.h"
#include "ov_core/math/so3.h"

namespace ovton::msckf {

State::State(bool estimate_td) {
  const int n = ImuState::kSize + (estimate_td ? 1 : 0);
  P = Eigen::MatrixXd::Zero(n, n);
  if (estimate_td)
    td_index = ImuState::kSize;
}

int State::add_variable(const Eigen::MatrixXd &prior) {
  const int n = dim(), k = static_cast<int>(prior.rows());
  for_each_covariance([&](auto &C) {
    using Mat = std::decay_t<decltype(C)>;
    Mat Pn = Mat::Zero(n + k, n + k);
    Pn.topLeftCorner(n, n) = C;
    Pn.bottomRightCorner(k, k) = prior.cast<covariance_scalar<decltype(C)>>();
    C = std::move(Pn);
  });
  return n;
}

void State::remove_block(int idx, int size) {
  const int n = dim(), m = n - size;
  // Keep [0, idx) and [idx + size, n): four contiguous blocks, no index lists.
  const int tail = n - idx - size;
  for_each_covariance([&](auto &C) {
    std::decay_t<decltype(C)> Pn(m, m);
    Pn.topLeftCorner(idx, idx) = C.topLeftCorner(idx, idx);
    Pn.topRightCorner(idx, tail) = C.topRightCorner(idx, tail);
    Pn.bottomLeftCorner(tail, idx) = C.bottomLeftCorner(tail, idx);
    Pn.bottomRightCorner(tail, tail) = C.bottomRightCorner(tail, tail);
    C = std::move(Pn);
  });
  const auto shift = [&](int &i) {
    if (i > idx)
      i -= size;
  };
  shift(td_index);
  shift(td_rate_index);
  for (auto &c : cam_td) {
    shift(c.index);
    shift(c.rate_index);
  }
  shift(calib.extrinsics_index);
  shift(calib.intrinsics_index);
  shift(calib.readout_index);
  shift(calib.imu_intrinsics_index);
  for (auto &[key, c] : clones)
    shift(c.index);
  for (auto &[key, l] : landmarks)
    shift(l.index);
}

void State::boxplus(const Eigen::VectorXd &dx) {
  imu.R = ovton::core::so3_exp(dx.segment<3>(ImuState::kTheta)) * imu.R;
  imu.p += dx.segment<3>(ImuState::kPos);
  imu.v += dx.segment<3>(ImuState::kVel);
  imu.bg += dx.segment<3>(ImuState::kBg);
  imu.ba += dx.segment<3>(ImuState::kBa);
  if (td_index >= 0)
    td += dx(td_index);
  if (td_rate_index >= 0)
    td_rate += dx(td_rate_index);
  for (auto &c : cam_td) {
    c.delta += dx(c.index);
    if (c.rate_index >= 0)
      c.rate += dx(c.rate_index);
  }
  for (auto &[key, c] : clones) {
    c.R = ovton::core::so3_exp(dx.segment<3>(c.index)) * c.R;
    c.p += dx.segment<3>(c.index + 3);
  }
  for (auto &[key, l] : landmarks)
    l.p_W += dx.segment<3>(l.index);
  if (calib.extrinsics_index >= 0) {
    calib.R_BC = ovton::core::so3_exp(dx.segment<3>(calib.extrinsics_index)) * calib.R_BC;
    calib.p_BC += dx.segment<3>(calib.extrinsics_index + 3);
  }
  if (calib.intrinsics_index >= 0)
    calib.intrinsics += dx.segment<8>(calib.intrinsics_index);
  if (calib.readout_index >= 0)
    calib.readout_s += dx(calib.readout_index);
  if (calib.imu_intrinsics_index >= 0)
    for (int k = 0; k < 6; ++k) {
      calib.D_w(kTriRow[k], kTriCol[k]) += dx(calib.imu_intrinsics_index + k);
      calib.D_a(kTriRow[k], kTriCol[k]) += dx(calib.imu_intrinsics_index + 6 + k);
    }
}

} // namespace ovton::msckf
