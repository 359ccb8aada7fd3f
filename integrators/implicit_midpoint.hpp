// Implicit midpoint rule with constraints at the end of the step: the forces
// are the gradients at q_mid. Symplectic and momentum conserving, but energy
// is not conserved for non-quadratic potentials, and for stiff nonlinear
// elasticity at large steps it may lose energy stability altogether: that is
// what the comparison with the energy-momentum scheme is for.
#pragma once

#include "integrators/midpoint_family.hpp"

namespace emdae {

class ImplicitMidpointStepper final : public MidpointFamilyStepper {
 public:
  ImplicitMidpointStepper(const System& system, NewtonSettings newton,
                          MidpointFamilySettings scheme = {})
      : MidpointFamilyStepper(system, GradientKind::Midpoint, newton, scheme) {}
  std::string name() const override { return "midpoint"; }
};

}  // namespace emdae
