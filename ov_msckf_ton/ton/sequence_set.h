#pragma once
// Training data containers. They keep their capacity across clear() so that refilling them every frame does not
// allocate once the largest window has been seen.
#include "ov_msckf_ton/ton/ton_error.h"

#include <Eigen/Core>
#include <vector>

namespace ovton::msckf {
namespace ton {

/// Independent (input, target) pairs for the MLP.
template <int In, int Out> class PairSet {
public:
  using Input = Eigen::Matrix<double, In, 1>;
  using Target = Eigen::Matrix<double, Out, 1>;

  void clear() {
    inputs_.clear();
    targets_.clear();
  }
  void reserve(int n) {
    inputs_.reserve(n);
    targets_.reserve(n);
  }
  void push(const Input &x, const Target &y) {
    OVTON_TON_CHECK(x.allFinite() && y.allFinite(), "PairSet::push: non-finite sample");
    inputs_.push_back(x);
    targets_.push_back(y);
  }
  int num_labels() const { return static_cast<int>(inputs_.size()); }
  const Input &input(int i) const { return inputs_[i]; }
  const Target &target(int i) const { return targets_[i]; }

private:
  std::vector<Input> inputs_;
  std::vector<Target> targets_;
};

/// Ragged set of sequences for the LSTM: every step has an input and a target (the paper's labels, eq. 7/12).
/// The steps are a PairSet stored back to back; each sequence starts from a zero hidden and cell state.
template <int In, int Out> class SequenceSet : public PairSet<In, Out> {
  using Base = PairSet<In, Out>;

public:
  using typename Base::Input;
  using typename Base::Target;

  void clear() {
    Base::clear();
    starts_.clear();
  }
  void reserve(int steps, int sequences) {
    Base::reserve(steps);
    starts_.reserve(sequences);
  }
  /// Opens a new sequence; the following push() calls append to it.
  void begin_sequence() { starts_.push_back(Base::num_labels()); }
  void push(const Input &x, const Target &y) {
    OVTON_TON_CHECK(!starts_.empty(), "SequenceSet::push before begin_sequence");
    Base::push(x, y);
  }

  int num_sequences() const { return static_cast<int>(starts_.size()); }
  int begin(int s) const { return starts_[s]; }
  int end(int s) const { return s + 1 < num_sequences() ? starts_[s + 1] : Base::num_labels(); }

private:
  std::vector<int> starts_;
};

} // namespace ton
} // namespace ovton::msckf
