#pragma once
// Stateless per-pixel (per-texel) noise: a value depends only on (seed, index), so images are reproducible whatever
// order pixels are drawn in, and no generator state is carried between frames.
#include <cstdint>

namespace ovton::sim {

/// SplitMix64's finaliser, top 32 bits: a well-mixed hash of a 64-bit key.
inline uint32_t hash32(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  x ^= x >> 33;
  return static_cast<uint32_t>(x);
}

/// Key of element `index` of a noise field `seed`.
inline uint64_t noise_key(uint64_t seed, uint64_t index) {
  return seed * 0x9E3779B97F4A7C15ULL + index;
}

/// Approximately standard normal from one key: the sum of four 16-bit uniforms (Irwin-Hall), rescaled to unit
/// variance. Tails stop at 3.46 sigma, which sensor and grain noise never need to exceed.
inline float approx_normal(uint64_t key) {
  const uint64_t a = hash32(key), b = hash32(key ^ 0xD1B54A32D192ED03ULL);
  const float s = static_cast<float>(a & 0xFFFF) + static_cast<float>(a >> 16) + static_cast<float>(b & 0xFFFF) +
                  static_cast<float>(b >> 16);
  // Mean 2 * 65535, variance 4 * 65536^2 / 12 (uniform on [0, 65535]); 1 / sqrt(4/12) / 65536 = 2.6429e-5.
  return (s - 131070.0f) * 2.6429e-5f;
}

} // namespace ovton::sim
