// Subnormal numbers flushed to zero while padae computes.
//
// Magnitudes below 2.2e-308 mean nothing at any tolerance an integrator works to, yet on x86
// every operation that reads or produces one takes a microcode assist about a hundred times
// slower than normal arithmetic. They are common, not exotic: a step diffusing down a long RC
// line leaves the nodes beyond its front at exp(-k^2)-small voltages, and the residuals, LU
// solves and norms over those nodes then run at the assist's speed (a 1.1e4-unknown ladder
// spent 60 % of its time so).
#pragma once

#if defined(__SSE2__) || defined(_M_X64)
#include <pmmintrin.h>
#include <xmmintrin.h>
#define PADAE_FLUSHES_SUBNORMALS 1
#else
#define PADAE_FLUSHES_SUBNORMALS 0
#endif

namespace padae {

// While alive: subnormal results are flushed to zero and subnormal operands read as zero (x86
// FTZ and DAZ). The caller's mode is restored on exit. Elsewhere it does nothing.
class SubnormalsFlushed {
 public:
  static constexpr bool supported = PADAE_FLUSHES_SUBNORMALS;

#if PADAE_FLUSHES_SUBNORMALS
  SubnormalsFlushed() : caller_mode_(_mm_getcsr()) {
    _mm_setcsr(caller_mode_ | _MM_FLUSH_ZERO_ON | _MM_DENORMALS_ZERO_ON);
  }
  ~SubnormalsFlushed() { _mm_setcsr(caller_mode_); }
#else
  SubnormalsFlushed() = default;
#endif
  SubnormalsFlushed(const SubnormalsFlushed&) = delete;
  SubnormalsFlushed& operator=(const SubnormalsFlushed&) = delete;

 private:
#if PADAE_FLUSHES_SUBNORMALS
  unsigned caller_mode_;
#endif
};

}  // namespace padae
