#include "integrators/stepper.hpp"

#include <stdexcept>

#include "core/gradient.hpp"
#include "integrators/energy_momentum.hpp"
#include "integrators/generalized_alpha.hpp"
#include "integrators/ida_stepper.hpp"
#include "integrators/implicit_midpoint.hpp"
#include "integrators/schemes.hpp"

namespace emdae {

void activate_candidate(State& s, int id) {
  s.active.push_back(id);
  s.lambda.conservativeResize(s.lambda.size() + 1);
  s.lambda[s.lambda.size() - 1] = 0.0;
}

void deactivate_candidate(State& s, int n_static, std::size_t k) {
  const Eigen::Index pos = n_static + static_cast<Eigen::Index>(k);
  Vec lam(s.lambda.size() - 1);
  lam.head(pos) = s.lambda.head(pos);
  lam.tail(lam.size() - pos) = s.lambda.tail(s.lambda.size() - pos - 1);
  s.lambda = lam;
  s.active.erase(s.active.begin() + static_cast<std::ptrdiff_t>(k));
}

double driven_constraint_power(const System& system, const Vec& q, const Vec& lambda, double t) {
  double power = 0.0;
  Vec ql;
  for (int l = 0; l < system.n_constraints() && l < lambda.size(); ++l) {
    const Term& c = *system.constraints()[static_cast<std::size_t>(l)];
    if (!c.depends_on_time()) continue;
    gather(c, q, ql);
    power += lambda[l] * c.value_t(ql, t);
  }
  return power;
}

State initial_state(const System& system) {
  State s;
  s.q = system.initial_positions();
  s.v = system.initial_velocities();
  for (const auto& p : system.prescribed()) {
    if (p.position) s.q[p.dof] = p.position(0.0);
    s.v[p.dof] = p.velocity ? p.velocity(0.0) : 0.0;
  }
  s.lambda = Vec::Zero(system.n_constraints());
  return s;
}

std::vector<std::string> known_schemes() {
  return {"em", "midpoint", "ida", "galpha"};
}

std::unique_ptr<Stepper> make_stepper(const std::string& name, const System& system,
                                      const SchemeSettings& settings) {
  MidpointFamilySettings midpoint;
  static_cast<ContactSettings&>(midpoint) = settings.contact;
  if (name == "em")
    return std::make_unique<EnergyMomentumStepper>(system, settings.newton, midpoint);
  if (name == "midpoint")
    return std::make_unique<ImplicitMidpointStepper>(system, settings.newton, midpoint);
  if (name == "ida") {
    IdaSettings ida = settings.ida;
    ida.gap_tolerance = settings.contact.gap_tolerance;
    ida.linear_solver = settings.newton.linear_solver;
    ida.umfpack_flops = settings.newton.umfpack_flops;
    return std::make_unique<IdaStepper>(system, ida);
  }
  if (name == "galpha") {
    GeneralizedAlphaSettings galpha = settings.galpha;
    galpha.gap_tolerance = settings.contact.gap_tolerance;
    return std::make_unique<GeneralizedAlphaStepper>(system, galpha, settings.newton);
  }
  std::string known;
  for (const auto& k : known_schemes()) known += (known.empty() ? "" : ", ") + k;
  throw std::invalid_argument("unknown scheme '" + name + "' (known: " + known + ")");
}

}  // namespace emdae
