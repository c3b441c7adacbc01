// The paper's examples with impacts, (7) the clock escapement and (10) the pendulum striking a
// wall, and the quadrature their closed forms need. Shared by the tests and the IDA comparison.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include "padae/semi_explicit.hpp"
#include "paper_masses.hpp"  // kDifferential, kAlgebraic

namespace padae::testing {

constexpr auto kAuxiliary = UnknownKind::auxiliary;

// --- (7) the clock escapement, with the kick counter q ---------------------------------------
struct Escapement {
  double damping = 0.1, omega = 2 * std::numbers::pi, kick = 0.5;
};

class EscapementModel : public SemiExplicitSystem {
 public:
  explicit EscapementModel(Escapement e) : SemiExplicitSystem({kDifferential, kDifferential, kAlgebraic, kAuxiliary}), e_(e) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = z[1];
    out[1] = z[2];
    out[2] = z[2] + 2 * e_.damping * z[1] + e_.omega * e_.omega * z[0];
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = z[0];  // p = (x >= 0)
    return EvalStatus::ok;
  }
  bool has_jumps() const override { return true; }
  // v' = w + (p|0|a) p',  q' = (p|0|1) p', evaluated before the event.
  void jump_matrix(double, const Vector&, const Predicates& p, std::vector<padae::JumpEntry>& out) const override {
    if (p[0]) return;
    out.push_back({1, 0, e_.kick});
    out.push_back({3, 0, 1.0});
  }

 private:
  Escapement e_;
};

// --- (10) the pendulum striking a wall --------------------------------------------------------
struct Pendulum {
  double c = 3 * 9.81 / (4 * 0.5);   // C = 3 g / (4 r), r = 0.5 m
  double wall = 0.5;                 // a / (2 r): the rod's end touches the wall at sin(phi) = 0.5
  double restitution = 0.5;
};

class PendulumModel : public SemiExplicitSystem {
 public:
  explicit PendulumModel(Pendulum p) : SemiExplicitSystem({kDifferential, kDifferential}), p_(p) {}
  EvalStatus equations(double, const Vector& z, const Predicates&, Vector& out) override {
    out[0] = z[1];
    out[1] = p_.c * std::sin(z[0]);
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 1; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = p_.wall - std::sin(z[0]);  // p = (sin(phi) < a / 2r): clear of the wall
    return EvalStatus::ok;
  }
  bool has_jumps() const override { return true; }
  // omega' = ... + (p | (1 + k) omega | 0) p': at impact (p: 1 -> 0) omega -> -k omega.
  void jump_matrix(double, const Vector& z, const Predicates& p, std::vector<padae::JumpEntry>& out) const override {
    if (p[0]) out.push_back({1, 0, (1 + p_.restitution) * z[1]});
  }

 private:
  Pendulum p_;
};

// Gauss-Legendre (20 points) on n panels of [a, b].
template <class F>
double gauss_legendre(F f, double a, double b, int panels) {
  static const double nodes[10] = {0.0765265211334973, 0.2277858511416451, 0.3737060887154195,
                                   0.5108670019508271, 0.6360536807265150, 0.7463319064601508,
                                   0.8391169718222188, 0.9122344282513259, 0.9639719272779138,
                                   0.9931285991850949};
  static const double weights[10] = {0.1527533871307258, 0.1491729864726037, 0.1420961093183820,
                                     0.1316886384491766, 0.1181945319615184, 0.1019301198172404,
                                     0.0832767415767048, 0.0626720483341091, 0.0406014298003869,
                                     0.0176140071391521};
  double sum = 0, width = (b - a) / panels;
  for (int i = 0; i < panels; ++i) {
    double middle = a + (i + 0.5) * width, half = 0.5 * width;
    for (int j = 0; j < 10; ++j)
      sum += half * weights[j] * (f(middle - half * nodes[j]) + f(middle + half * nodes[j]));
  }
  return sum;
}

// The pendulum's closed form by quadrature, from phi0 and omega0 (Gauss-Legendre on `panels`).
struct PendulumClosedForm {
  Pendulum pendulum;
  double phi0, omega0;
  int panels;

  double phi_wall() const { return std::asin(pendulum.wall); }
  // Energy: omega^2 / 2 + C cos(phi) is conserved between impacts.
  double speed(double phi) const {
    return std::sqrt(omega0 * omega0 + 2 * pendulum.c * (std::cos(phi0) - std::cos(phi)));
  }
  double first_impact_time() const {
    return gauss_legendre([&](double phi) { return 1 / speed(phi); }, phi0, phi_wall(), panels);
  }
  double first_impact_speed() const { return speed(phi_wall()); }
  // After an impact at speed s the rod leaves at k s, turns at phi_t and returns at speed k s:
  // flight time 2 int_{phi_t}^{phi_wall} dphi / omega, with phi = phi_t + u^2 removing the
  // turning point's square-root singularity.
  double flight(double s) const {
    const double c = pendulum.c, leave = pendulum.restitution * s;
    const double phi_turn = std::acos(std::cos(phi_wall()) + leave * leave / (2 * c));
    auto integrand = [&](double u) {
      if (u == 0) return 2 / std::sqrt(2 * c * std::sin(phi_turn));
      double drop = 2 * std::sin(phi_turn + 0.5 * u * u) * std::sin(0.5 * u * u);
      return 2 * u / std::sqrt(2 * c * drop);
    };
    return 2 * gauss_legendre(integrand, 0.0, std::sqrt(phi_wall() - phi_turn), panels);
  }
};

}  // namespace padae::testing
