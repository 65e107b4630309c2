#pragma once

#include <cmath>
#include <cstdint>

namespace ssta::synth {

/// SplitMix64 finaliser: a well-mixed 64-bit hash of `x`.
inline std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A small deterministic random generator (SplitMix64). Unlike the standard distributions its
/// numbers are the same on every platform and library, so a seed always gives the same bytes.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(Mix64(seed)) {}
  std::uint64_t Next() {
    state_ += 0x9e3779b97f4a7c15ULL;
    return Mix64(state_);
  }
  /// Uniform in [lo, hi).
  double Uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(Next() >> 11) * (1.0 / 9007199254740992.0);
  }
  /// Standard normal (Box-Muller).
  double Gaussian() {
    const double u1 = Uniform(1e-300, 1.0), u2 = Uniform(0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace ssta::synth
