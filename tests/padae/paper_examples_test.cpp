// The paper's examples (shared/docs/predicate-dae.md, section 6), each against its closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "padae/integrator.hpp"
#include "padae/semi_explicit.hpp"
#include "paper_impacts.hpp"
#include "paper_masses.hpp"
#include "run_until.hpp"

namespace padae {
namespace {

using testing::Escapement;
using testing::EscapementModel;
using testing::PendulumClosedForm;
using testing::Pendulum;
using testing::PendulumModel;
using testing::run_until;
using testing::Masses;
using testing::MassesClosedForm;
using testing::MassesMomentum;
using testing::MassesWithJump;

Options tight() {
  Options options;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  options.time_scale = 3;
  return options;
}

TEST(PaperExample6, CaptureContactAndMotionAfterwardsMatchTheClosedForm) {
  Masses m;
  MassesClosedForm exact(m);
  ASSERT_GT(exact.t_contact, exact.t_capture);
  MassesWithJump model(m);
  Integrator integrator(model, tight());
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{0.0, 0.0, 0.0}})) << integrator.failure().reason;
  std::vector<EventRecord> events;
  const double t_end = exact.t_contact + 0.9 * (exact.t_return - exact.t_contact);
  ASSERT_TRUE(run_until(integrator, t_end, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) events.push_back(integrator.last_event());
    EXPECT_NEAR(integrator.state()[0], exact.position(integrator.time()), 1e-7);
  })) << integrator.failure().reason;
  ASSERT_EQ(events.size(), 2u);
  EXPECT_NEAR(events[0].t, exact.t_capture, 1e-9);
  EXPECT_NEAR(events[0].x_before[1], exact.v_before_capture, 1e-8);
  // The inelastic capture: v jumps by the factor M1 / (M1 + M2) on the computed v- (up to the
  // drift over the re-initialization's step of a few ulps of t).
  EXPECT_NEAR(events[0].x_after[1], m.m1 / (m.m1 + m.m2) * events[0].x_before[1], 1e-13);
  EXPECT_TRUE(events[0].jumped);
  EXPECT_NEAR(events[1].t, exact.t_contact, 1e-9);
  EXPECT_FALSE(events[1].jumped);
  EXPECT_NEAR(integrator.state()[0], exact.position(t_end), 1e-8);
  EXPECT_NEAR(integrator.state()[1], exact.velocity(t_end), 1e-8);
}

TEST(PaperExample4, MomentumFormGivesTheSameMotionWithoutJumps) {
  Masses m;
  MassesClosedForm exact(m);
  MassesMomentum model(m);
  Integrator integrator(model, tight());
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{0.0, 0.0}})) << integrator.failure().reason;
  std::vector<double> event_times;
  const double t_end = exact.t_contact + 0.9 * (exact.t_return - exact.t_contact);
  ASSERT_TRUE(run_until(integrator, t_end, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) event_times.push_back(outcome.t);
  }));
  ASSERT_EQ(event_times.size(), 2u);
  EXPECT_NEAR(event_times[0], exact.t_capture, 1e-9);
  EXPECT_NEAR(event_times[1], exact.t_contact, 1e-9);
  EXPECT_NEAR(integrator.state()[0], exact.position(t_end), 1e-8);
  EXPECT_NEAR(integrator.state()[1] / (m.m1 + m.m2), exact.velocity(t_end), 1e-8);
  EXPECT_EQ(integrator.statistics().jumps, 0);
}

