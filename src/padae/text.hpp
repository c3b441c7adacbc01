// Numbers in padae's messages (padae depends on no formatting library).
#pragma once

#include <sstream>
#include <string>

namespace padae {

// value to `digits` significant digits: 17 writes the double itself (a time to land on again),
// 2 a figure to read.
inline std::string format_number(double value, int digits) {
  std::ostringstream text;
  text.precision(digits);
  text << value;
  return text.str();
}

}  // namespace padae
