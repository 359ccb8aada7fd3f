// What the study's tables (study.cpp) and its page (study_report.cpp) share.
// Internal to verify/.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "verify/study.hpp"

namespace emdae::study_detail {

inline bool positive(double x) {
  return std::isfinite(x) && x > 0;
}

/// "dt 0.01" or "tol 1e-06": what a run is varied by.
inline std::string axis_label(const StudyRun& r) {
  return r.tol ? fmt::format("tol {:g}", *r.tol) : fmt::format("dt {:g}", r.dt);
}

inline std::string short_sci(double x) {
  return std::isfinite(x) ? fmt::format("{:.3e}", x) : "-";
}

inline std::string short_sci(const std::optional<double>& x) {
  return x ? short_sci(*x) : "-";
}

inline std::string short_order(const std::optional<double>& x) {
  // No "-0.00" for an order that rounds to zero.
  return x ? fmt::format("{:.2f}", std::abs(*x) < 0.005 ? 0.0 : *x) : "-";
}

/// The rows of the tables: the runs, the check (when there is one), the reference.
inline std::vector<const StudyRun*> table_rows(const Study& study) {
  std::vector<const StudyRun*> rows;
  for (const auto& r : study.runs) rows.push_back(&r);
  if (study.check_reference) rows.push_back(&study.reference_check);
  rows.push_back(&study.reference);
  return rows;
}

/// "a, b, c".
inline std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

/// "reference", "reference check" or the scheme.
inline std::string role_label(const StudyRun& r) {
  return r.reference ? "reference" : r.reference_check ? "ref. check" : r.scheme;
}

/// A short text of a measure's value: "1.234e-01" or "(1.000e+00, -2.000e+00)".
inline std::string value_text(const Vec& v) {
  if (v.size() == 0) return "-";
  if (v.size() == 1) return short_sci(v[0]);
  std::string out = "(";
  for (Eigen::Index i = 0; i < v.size(); ++i) out += (i ? ", " : "") + short_sci(v[i]);
  return out + ")";
}

}  // namespace emdae::study_detail
