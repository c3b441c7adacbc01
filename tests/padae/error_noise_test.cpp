#include "padae/error_noise.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace padae {
namespace {

// Attempts at order 1, each a quarter of the last, whose errors fall 16 x each: truncation.
std::vector<RejectedAttempt> order_one_truncation(double h, double error, int count) {
  std::vector<RejectedAttempt> attempts;
  for (int k = 0; k < count; ++k) attempts.push_back({1, h * std::pow(0.25, k), error * std::pow(1.0 / 16, k)});
  return attempts;
}

TEST(UnfallingError, ErrorsThatFallAsTruncationDoAreNotNoise) {
  EXPECT_EQ(unfalling_error(order_one_truncation(1.6e-7, 4.1e7, 7)), "");
  // Falling 20 x slower than predicted (the derivative changes between attempts) is still
  // taken for truncation.
  EXPECT_EQ(unfalling_error(std::vector<RejectedAttempt>{{3, 1e-3, 50}, {3, 2.5e-4, 50 * std::pow(0.25, 4) * 20}}), "");
}

TEST(UnfallingError, AnErrorThatStaysAtOrderFiveIsNamedWithItsFigures) {
  // The rejected attempts of circuits/relaxation_oscillator.cir at reltol 1e-12, vntol 1e-15,
  // where v(cap) crosses zero between nodes at 5 V and 2.5 V: at order 5 the step fell 6.7 x and
  // the error 5 x (truncation: 9e4 x); then order 1 falls as truncation does.
  std::vector<RejectedAttempt> attempts{{5, 4.33e-6, 9.54}, {5, 2.59e-6, 8.49}, {5, 6.47e-7, 1.89}};
  for (const RejectedAttempt& a : order_one_truncation(1.62e-7, 4.12e7, 7)) attempts.push_back(a);
  const std::string diagnosis = unfalling_error(attempts);
  // The pair furthest above its prediction, 9.54 * (6.47e-7 / 4.33e-6)^6 = 1.07e-4, with its figures.
  for (const char* part : {"did not fall with the step", "at order 5, 9.5 tolerances at h = 4.3e-06 s, 1.9 at 6.5e-07 s",
                           "where truncation gives 0.00011", "round-off", "discontinuity of the model"})
    EXPECT_NE(diagnosis.find(part), std::string::npos) << part << " in: " << diagnosis;
}

TEST(UnfallingError, AttemptsOfDifferentOrdersAreNotCompared) {
  EXPECT_EQ(unfalling_error(std::vector<RejectedAttempt>{{5, 1e-6, 2}, {1, 1e-8, 2}}), "");
  // Nor are steps too close in size to tell.
  EXPECT_EQ(unfalling_error(std::vector<RejectedAttempt>{{5, 1e-6, 2}, {5, 0.9e-6, 2}}), "");
}

}  // namespace
}  // namespace padae
