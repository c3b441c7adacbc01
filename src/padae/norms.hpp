// The largest weighted entry |v_i| w_i, with its index; NaN counts as infinite (a diverging
// iterate is never taken as small). Shared by the integrator and re-initialization.
#pragma once

#include "padae/system.hpp"

namespace padae {

double weighted_max_norm(const Vector& v, const Vector& inverse_weight, int* worst = nullptr);

}  // namespace padae