TEST(PaperExample7, EscapementCountsKicksAndSettlesOnTheLimitCycle) {
  Escapement e;
  EscapementModel model(e);
  Options options = tight();
  options.time_scale = 120;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{-0.5, 0.0, 0.0, 0.0}})) << integrator.failure().reason;
  std::vector<double> kick_times, velocity_after_kick;
  int upward = 0;
  ASSERT_TRUE(run_until(integrator, 120.0, [&](const StepOutcome& outcome) {
    if (outcome.kind != StepKind::event) return;
    const EventRecord& event = integrator.last_event();
    ASSERT_FALSE(event.flips.empty());
    if (!event.flips.front().to) return;  // downward crossing: no kick
    ++upward;
    kick_times.push_back(event.t);
    velocity_after_kick.push_back(event.x_after[1]);
    EXPECT_NEAR(event.x_after[1] - event.x_before[1], e.kick, 1e-12);
    EXPECT_EQ(event.x_after[3], upward);  // q counts the kicks
  })) << integrator.failure().reason;
  ASSERT_GE(upward, 100);
  EXPECT_EQ(integrator.state()[3], upward);

  // Between kicks the oscillator is free and damped: from x = 0 upward to the next upward
  // zero crossing takes exactly the damped period.
  const double damped = std::sqrt(e.omega * e.omega - e.damping * e.damping);
  const double period = 2 * std::numbers::pi / damped;
  for (std::size_t i = 1; i < kick_times.size(); ++i)
    EXPECT_NEAR(kick_times[i] - kick_times[i - 1], period, 1e-8);
  // Return map v+_{n+1} = v+_n exp(-k T) + a: its fixed point is a / (1 - exp(-k T)).
  const double decay = std::exp(-e.damping * period);
  for (std::size_t i = 1; i < velocity_after_kick.size(); ++i)
    EXPECT_NEAR(velocity_after_kick[i], velocity_after_kick[i - 1] * decay + e.kick, 1e-7);
  EXPECT_NEAR(velocity_after_kick.back(), e.kick / (1 - decay), 1e-3);
}


TEST(PaperExample10, PendulumImpactsFollowTheQuadratureAndAccumulationIsDiagnosed) {
  Pendulum pendulum;
  const double phi0 = 0.1, omega0 = 0.5;
  const PendulumClosedForm closed_form{pendulum, phi0, omega0, 64};
  std::vector<double> impact_times{closed_form.first_impact_time()};
  std::vector<double> impact_speeds{closed_form.first_impact_speed()};
  double t_accumulation = impact_times[0];
  for (double s = impact_speeds[0]; s > 1e-30; s *= pendulum.restitution) {
    double dt = closed_form.flight(s);
    t_accumulation += dt;
    if (impact_times.size() < 8) {
      impact_times.push_back(impact_times.back() + dt);
      impact_speeds.push_back(pendulum.restitution * s);
    }
  }

  PendulumModel model(pendulum);
  Options options = tight();
  options.time_scale = 1;
  Integrator integrator(model, options);
  ASSERT_TRUE(integrator.initialize(0.0, Vector{{phi0, omega0}})) << integrator.failure().reason;
  std::vector<EventRecord> impacts;
  bool finished = run_until(integrator, 10.0, [&](const StepOutcome& outcome) {
    if (outcome.kind == StepKind::event) impacts.push_back(integrator.last_event());
    EXPECT_LE(std::sin(integrator.state()[0]), pendulum.wall + 1e-9);  // never through the wall
  });
  ASSERT_GE(impacts.size(), 8u);
  // Between impacts the error accumulates like any global error (about 1e-8 in omega per
  // flight at rtol 1e-10), so later impact times carry the sum of the earlier flights' errors.
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(impacts[i].t, impact_times[i], 1e-7) << "impact " << i;
    EXPECT_NEAR(impacts[i].x_before[1], impact_speeds[i], 1e-7 * impact_speeds[0]) << "impact " << i;
    // omega+ = -k omega- (up to the drift over a few ulps of t), with convention (9): the rod
    // is back on the free side.
    EXPECT_NEAR(impacts[i].x_after[1], -pendulum.restitution * impacts[i].x_before[1], 1e-13)
        << "impact " << i;
  }
  // The impacts accumulate (Zeno): the run stops before the accumulation point with a
  // diagnostic that names it, extrapolated from the shrinking intervals.
  ASSERT_FALSE(finished);
  const std::string& reason = integrator.failure().reason;
  const std::string marker = "event accumulation at t = ";
  ASSERT_NE(reason.find(marker), std::string::npos) << reason;
  double named = std::strtod(reason.c_str() + reason.find(marker) + marker.size(), nullptr);
  EXPECT_NEAR(named, t_accumulation, 1e-6) << reason;
  EXPECT_LT(integrator.failure().t, t_accumulation);
  EXPECT_GT(integrator.failure().t, t_accumulation - 1e-3);
}

}  // namespace
}  // namespace padae
