// What a run was asked to do, in words: the settings table of its report.
#pragma once

#include "core/model.hpp"
#include "run/run.hpp"
#include "verify/report.hpp"

namespace emdae {

/// The scene, the scheme and the settings that shape the results, as the
/// report shows them (label, value), in reading order.
ReportInfo report_info(const Model& model, const RunSettings& settings);

}  // namespace emdae
