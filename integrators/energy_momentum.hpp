// Energy-momentum mG(1) scheme of Betsch & Steinmann, paper eq. (47): the
// discrete gradient of every term (eqs. (34)-(35)) makes total energy, linear
// and angular momentum exact invariants of the discrete flow for any step
// size, with the constraints satisfied at every t_n.
#pragma once

#include "integrators/midpoint_family.hpp"

namespace emdae {

class EnergyMomentumStepper final : public MidpointFamilyStepper {
 public:
  EnergyMomentumStepper(const System& system, NewtonSettings newton,
                        MidpointFamilySettings scheme = {})
      : MidpointFamilyStepper(system, GradientKind::Discrete, newton, scheme) {}
  std::string name() const override { return "em"; }
};

}  // namespace emdae
