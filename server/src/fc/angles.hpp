// The flight controller's angle helpers are the project's one implementation (uavsim/common/angles.hpp);
// this header names them in uavsim::server::fc, where the controller modules use them unqualified.
#pragma once

#include "uavsim/common/angles.hpp"

namespace uavsim::server::fc {

using common::kDegToRad;
using common::kPi;
using common::kRadToDeg;
using common::wrap_pi;  // (-pi, pi], O(1), non-finite -> 0

}  // namespace uavsim::server::fc
