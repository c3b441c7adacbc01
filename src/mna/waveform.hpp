// Independent-source time functions with ngspice's semantics and defaults: PULSE, SIN, EXP,
// SFFM, PWL. Each also lists its corners, the instants where it is not smooth, which the integrator
// must hit exactly.
#pragma once

#include <optional>
#include <vector>

#include "mna/circuit_spec.hpp"

namespace mna {

class SourceFunction {
 public:
  // Fills omitted parameters with ngspice's defaults (TSTEP, TSTOP from the run); throws
  // ModelError for too many parameters or a PWL whose times decrease.
  SourceFunction(const Waveform& waveform, double dc_value, const RunSettings& run,
                 const std::string& element);

  double value(double t) const;
  // First corner strictly after t, or +infinity.
  double next_corner(double t) const;
  // The longest step that still resolves the function: a twentieth of a sine's period, or of an
  // SFFM's shortest (+infinity for the others, whose corners are time events and which are linear or
  // monotone in between).
  double resolution_step() const;
  // Whether the function jumps at t (a PWL's two points at one time, a PULSE cut short by PW or
  // PER, an EXP at TD1 when TD2 < TD1): value(t) is the left limit there, and the right limit
  // differs.
  bool jumps_at(double t) const;

 private:
  struct PulseCorners {
    double rise_start, rise_end, fall_start, fall_end, next_period;
  };
  PulseCorners pulse_corners(double t, bool left) const;
  PulseCorners compute_pulse_corners(double t, bool left) const;
  // PWL r=: repetition j's start, the repetition that contains t (its end belongs to it, where
  // the value is the left limit), and a time point's time in repetition j.
  double repetition_start(double j) const;
  double repetition_index(double t) const;
  double repetition_time(std::size_t point, double j) const;
  double pwl_value(double t) const;
  double pwl_next_corner(double t) const;

  Waveform::Shape shape_;
  std::vector<double> p_;  // parameters with defaults filled in
  double dc_;
  std::optional<double> repeat_from_;
  double repeat_period_ = 0;  // last PWL time - repeat_from_
  std::size_t repeat_first_point_ = 0;  // a repetition starts at the last point at time r
  // The period pulse_corners() found last: every load asks for the same one (the integrator,
  // its output and its event location all evaluate inside one step), and finding it costs a
  // division and a floor. Not thread-safe, as the model that owns it is not.
  mutable std::optional<PulseCorners> last_period_;
};

}  // namespace mna
