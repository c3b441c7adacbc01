// The Bari test set's transistor amplifier (index 1, eight node voltages, reference at t = 0.2),
// in charge form. Shared by the stiff tests and the integrator benchmark.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include "padae/system.hpp"

namespace padae::testing {

// The Bari test set's transistor amplifier: M y' = f(t, y), index 1, eight node voltages.
// In charge form q = M y holds the five capacitor charges.
class TransistorAmplifier : public System {
 public:
  static constexpr double reference[8] = {-0.5562145012262709e-02, 0.3006522471903042e+01,
                                          0.2849958788608128e+01, 0.2926422536206241e+01,
                                          0.2704617865010554e+01, 0.2761837778393145e+01,
                                          0.4770927631616772e+01, 0.1236995868091548e+01};
  static Vector initial_state() {
    const double ub = 6;
    return Vector{{0, ub / 2, ub / 2, ub, ub / 2, ub / 2, ub, 0}};
  }
  // Correct digits: -log10 of the largest error relative to |reference| + 1.
  static double correct_digits(const Vector& y) {
    double worst = 0;
    for (int i = 0; i < 8; ++i) worst = std::max(worst, std::abs(y[i] - reference[i]) / (std::abs(reference[i]) + 1));
    return -std::log10(worst);
  }

  TransistorAmplifier() {
    std::vector<std::pair<int, int>> entries;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) entries.emplace_back(i, j);
    pattern_ = Pattern(8, entries);
  }
  int size() const override { return 8; }
  UnknownKind kind(int) const override { return UnknownKind::differential; }
  const Pattern& pattern() const override { return pattern_; }
  EvalStatus load(double t, const Vector& y, const Predicates&, Load& out) override {
    const double ub = 6, uf = 0.026, alpha = 0.99, beta = 1e-6, r0 = 1000, r = 9000;
    const double c[5] = {1e-6, 2e-6, 3e-6, 4e-6, 5e-6};
    const double input = 0.1 * std::sin(200 * std::numbers::pi * t);
    const double e1 = std::exp((y[1] - y[2]) / uf), e2 = std::exp((y[4] - y[5]) / uf);
    const double fac1 = beta * (e1 - 1), fac2 = beta * (e2 - 1);
    // The test set writes M y' - f(t, y) = 0; so here f_charge = -f.
    double f[8] = {(y[0] - input) / r0,
                   y[1] / r + (y[1] - ub) / r + (1 - alpha) * fac1,
                   y[2] / r - fac1,
                   (y[3] - ub) / r + alpha * fac1,
                   y[4] / r + (y[4] - ub) / r + (1 - alpha) * fac2,
                   y[5] / r - fac2,
                   (y[6] - ub) / r + alpha * fac2,
                   y[7] / r};
    for (int i = 0; i < 8; ++i) out.f[i] = -f[i];
    out.q[0] = -c[0] * y[0] + c[0] * y[1];
    out.q[1] = -out.q[0];
    out.q[2] = -c[1] * y[2];
    out.q[3] = -c[2] * y[3] + c[2] * y[4];
    out.q[4] = -out.q[3];
    out.q[5] = -c[3] * y[5];
    out.q[6] = -c[4] * y[6] + c[4] * y[7];
    out.q[7] = -out.q[6];
    if (!out.jacobian_requested) return EvalStatus::ok;
    auto df = [&](int row, int column, double value) { out.df_dx[static_cast<std::size_t>(pattern_.index(row, column))] -= value; };
    auto dq = [&](int row, int column, double value) { out.dq_dx[static_cast<std::size_t>(pattern_.index(row, column))] += value; };
    const double d1 = beta * e1 / uf, d2 = beta * e2 / uf;
    df(0, 0, 1 / r0);
    df(1, 1, 2 / r + (1 - alpha) * d1);
    df(1, 2, -(1 - alpha) * d1);
    df(2, 2, 1 / r + d1);
    df(2, 1, -d1);
    df(3, 3, 1 / r);
    df(3, 1, alpha * d1);
    df(3, 2, -alpha * d1);
    df(4, 4, 2 / r + (1 - alpha) * d2);
    df(4, 5, -(1 - alpha) * d2);
    df(5, 5, 1 / r + d2);
    df(5, 4, -d2);
    df(6, 6, 1 / r);
    df(6, 4, alpha * d2);
    df(6, 5, -alpha * d2);
    df(7, 7, 1 / r);
    const int first[3] = {0, 3, 6};
    const double pair_c[3] = {c[0], c[2], c[4]};
    for (int k = 0; k < 3; ++k) {
      int a = first[k], b = first[k] + 1;
      dq(a, a, -pair_c[k]);
      dq(a, b, pair_c[k]);
      dq(b, a, pair_c[k]);
      dq(b, b, -pair_c[k]);
    }
    dq(2, 2, -c[1]);
    dq(5, 5, -c[3]);
    return EvalStatus::ok;
  }

 private:
  Pattern pattern_;
};

}  // namespace padae::testing
