#include "padae/norms.hpp"

#include <cmath>
#include <limits>

namespace padae {

double weighted_max_norm(const Vector& v, const Vector& inverse_weight, int* worst) {
  double largest = 0;
  int where = -1;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    double scaled = std::abs(v[i]) * inverse_weight[i];
    if (scaled > largest || std::isnan(scaled)) {
      largest = std::isnan(scaled) ? std::numeric_limits<double>::infinity() : scaled;
      where = static_cast<int>(i);
    }
  }
  if (worst) *worst = where;
  return largest;
}

}  // namespace padae
