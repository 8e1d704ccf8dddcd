#pragma once
// Seeded weight initialisation shared by the networks.
#include <Eigen/Core>
#include <cstdint>
#include <random>

namespace ovton::msckf {
namespace ton {

/// Uniform draw in (-bound, bound) built from the raw mt19937 output rather than std::uniform_real_distribution,
/// whose algorithm is implementation-defined: the same seed then gives the same weights with any standard library.
inline double uniform_symmetric(std::mt19937 &rng, double bound) {
  const double u = (static_cast<double>(rng()) + 0.5) / 4294967296.0; // (0,1)
  return bound * (2.0 * u - 1.0);
}

template <typename Derived> void fill_uniform(Eigen::MatrixBase<Derived> &&m, std::mt19937 &rng, double bound) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      m(r, c) = uniform_symmetric(rng, bound);
}

} // namespace ton
} // namespace ovton::msckf
