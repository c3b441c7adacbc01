// B: a behavioral source, V= (a branch current like a voltage source, va - vb = value) or I=
// (current value from node a through the source to node b). Its conditions are predicates
// (see behavioral_expression.hpp); its derivatives come from the expression itself.
#include <memory>

#include "mna/behavioral_expression.hpp"
#include "mna/device.hpp"

namespace mna {
namespace {

class BehavioralSource final : public PredicateDevice {
 public:
  explicit BehavioralSource(const ElementSpec& spec)
      : PredicateDevice(spec), is_current_(spec.expression_is_current) {
    require_nodes(spec, 2);
    if (!spec.expression) throw ModelError("B source '" + spec.name + "' needs V= or I=");
  }
  void allocate(Unknowns& u) override {
    a_ = u.node(card().nodes[0]), b_ = u.node(card().nodes[1]);
    if (!is_current_) branch_ = u.add("i(" + name() + ")", UnknownCategory::branch_current, name());
  }
  void declare(Stamper& s) override {
    expression_ = std::make_unique<BehavioralExpression>(*card().expression, s.unknowns(), name());
    const auto& inputs = expression_->inputs();
    gradient_.resize(inputs.size());
    if (is_current_) {
      slots_a_.resize(inputs.size()), slots_b_.resize(inputs.size());
      for (std::size_t k = 0; k < inputs.size(); ++k)
        s.entry(a_, inputs[k], slots_a_[k]), s.entry(b_, inputs[k], slots_b_[k]);
      return;
    }
    s.entry(a_, branch_, slot_a_branch_), s.entry(b_, branch_, slot_b_branch_);
    s.entry(branch_, a_, slot_branch_a_), s.entry(branch_, b_, slot_branch_b_);
    slots_a_.resize(inputs.size());
    for (std::size_t k = 0; k < inputs.size(); ++k) s.entry(branch_, inputs[k], slots_a_[k]);
  }
  bool constant_jacobian() const override { return expression_->constant_gradient(); }
  void load(Evaluation& e) const override {
    const std::uint8_t* p = e.p.data() + first_predicate();
    const double value = expression_->evaluate(e.t, e.x, p, e.jacobian() ? gradient_.data() : nullptr);
    if (is_current_) {
      e.f(a_, value), e.f(b_, -value);
      if (e.jacobian())
        for (std::size_t k = 0; k < gradient_.size(); ++k) e.df(slots_a_[k], gradient_[k]), e.df(slots_b_[k], -gradient_[k]);
      return;
    }
    const double i = e.value(branch_);
    e.f(a_, i), e.f(b_, -i);
    e.f(branch_, e.value(a_) - e.value(b_) - value);
    if (!e.jacobian()) return;
    e.df(slot_a_branch_, 1), e.df(slot_b_branch_, -1), e.df(slot_branch_a_, 1), e.df(slot_branch_b_, -1);
    for (std::size_t k = 0; k < gradient_.size(); ++k) e.df(slots_a_[k], -gradient_[k]);
  }
  void edges(std::vector<Edge>& out) const override {
    out.push_back({a_, b_, is_current_ ? current_source_connection(a_, b_, expression_->inputs()) : Connection::voltage_defined,
                   name()});
  }
  int predicate_count() const override { return expression_ ? expression_->predicate_count() : 0; }
  std::string predicate_label(int local) const override { return expression_->predicate_label(local); }
  void guards(double t, const Vector& x, double* out) const override { expression_->guards(t, x, out); }

 private:
  bool is_current_;
  std::unique_ptr<BehavioralExpression> expression_;
  mutable std::vector<double> gradient_;
  int a_ = ground, b_ = ground, branch_ = ground;
  std::vector<int> slots_a_, slots_b_;  // I=: rows a and b; V=: the branch row
  int slot_a_branch_ = -1, slot_b_branch_ = -1, slot_branch_a_ = -1, slot_branch_b_ = -1;
};

const Registration registration("b", [](const ElementSpec& spec, const RunSettings&, DeviceArena& arena) {
  return arena.make<BehavioralSource>(spec);
});

}  // namespace
}  // namespace mna
