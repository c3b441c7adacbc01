#include "padae/error_noise.hpp"

#include <cmath>

#include "padae/text.hpp"

namespace padae {

namespace {

// An error this far above truncation's prediction is not truncation: the prediction's own
// uncertainty (the derivative changing between the two attempts) is a few times, not 100.
constexpr double kNoiseExcess = 100;
// Pairs closer than this in h say little: their predictions differ from 1 by too little.
constexpr double kSmallerStep = 0.5;

double predicted_error(const RejectedAttempt& larger, double h) {
  return larger.error * std::pow(h / larger.h, larger.order + 1);
}

}  // namespace

std::string unfalling_error(std::span<const RejectedAttempt> attempts) {
  const RejectedAttempt* larger = nullptr;
  const RejectedAttempt* smaller = nullptr;
  double worst_excess = kNoiseExcess;
  for (std::size_t i = 0; i < attempts.size(); ++i)
    for (std::size_t j = 0; j < attempts.size(); ++j) {
      const RejectedAttempt &a = attempts[i], &b = attempts[j];
      if (a.order != b.order || !(b.h <= kSmallerStep * a.h)) continue;
      const double excess = b.error / predicted_error(a, b.h);
      if (excess > worst_excess) {
        worst_excess = excess;
        larger = &a;
        smaller = &b;
      }
    }
  if (!larger) return {};
  return "the error did not fall with the step: at order " + std::to_string(larger->order) + ", " +
         format_number(larger->error, 2) + " tolerances at h = " + format_number(larger->h, 2) + " s, " +
         format_number(smaller->error, 2) + " at " + format_number(smaller->h, 2) + " s, where truncation gives " +
         format_number(predicted_error(*larger, smaller->h), 2) +
         "; it is round-off (a tolerance below what double precision resolves here) or a "
         "discontinuity of the model";
}

}  // namespace padae
