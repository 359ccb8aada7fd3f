// The schemes by name, and the settings of every one of them.
//
// A scene carries the settings of every scheme it may be run with (its
// [scheme], [scheme.ida] and [scheme.galpha] tables), so that one scene can
// be compared across schemes; make_stepper picks those of the scheme named.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/generalized_alpha.hpp"
#include "integrators/ida_stepper.hpp"
#include "integrators/newton.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

/// Names accepted by make_stepper, in the order shown to users.
std::vector<std::string> known_schemes();

/// The settings of every scheme: the Newton solve (em, midpoint, galpha),
/// the impact treatment (shared; its gap tolerance also ida's), IDA's error
/// tolerances and BDF order, generalized-alpha's parameters.
struct SchemeSettings {
  SchemeSettings() = default;
  /// Defaults but for the Newton solve (implicit: make_stepper(name, system, newton)).
  SchemeSettings(const NewtonSettings& newton_settings) : newton(newton_settings) {}

  NewtonSettings newton;
  ContactSettings contact;
  IdaSettings ida;  // its gap_tolerance is contact's
  GeneralizedAlphaSettings galpha = GeneralizedAlphaSettings::chung_hulbert(1.0);
};

/// Builds the stepper called `name` for `system` with its settings out of
/// `settings`; throws std::invalid_argument naming the known schemes when
/// `name` is not one of them.
std::unique_ptr<Stepper> make_stepper(const std::string& name, const System& system,
                                      const SchemeSettings& settings = {});

}  // namespace emdae
