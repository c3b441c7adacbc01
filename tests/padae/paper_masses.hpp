// The paper's first example, (6) and (4): mass 1 on spring 1 captures mass 2 at xa and meets
// spring 2 at xb; its closed form. Shared by the tests and the "logical function" benchmark.
#pragma once

#include <cmath>
#include <vector>

#include "padae/semi_explicit.hpp"

namespace padae::testing {

constexpr auto kDifferential = UnknownKind::differential;
constexpr auto kAlgebraic = UnknownKind::algebraic;

struct Masses {
  double m1 = 1, m2 = 3, k1 = 4, k2 = 12, l1 = 2, xa = 1, xb = 1.5;
};

// Form (6): x' = v, v' = w + M2/(M1+M2) v p1', 0 = [M1 + (p1|0|M2)] w + K1(x-l1) + (p2|0|K2(x-xb)).
class MassesWithJump : public SemiExplicitSystem {
 public:
  explicit MassesWithJump(Masses m) : SemiExplicitSystem({kDifferential, kDifferential, kAlgebraic}), m_(m) {}
  EvalStatus equations(double, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = z[1];
    out[1] = z[2];
    out[2] = (m_.m1 + (p[0] ? 0 : m_.m2)) * z[2] + m_.k1 * (z[0] - m_.l1) +
             (p[1] ? 0 : m_.k2 * (z[0] - m_.xb));
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 2; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = m_.xa - z[0];  // p1 = (x < xa)
    out[1] = m_.xb - z[0];  // p2 = (x < xb)
    return EvalStatus::ok;
  }
  bool has_jumps() const override { return true; }
  void jump_matrix(double, const Vector& z, const Predicates&, std::vector<JumpEntry>& out) const override {
    out.push_back({1, 0, m_.m2 / (m_.m1 + m_.m2) * z[1]});
  }

 private:
  Masses m_;
};

// Form (4): x' = P / (M1 + (p1|0|M2)), P' = -K1(x-l1) - (p2|0|K2(x-xb)); P is the momentum.
class MassesMomentum : public SemiExplicitSystem {
 public:
  explicit MassesMomentum(Masses m) : SemiExplicitSystem({kDifferential, kDifferential}), m_(m) {}
  EvalStatus equations(double, const Vector& z, const Predicates& p, Vector& out) override {
    out[0] = z[1] / (m_.m1 + (p[0] ? 0 : m_.m2));
    out[1] = -m_.k1 * (z[0] - m_.l1) - (p[1] ? 0 : m_.k2 * (z[0] - m_.xb));
    return EvalStatus::ok;
  }
  int predicate_count() const override { return 2; }
  EvalStatus guards(double, const Vector& z, Vector& out) const override {
    out[0] = m_.xa - z[0];
    out[1] = m_.xb - z[0];
    return EvalStatus::ok;
  }

 private:
  Masses m_;
};

// The closed form: three harmonic phases glued at the capture and the contact.
struct MassesClosedForm {
  explicit MassesClosedForm(Masses m) : m(m) {
    const double w1 = std::sqrt(m.k1 / m.m1);
    t_capture = std::acos((m.xa - m.l1) / (0 - m.l1)) / w1;  // x = l1 - l1 cos(w1 t), from rest at 0
    v_before_capture = m.l1 * w1 * std::sin(w1 * t_capture);
    v_after_capture = m.m1 / (m.m1 + m.m2) * v_before_capture;
    w2 = std::sqrt(m.k1 / (m.m1 + m.m2));
    a2 = m.xa - m.l1;
    b2 = v_after_capture / w2;
    const double radius = std::hypot(a2, b2), angle = std::atan2(b2, a2);
    t_contact = t_capture + (angle - std::acos((m.xb - m.l1) / radius)) / w2;
    v_contact = velocity(t_contact);
    w3 = std::sqrt((m.k1 + m.k2) / (m.m1 + m.m2));
    center3 = (m.k1 * m.l1 + m.k2 * m.xb) / (m.k1 + m.k2);
    // x returns to xb after w3 (t - t_contact) = 2 atan2(b3, a3) - ... : the other root.
    a3 = m.xb - center3;
    b3 = v_contact / w3;
    t_return = t_contact + std::atan2(b3, a3) / w3;
  }
  double position(double t) const {
    if (t <= t_capture) return m.l1 - m.l1 * std::cos(std::sqrt(m.k1 / m.m1) * t);
    if (t <= t_contact) {
      double s = w2 * (t - t_capture);
      return m.l1 + a2 * std::cos(s) + b2 * std::sin(s);
    }
    double s = w3 * (t - t_contact);
    return center3 + a3 * std::cos(s) + b3 * std::sin(s);
  }
  double velocity(double t) const {
    if (t <= t_capture) return m.l1 * std::sqrt(m.k1 / m.m1) * std::sin(std::sqrt(m.k1 / m.m1) * t);
    if (t <= t_contact) {
      double s = w2 * (t - t_capture);
      return w2 * (-a2 * std::sin(s) + b2 * std::cos(s));
    }
    double s = w3 * (t - t_contact);
    return w3 * (-a3 * std::sin(s) + b3 * std::cos(s));
  }
  Masses m;
  double t_capture, v_before_capture, v_after_capture, w2, a2, b2, t_contact, v_contact, w3,
      center3, a3, b3, t_return;
};

}  // namespace padae::testing
