// Mathematical constants, defined once for every part.
#pragma once

namespace weathergs {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace weathergs
