// A model and its run settings in words: what `emdae check` shows, and the
// settings table of the report.
#pragma once

#include "core/model.hpp"
#include "run/run.hpp"
#include "verify/report.hpp"

namespace emdae {

using Settings = std::vector<std::pair<std::string, std::string>>;

/// What a scene builds and how it would run, one (label, value) row per
/// line of `emdae check`: nodes, bodies, dofs, Dirichlet sets, constraints
/// and potentials by kind, contact pairs, loads, statics, scheme, time,
/// output, which momenta are conserved, tolerances.
Settings overview(const Model& model, const RunSettings& settings);

/// The scene, the scheme and the settings that shape the results, as the
/// report shows them (label, value), in reading order.
ReportInfo report_info(const Model& model, const RunSettings& settings);

}  // namespace emdae
