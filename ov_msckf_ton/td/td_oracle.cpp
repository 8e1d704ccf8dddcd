// Mode oracle: t_d is read from the dataset's truth at every image; nothing is estimated.
#include "ov_msckf_ton/td/td_models.h"

namespace ovton::msckf {

namespace {

class OracleTdModel : public TdModel {
public:
  explicit OracleTdModel(std::function<double(int64_t)> truth) : truth_(std::move(truth)) {}
  TdProcess kind() const override { return TdProcess::Constant; }
  double td_at_image(const State &, int64_t t_cam_ns, int64_t) const override { return truth_(t_cam_ns); }
  void propagate(State &s, double td_end, double) override { s.td = td_end; }

private:
  std::function<double(int64_t)> truth_;
};

} // namespace

std::unique_ptr<TdModel> make_oracle_model(std::function<double(int64_t)> truth) {
  return std::make_unique<OracleTdModel>(std::move(truth));
}

} // namespace ovton::msckf
