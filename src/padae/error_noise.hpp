// Whether the errors of a step's rejected attempts came from the step. A truncation error falls
// as h^(order + 1); one that does not fall with the step is noise no step removes: round-off
// (a tolerance below what double precision resolves) or a jump of the model inside the step.
// When the error test gives up, this tells the user whether it was the step's truncation error
// or such noise.
#pragma once

#include <span>
#include <string>

namespace padae {

// A step attempt the error test rejected: its order, size and the error it measured (in
// tolerances).
struct RejectedAttempt {
  int order;
  double h, error;
};

// Of two attempts of one order, the smaller step's error is predicted from the larger's; where
// one stays more than a hundred times above its prediction, the sentence that says so with the
// figures of the pair that stays furthest above. Empty when every error fell as truncation does.
std::string unfalling_error(std::span<const RejectedAttempt> attempts);

}  // namespace padae
