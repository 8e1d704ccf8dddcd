#pragma once
// The online training loop shared by ITS-FVON, F2F-FVON and TPN: full-batch Adam steps on the window's labels,
// stopped at the paper's epoch limit or loss threshold (Table I).
#include "ov_msckf_ton/ton/adam.h"
#include "ov_msckf_ton/ton/ton_options.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace ovton::msckf {
namespace ton {

struct TrainReport {
  int epochs = 0;           ///< Adam steps taken in this call.
  int num_labels = 0;       ///< Labels in the training window (n in eq. 7 / 12).
  double initial_loss = 0.; ///< MSE before the first step (normalised units).
  double final_loss = 0.;   ///< MSE after the last step (normalised units).
  bool converged = false;   ///< True if stopped by the loss threshold.
  bool plateaued = false;   ///< True if stopped by the plateau rule.
  double seconds = 0.;      ///< Wall time of the call, so the per-frame cost can be reported.
};

/// Runs at most `opt.max_epochs` Adam steps on `net`, continuing from its current weights (warm start). The loss is
/// evaluated once more after the last step so that `final_loss` is the loss of the weights that are kept.
template <typename Net>
TrainReport train_network(Net &net, Adam<Net::kNumParams> &adam, const typename Net::Data &data,
                          const TrainOptions &opt) {
  const auto t0 = std::chrono::steady_clock::now();
  TrainReport rep;
  rep.num_labels = data.num_labels();
  if (rep.num_labels == 0)
    return rep;
  OVTON_TON_CHECK(opt.max_epochs >= 0, "train_network: max_epochs must be >= 0");
  typename Net::Params grad;
  double checkpoint = 0.0;
  for (int epoch = 0;; ++epoch) {
    const double loss = net.loss_and_gradient(data, grad);
    OVTON_TON_CHECK(std::isfinite(loss), "train_network: loss became non-finite");
    if (epoch == 0)
      rep.initial_loss = checkpoint = loss;
    rep.final_loss = loss;
    if (opt.loss_threshold > 0.0 && loss < opt.loss_threshold) {
      rep.converged = true;
      break;
    }
    if (opt.plateau_epochs > 0 && epoch > 0 && epoch % opt.plateau_epochs == 0) {
      if (checkpoint - loss < opt.plateau_rel * loss) {
        rep.plateaued = true;
        break;
      }
      checkpoint = loss;
    }
    if (epoch == opt.max_epochs)
      break;
    adam.step(net.params(), grad);
    rep.epochs = epoch + 1;
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rep;
}

} // namespace ton
} // namespace ovton::msckf
