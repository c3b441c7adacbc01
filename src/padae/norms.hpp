// The largest weighted entry |v_i| w_i, with its index; NaN counts as infinite (a diverging
// iterate is never taken as small). Shared by the integrator and re-initialization.
#pragma once

#include <cstdint>

#include "padae/system.hpp"

namespace padae {

double weighted_max_norm(const Vector& v, const Vector& inverse_weight, int* worst = nullptr);

// The magnitude the error test applies rtol to: |x_i|, or at least peak_floor of the unknown's
// peak so far (Options::peak_floor). An expression on x and peak, evaluated where it is
// assigned (the integrator's per-step weights reuse their vector).
inline auto error_scale(const Vector& x, const Vector& peak, double peak_floor) {
  return x.cwiseAbs().cwiseMax(peak_floor * peak);
}

// Knuth's multiplicative hash of an index: bits independent of the circuit's structure, for
// start vectors and rounding signs that must not cancel systematically.
inline std::uint32_t scrambled(int index) { return static_cast<std::uint32_t>(index) * 2654435761u; }

// A Newton correction (norm in tolerance units) that no longer contracts on a fresh matrix.
inline bool stalled(double norm, double previous_norm) { return norm >= 0.5 * previous_norm; }
// Stalled within the tolerance: the round-off floor of the solves (tight tolerances,
// ill-conditioned matrices), not a failure.
inline bool stalled_at_roundoff(double norm, double previous_norm) { return norm <= 1 && stalled(norm, previous_norm); }

}  // namespace padae
