#pragma once
/// \file Six joint angles written in degrees, as the arm tests state their postures.

#include "ifab/arm/arm_model.h"
#include "ifab/core/angles.h"

namespace ifab::arm {

inline Vector6d Deg(double a, double b, double c, double d, double e, double f) {
  return (Vector6d() << a, b, c, d, e, f).finished() * kDeg;
}

}  // namespace ifab::arm
