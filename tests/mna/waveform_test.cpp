// Source functions against their closed forms, with ngspice's defaults, and their corners.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "mna/device.hpp"
#include "mna/waveform.hpp"

namespace mna {
namespace {

using Shape = Waveform::Shape;
const RunSettings run{.tstep = 1e-6, .tstop = 1e-3};

TEST(Waveform, PulseRampsHoldsAndRepeats) {
  SourceFunction f({Shape::pulse, {1, 5, 2e-6, 1e-6, 2e-6, 3e-6, 10e-6}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(0), 1);
  EXPECT_DOUBLE_EQ(f.value(2.5e-6), 3);        // halfway up the rise
  EXPECT_DOUBLE_EQ(f.value(4e-6), 5);
  EXPECT_DOUBLE_EQ(f.value(7e-6), 3);          // halfway down the fall (6 us .. 8 us)
  EXPECT_DOUBLE_EQ(f.value(9e-6), 1);
  EXPECT_NEAR(f.value(12.5e-6), 3, 1e-9);      // next period
  EXPECT_DOUBLE_EQ(f.next_corner(0), 2e-6);
  EXPECT_DOUBLE_EQ(f.next_corner(2e-6), 3e-6);
  EXPECT_DOUBLE_EQ(f.next_corner(3e-6), 6e-6);
  EXPECT_DOUBLE_EQ(f.next_corner(6e-6), 8e-6);
  EXPECT_NEAR(f.next_corner(8e-6), 12e-6, 1e-18);
  EXPECT_NEAR(f.next_corner(12.1e-6), 13e-6, 1e-18);
}

TEST(Waveform, PulseCornersAgreeWithValuesAfterManyPeriods) {
  // A triangle: every period starts at -1 exactly on the corner the integrator lands on, and
  // rises right after it (floating-point period arithmetic must not put the kink a few ulps off).
  SourceFunction f({Shape::pulse, {-1, 1, 0, 50e-6, 50e-6, 1e-15, 100e-6}}, 0, run, "vtri");
  for (double t = f.next_corner(0); t < 10e-3; t = f.next_corner(t)) {
    const double v = f.value(t), after = f.value(t + 1e-12);
    if (v < 0) {
      EXPECT_DOUBLE_EQ(v, -1) << "corner " << t;
      EXPECT_GT(after, -1) << "corner " << t;
    } else {
      EXPECT_DOUBLE_EQ(v, 1) << "corner " << t;
      EXPECT_LT(after, 1) << "corner " << t;
    }
  }
}

TEST(Waveform, PulseValuesAndCornersDoNotDependOnTheOrderOfQueries) {
  // Queries jumping back and forth between periods (the integrator, its event location and its
  // output each evaluate at their own times) each see their own period. Reference: ngspice's
  // form of PULSE, by fmod of the time since TD.
  const double v1 = 1, v2 = 5, td = 2e-6, tr = 1e-6, tf = 2e-6, pw = 3e-6, per = 10e-6;
  SourceFunction f({Shape::pulse, {v1, v2, td, tr, tf, pw, per}}, 0, run, "v1");
  auto pulse = [&](double t) {
    if (t <= td) return v1;
    const double tt = std::fmod(t - td, per);
    if (tt < tr) return v1 + (v2 - v1) * tt / tr;
    if (tt <= tr + pw) return v2;
    if (tt < tr + pw + tf) return v2 + (v1 - v2) * (tt - tr - pw) / tf;
    return v1;
  };
  auto next_corner = [&](double t) {
    double next = infinity;
    for (double m = std::max(0.0, std::floor((t - td) / per) - 1); m <= std::floor((t - td) / per) + 2; ++m) {
      const double start = td + m * per;
      for (double corner : {start, start + tr, start + tr + pw, start + tr + pw + tf})
        if (corner > t) next = std::min(next, corner);
    }
    return next;
  };
  std::mt19937 random(7);
  std::uniform_real_distribution<double> time(0, 100e-6);
  for (int k = 0; k < 2000; ++k) {
    const double t = time(random);
    EXPECT_NEAR(f.value(t), pulse(t), 1e-9) << "t = " << t;
    EXPECT_NEAR(f.next_corner(t), next_corner(t), 1e-18) << "t = " << t;
  }
}

TEST(Waveform, ZeroPulseWidthMeansTstopAsInNgspice) {
  // PULSE(-1 1 0 50u 50u 0 100u) is no triangle in ngspice: PW = 0 becomes TSTOP, so the
  // level stays high until the period restarts.
  SourceFunction f({Shape::pulse, {-1, 1, 0, 50e-6, 50e-6, 0, 100e-6}}, 0, run, "vtri");
  EXPECT_DOUBLE_EQ(f.value(75e-6), 1);
  EXPECT_DOUBLE_EQ(f.value(100e-6), 1);  // the left limit at the jump
  EXPECT_DOUBLE_EQ(f.value(100.001e-6), -1 + 2 * 0.001 / 50);
  EXPECT_DOUBLE_EQ(f.next_corner(50e-6), 100e-6);
  EXPECT_DOUBLE_EQ(f.next_corner(100e-6), 150e-6);
}

TEST(Waveform, PulseDefaultsFollowNgspice) {
  // TR = TF = TSTEP when omitted or zero; PW = PER = TSTOP.
  SourceFunction f({Shape::pulse, {0, 1, 0, 0}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(0.5e-6), 0.5);
  EXPECT_DOUBLE_EQ(f.value(0.5e-3), 1);
  EXPECT_DOUBLE_EQ(f.next_corner(0), 1e-6);
  // TR + PW > PER: the pulse restarts at the period's end, as ngspice's fmod(t - TD, PER) does.
  EXPECT_DOUBLE_EQ(f.next_corner(1e-6), 1e-3);
}

TEST(Waveform, PulseCutShortByItsPeriodJumpsAtThePeriodsStart) {
  // TR + PW + TF = 12 us > PER = 3 us: each period starts while the last is still at V2.
  SourceFunction f({Shape::pulse, {0, 2, 1e-6, 1e-9, 1e-9, 10e-6, 3e-6}}, 0, run, "v1");
  EXPECT_FALSE(f.jumps_at(1e-6));  // the first rise starts from V1
  EXPECT_FALSE(f.jumps_at(1e-6 + 1e-9));
  int jumps = 0;
  for (double t = f.next_corner(1e-6 + 1e-9); t < 301.5e-6; t = f.next_corner(t)) {
    const double phase = std::fmod(t - 1e-6, 3e-6);  // near 0: a period's start; else the rise's end
    const bool starts_period = std::min(phase, 3e-6 - phase) < 1e-12;
    EXPECT_EQ(f.jumps_at(t), starts_period) << "t = " << t;
    EXPECT_FALSE(f.jumps_at(std::nextafter(std::nextafter(t, 1.0), 1.0))) << "t = " << t;  // no corner there
    jumps += starts_period;
  }
  EXPECT_EQ(jumps, 100);
  SourceFunction sine({Shape::sine, {0, 1, 1e3, 1e-4}}, 0, run, "v2");
  EXPECT_FALSE(sine.jumps_at(1e-4));
}

TEST(Waveform, PulseCountStopsRepeating) {
  SourceFunction f({Shape::pulse, {0, 1, 0, 1e-6, 1e-6, 1e-6, 5e-6, 2}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(6.5e-6), 1);  // second pulse
  EXPECT_DOUBLE_EQ(f.value(11.5e-6), 0); // no third
  EXPECT_EQ(f.next_corner(10e-6), infinity);
}

TEST(Waveform, SineWithDelayDampingAndPhase) {
  using std::numbers::pi;
  SourceFunction f({Shape::sine, {0.5, 2, 1e3, 1e-4, 100, 30}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(0), 0.5 + 2 * std::sin(pi / 6));
  const double t = 3e-4;
  EXPECT_NEAR(f.value(t), 0.5 + 2 * std::sin(2 * pi * 1e3 * (t - 1e-4) + pi / 6) * std::exp(-(t - 1e-4) * 100), 1e-14);
  EXPECT_DOUBLE_EQ(f.next_corner(0), 1e-4);
  EXPECT_EQ(f.next_corner(1e-4), infinity);
  // FREQ defaults to 1/TSTOP.
  SourceFunction g({Shape::sine, {0, 1}}, 0, run, "v2");
  EXPECT_NEAR(g.value(0.25e-3), 1, 1e-12);
  EXPECT_DOUBLE_EQ(f.resolution_step(), 1 / (20 * 1e3));  // a twentieth of the period
}

TEST(Waveform, FrequencyModulatedSineAsNgspice) {
  // SFFM(VO VA FC MDI FS PHASEC PHASES), phases in degrees: ngspice 38 writes
  // 0.5 + 2 sin(2 pi 10k t + PHASEC + 3 sin(2 pi 1k t + PHASES)) to within 5e-9 V.
  using std::numbers::pi;
  SourceFunction f({Shape::frequency_modulated, {0.5, 2, 10e3, 3, 1e3, 45, 30}}, 0, run, "v1");
  for (double t : {0.0, 1.3e-5, 2.71e-4, 9.99e-4})
    EXPECT_NEAR(f.value(t), 0.5 + 2 * std::sin(2 * pi * 10e3 * t + pi / 4 + 3 * std::sin(2 * pi * 1e3 * t + pi / 6)),
                1e-12)
        << "t = " << t;
  EXPECT_EQ(f.next_corner(0), infinity);
  EXPECT_DOUBLE_EQ(f.resolution_step(), 1 / (20 * (10e3 + 3 * 1e3)));  // the highest frequency
  // FC and FS 1/TSTOP when omitted or zero, MDI 0 when omitted.
  SourceFunction g({Shape::frequency_modulated, {0.1, 1, 0, 2}}, 0, run, "v2");
  EXPECT_NEAR(g.value(0.3e-3), 0.1 + std::sin(2 * pi * 0.3 + 2 * std::sin(2 * pi * 0.3)), 1e-12);
  SourceFunction h({Shape::frequency_modulated, {0, 1}}, 0, run, "v3");
  EXPECT_NEAR(h.value(0.25e-3), 1, 1e-12);
}

TEST(Waveform, ExponentialRiseAndFall) {
  SourceFunction f({Shape::exponential, {0, 1, 1e-6, 2e-6, 5e-6, 1e-6}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(0.5e-6), 0);
  EXPECT_NEAR(f.value(3e-6), 1 - std::exp(-1.0), 1e-15);
  EXPECT_NEAR(f.value(7e-6), (1 - std::exp(-3.0)) - (1 - std::exp(-2.0)), 1e-15);
  EXPECT_DOUBLE_EQ(f.next_corner(0), 1e-6);
  EXPECT_DOUBLE_EQ(f.next_corner(1e-6), 5e-6);
}

// TD2 before TD1: ngspice holds V1 up to TD1, then jumps to both terms at once (vsrcload.c).
// padsim applied the fall from TD2 on, below V1 before the rise began. The numbers are ngspice
// 39's run of V1 x 0 EXP(0 1 1m 10u 0.5m 20u) with .tran 1u 2m 0 1u.
TEST(Waveform, ExponentialWithTd2BeforeTd1HoldsV1UntilTd1AsNgspice) {
  SourceFunction f({Shape::exponential, {0, 1, 1e-3, 10e-6, 0.5e-3, 20e-6}}, 0, run, "v1");
  EXPECT_EQ(f.value(0.75e-3), 0);
  EXPECT_EQ(f.value(1e-3), 0);  // the left limit at the jump
  EXPECT_NEAR(f.value(1.00028e-3), -9.72388367e-01, 1e-8);
  EXPECT_NEAR(f.value(1.00328e-3), -7.20363020e-01, 1e-8);
  EXPECT_NEAR(f.value(1.00928e-3), -3.95343607e-01, 1e-8);
  EXPECT_DOUBLE_EQ(f.next_corner(0), 1e-3);
  EXPECT_EQ(f.next_corner(1e-3), infinity);
  EXPECT_TRUE(f.jumps_at(1e-3));  // written as two rows where no step ends there
  EXPECT_FALSE(f.jumps_at(0.5e-3));
  EXPECT_FALSE(SourceFunction({Shape::exponential, {0, 1, 1e-6, 2e-6, 5e-6, 1e-6}}, 0, run, "v2").jumps_at(1e-6));
}

TEST(Waveform, PiecewiseLinearInterpolatesAndHoldsEnds) {
  SourceFunction f({Shape::piecewise_linear, {1e-6, 0, 2e-6, 4, 4e-6, 4, 5e-6, -1}}, 0, run, "v1");
  EXPECT_DOUBLE_EQ(f.value(0), 0);
  EXPECT_DOUBLE_EQ(f.value(1.5e-6), 2);
  EXPECT_DOUBLE_EQ(f.value(3e-6), 4);
  EXPECT_DOUBLE_EQ(f.value(4.5e-6), 1.5);
  EXPECT_DOUBLE_EQ(f.value(9e-6), -1);
  EXPECT_DOUBLE_EQ(f.next_corner(2e-6), 4e-6);
  EXPECT_EQ(f.next_corner(5e-6), infinity);
}

TEST(Waveform, PiecewiseLinearRepeatsFromRAsNgspice) {
  // PWL(0 0 1u 1 2u 0 3u 0.5) r=1u td=0.25u: ngspice 38 (maxstep 50 ns) writes the first pass,
  // then jumps from 0.5 back to the value at r (1) at 3.25 us and repeats the 2 us from r on.
  Waveform w{Shape::piecewise_linear, {0.25e-6, 0, 1.25e-6, 1, 2.25e-6, 0, 3.25e-6, 0.5}, 1.25e-6};
  SourceFunction f(w, 0, run, "v1");
  auto closed_form = [](double t) {
    auto first_pass = [](double s) {
      if (s <= 0.25e-6) return 0.0;
      if (s <= 1.25e-6) return (s - 0.25e-6) / 1e-6;
      if (s <= 2.25e-6) return 1 - (s - 1.25e-6) / 1e-6;
      return 0.5 * std::min(1.0, (s - 2.25e-6) / 1e-6);
    };
    if (t <= 3.25e-6) return first_pass(t);
    return first_pass(1.25e-6 + std::fmod(t - 3.25e-6, 2e-6));
  };
  EXPECT_DOUBLE_EQ(f.value(3.25e-6), 0.5);  // the left limit at the jump
  EXPECT_TRUE(f.jumps_at(3.25e-6));
  for (double kink : {0.25e-6, 1.25e-6, 2.25e-6, 4.25e-6}) EXPECT_FALSE(f.jumps_at(kink)) << "t = " << kink;
  EXPECT_NEAR(f.value(3.5e-6), 0.75, 1e-12);
  EXPECT_NEAR(f.value(5.75e-6), 0.5, 1e-12);  // the second repetition, 0.5 us after r
  EXPECT_DOUBLE_EQ(f.next_corner(3e-6), 3.25e-6);
  EXPECT_NEAR(f.next_corner(3.25e-6), 4.25e-6, 1e-20);
  EXPECT_NEAR(f.next_corner(4.25e-6), 5.25e-6, 1e-20);
  EXPECT_NEAR(f.next_corner(5.25e-6), 6.25e-6, 1e-20);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> time(0, 100e-6);
  for (int k = 0; k < 2000; ++k) {
    const double t = time(random);
    EXPECT_NEAR(f.value(t), closed_form(t), 1e-8) << "t = " << t;
  }
}

TEST(Waveform, RepeatedPiecewiseLinearJumpsJustAfterTheCornersItReports) {
  // A square wave of vertical edges, PWL(0 0 1u 0 1u 1 2u 1 2u 0 3u 0) r=0: at every corner
  // next_corner() reports, over a thousand repetitions, the value is the left limit and one ulp
  // later the right one, so that a step ending on the corner sees no part of the jump.
  SourceFunction f({Shape::piecewise_linear, {0, 0, 1e-6, 0, 1e-6, 1, 2e-6, 1, 2e-6, 0, 3e-6, 0}, 0.0}, 0, run, "v1");
  double t = 0;
  int edges = 0;
  while ((t = f.next_corner(t)) < 3e-3) {
    const double phase = std::fmod(t, 3e-6) / 1e-6;  // near 0 (holds 0), 1 (rises) or 2 (falls)
    const double before = f.value(t), after = f.value(std::nextafter(t, 1.0));
    EXPECT_EQ(f.jumps_at(t), std::abs(phase - 1) < 1e-6 || std::abs(phase - 2) < 1e-6) << "t = " << t;
    if (std::abs(phase - 1) < 1e-6) {
      EXPECT_EQ(before, 0) << "t = " << t;
      EXPECT_EQ(after, 1) << "t = " << t;
      ++edges;
    } else if (std::abs(phase - 2) < 1e-6) {
      EXPECT_EQ(before, 1) << "t = " << t;
      EXPECT_EQ(after, 0) << "t = " << t;
      ++edges;
    } else {
      EXPECT_EQ(before, 0) << "t = " << t;
      EXPECT_EQ(after, 0) << "t = " << t;
    }
  }
  EXPECT_EQ(edges, 2000);
}

TEST(Waveform, RejectsMalformedParameters) {
  EXPECT_THROW(SourceFunction({Shape::piecewise_linear, {0, 1, 2}}, 0, run, "v1"), ModelError);
  EXPECT_THROW(SourceFunction({Shape::piecewise_linear, {2, 1, 1, 0}}, 0, run, "v1"), ModelError);
  EXPECT_THROW(SourceFunction({Shape::pulse, {0}}, 0, run, "v1"), ModelError);
}

}  // namespace
}  // namespace mna
