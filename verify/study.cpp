#include "verify/study.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <istream>
#include <limits>
#include <ostream>

#include "verify/binary_io.hpp"
#include "verify/csv_field.hpp"
#include "verify/page.hpp"
#include "verify/study_detail.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;
using namespace report_detail;

using namespace study_detail;

Json number_or_null(double x) {
  return std::isfinite(x) ? Json(x) : Json(nullptr);
}

Json number_or_null(const std::optional<double>& x) {
  return x ? number_or_null(*x) : Json(nullptr);
}

Json vec_json(const Vec& v) {
  Json out = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(number_or_null(v[i]));
  return out;
}

// A CSV cell: empty for a missing number.
std::string cell(double x, const char* format = "{:.6e}") {
  return std::isfinite(x) ? fmt::format(fmt::runtime(format), x) : std::string();
}

std::string cell(const std::optional<double>& x, const char* format = "{:.6e}") {
  return x ? cell(*x, format) : std::string();
}

std::string csv_row(const Study& study, const StudyRun& r) {
  std::string out = fmt::format(
      "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
      r.reference         ? "reference"
      : r.reference_check ? "reference_check"
                          : "run",
      r.scheme, cell(r.dt, "{}"), cell(r.tol, "{}"), r.ran ? std::to_string(r.steps) : "",
      r.ran ? std::to_string(r.iterations) : "", r.ran ? cell(r.cpu_seconds, "{:.6f}") : "",
      cell(r.error), cell(r.error_rel), cell(r.order, "{:.4f}"), cell(r.energy_rel_error_max),
      cell(r.linear_momentum_error_max), cell(r.angular_momentum_rel_error_max),
      cell(r.constraint_residual_max), csv_field(r.status));
  for (std::size_t k = 0; k < study.measures.size(); ++k)
    out += "," + (k < r.measure_errors.size() ? cell(r.measure_errors[k]) : std::string());
  return out + "\n";
}

// A row `order` of a scheme: the fitted orders of the error and of every measure.
std::string csv_order_row(const Study& study, std::size_t scheme,
                          const std::vector<Study::MeasureSummary>& summaries) {
  std::vector<double> h, e;
  for (const auto& r : study.runs)
    if (r.scheme == study.schemes[scheme] && r.ok()) {
      h.push_back(r.axis());
      e.push_back(r.error);
    }
  std::string out = fmt::format("order,{},,,,,,,,{},,,,,", study.schemes[scheme],
                                cell(fitted_order(h, e, 1e-10 * study.size), "{:.4f}"));
  for (const auto& m : summaries) out += "," + cell(m.orders[scheme], "{:.4f}");
  return out + "\n";
}

Json run_json(const Study& study, const StudyRun& r) {
  Json j;
  j["scheme"] = r.scheme;
  j["dt"] = r.dt;
  j["tol"] = number_or_null(r.tol);
  j["status"] = r.status;
  j["steps"] = r.steps;
  j["iterations"] = r.iterations;
  j["cpu_seconds"] = r.cpu_seconds;
  j["error"] = number_or_null(r.error);
  j["error_rel"] = number_or_null(r.error_rel);
  j["order"] = number_or_null(r.order);
  j["energy_rel_error_max"] = number_or_null(r.energy_rel_error_max);
  j["linear_momentum_error_max"] = number_or_null(r.linear_momentum_error_max);
  j["angular_momentum_rel_error_max"] = number_or_null(r.angular_momentum_rel_error_max);
  j["constraint_residual_max"] = number_or_null(r.constraint_residual_max);
  if (study.contact) {
    const RunMeasures& m = r.measured;
    j["contact_window"] = m.complete && m.contact_first
                              ? Json::array({*m.contact_first, number_or_null(m.contact_last)})
                              : Json(nullptr);
    j["active_contacts_at_end"] = m.complete ? Json(m.active_at_end) : Json(nullptr);
  }
  // Each measure's error, and its value (but the positions: a node vector).
  Json errors = Json::object(), values = Json::object();
  for (std::size_t k = 0; k < study.measures.size(); ++k) {
    const MeasureSpec& spec = study.measures[k];
    errors[spec.id] =
        number_or_null(k < r.measure_errors.size() ? r.measure_errors[k] : std::nan(""));
    if (spec.kind != MeasureKind::Positions)
      values[spec.id] = vec_json(measure_value(spec, r.measured));
  }
  j["measures"] = errors;
  j["values"] = values;
  return j;
}

}  // namespace

void StudyRun::take(const Summary& s) {
  ran = true;
  status = s.status;
  steps = s.steps;
  iterations = s.newton_iterations;
  cpu_seconds = s.cpu_seconds;
  energy_rel_error_max = s.energy_rel_error_max;
  linear_momentum_error_max = s.linear_momentum_error_max;
  angular_momentum_rel_error_max = s.angular_momentum_rel_error_max;
  constraint_residual_max = s.constraint_residual_max;
}

namespace {

void put_optional(std::ostream& out, const std::optional<double>& x) {
  binary::put<char>(out, x ? 1 : 0);
  binary::put(out, x ? *x : 0.0);
}

std::optional<double> get_optional(std::istream& in) {
  const bool has = binary::get<char>(in) != 0;
  const double x = binary::get<double>(in);
  return has ? std::optional<double>(x) : std::nullopt;
}

void put_vecs(std::ostream& out, const std::vector<Vec>& v) {
  binary::put<std::uint64_t>(out, v.size());
  for (const Vec& x : v) binary::put_vec(out, x);
}

std::vector<Vec> get_vecs(std::istream& in) {
  std::vector<Vec> v(binary::get<std::uint64_t>(in));
  for (Vec& x : v) x = binary::get_vec(in);
  return v;
}

void put_doubles(std::ostream& out, const std::vector<double>& v) {
  binary::put<std::uint64_t>(out, v.size());
  for (double x : v) binary::put(out, x);
}

std::vector<double> get_doubles(std::istream& in) {
  std::vector<double> v(binary::get<std::uint64_t>(in));
  for (double& x : v) x = binary::get<double>(in);
  return v;
}

}  // namespace

void save_run(std::ostream& out, const StudyRun& r) {
  using namespace binary;
  put_string(out, r.scheme);
  put(out, r.dt);
  put_optional(out, r.tol);
  for (bool b : {r.reference, r.reference_check, r.ran}) put<char>(out, b ? 1 : 0);
  put_string(out, r.status);
  put(out, r.steps);
  put(out, r.iterations);
  put(out, r.cpu_seconds);
  put(out, r.energy_rel_error_max);
  put_optional(out, r.linear_momentum_error_max);
  put_optional(out, r.angular_momentum_rel_error_max);
  put(out, r.constraint_residual_max);
  put_vec(out, r.q_end);
  const RunMeasures& m = r.measured;
  put<char>(out, m.complete ? 1 : 0);
  put_doubles(out, m.times);
  put_vecs(out, m.positions);
  put_optional(out, m.contact_first);
  put_optional(out, m.contact_last);
  put(out, m.active_at_end);
  put<std::uint64_t>(out, m.groups.size());
  for (const RigidMotion& g : m.groups) {
    put(out, g.mass);
    put_vecs(out, {g.centre, g.linear_momentum, g.angular_momentum});
    for (double x : {g.kinetic, g.rigid_kinetic, g.momentum_scale, g.angular_scale}) put(out, x);
  }
  put(out, m.kinetic);
  put(out, m.potential);
  put(out, r.error);
  put(out, r.error_rel);
  put_optional(out, r.order);
  put_doubles(out, r.measure_errors);
}

StudyRun load_run(std::istream& in) {
  using namespace binary;
  StudyRun r;
  r.scheme = get_string(in);
  r.dt = get<double>(in);
  r.tol = get_optional(in);
  for (bool* b : {&r.reference, &r.reference_check, &r.ran}) *b = get<char>(in) != 0;
  r.status = get_string(in);
  r.steps = get<long>(in);
  r.iterations = get<long>(in);
  r.cpu_seconds = get<double>(in);
  r.energy_rel_error_max = get<double>(in);
  r.linear_momentum_error_max = get_optional(in);
  r.angular_momentum_rel_error_max = get_optional(in);
  r.constraint_residual_max = get<double>(in);
  r.q_end = get_vec(in);
  RunMeasures& m = r.measured;
  m.complete = get<char>(in) != 0;
  m.times = get_doubles(in);
  m.positions = get_vecs(in);
  m.contact_first = get_optional(in);
  m.contact_last = get_optional(in);
  m.active_at_end = get<int>(in);
  m.groups.resize(get<std::uint64_t>(in));
  for (RigidMotion& g : m.groups) {
    g.mass = get<double>(in);
    const std::vector<Vec> v = get_vecs(in);
    if (v.size() != 3) throw std::runtime_error("a study run's bytes are damaged");
    g.centre = v[0];
    g.linear_momentum = v[1];
    g.angular_momentum = v[2];
    for (double* x : {&g.kinetic, &g.rigid_kinetic, &g.momentum_scale, &g.angular_scale})
      *x = get<double>(in);
  }
  m.kinetic = get<double>(in);
  m.potential = get<double>(in);
  r.error = get<double>(in);
  r.error_rel = get<double>(in);
  r.order = get_optional(in);
  r.measure_errors = get_doubles(in);
  return r;
}

std::vector<std::string> Study::notes() const {
  std::vector<std::string> out;
  out.push_back(fmt::format(
      "error: max over the nodes of |q - q_ref| at t_end = {:g}; the reference is this scene "
      "with scheme em at dt = {:g}, the same discretization in space, so the error is that of "
      "the time discretization only",
      t_end, reference.dt));
  out.push_back(
      size > 0 ? fmt::format("relative error: the error / {:.6g}, the diagonal of the bounding "
                             "box of the initial positions",
                             size)
               : std::string("relative error: none (the initial positions span no box)"));
  if (const auto e = reference_error_estimate()) {
    if (check_reference)
      out.push_back(fmt::format(
          "the reference's own error at t_end, estimated as its distance from the check (em at "
          "dt = {:g}), is at most about {:.1e}: errors near it are not resolved (a smaller "
          "--reference-dt resolves them)",
          reference_check.dt, *e));
    else
      out.push_back(fmt::format(
          "the reference's own error, estimated from em's finest run as if em were of order 2, "
          "is about {:.1e}: errors near it are not resolved (a smaller --reference-dt resolves "
          "them)",
          *e));
  }
  if (reference.ran && !reference.ok())
    out.push_back("the reference run did not finish (" + reference.status +
                  "): no errors and no orders");
  if (check_reference && reference_check.ran && !reference_check.ok())
    out.push_back("the reference check did not finish (" + reference_check.status +
                  "): the reference is not checked");
  if (contact)
    out.push_back(
        "the scene has contact: through impacts the observed orders are not expected to be 2 "
        "(the solution is not smooth there)");
  if (std::find(schemes.begin(), schemes.end(), "ida") != schemes.end())
    out.push_back(
        "ida: rtol = atol = tol, output every scene dt; its order is the slope of the error "
        "against tol (1: proportional to it)");
  if (!reference.ok()) return out;
  // The measures.
  if (!measures.empty())
    out.push_back(
        "measures: each run's error against the reference; the order of a measure is the "
        "least-squares slope of log error against log dt (ida: log tol) over the scheme's runs");
  const auto asked = [&](const char* family) {
    return std::find(families.begin(), families.end(), family) != families.end();
  };
  const RunMeasures& ref = reference.measured;
  if (contact && asked("window") && !ref.contact_first)
    out.push_back("window: the reference run has no contact, so there is no contact window");
  else if (contact && asked("window") && ref.active_at_end > 0)
    out.push_back(
        "window: the reference is still in contact at t_end; only the start of the window is "
        "compared");
  if (contact && ref.contact_first && ref.active_at_end > 0 &&
      (asked("momenta") || asked("energy")))
    out.push_back(
        "the bodies are still in contact at t_end in the reference: their momenta and energies "
        "are not those after separation (a larger --t-end measures them after it)");
  if (asked("energy"))
    out.push_back(
        "energy split at t_end: the rigid motion of each group is |P|^2/2m + J_c^2/2I_c from "
        "its mass matrix (P its momentum, J_c its angular momentum and I_c its inertia about its "
        "centre of mass); vibration = T - the groups' rigid energies + V_int, V_int the potential "
        "terms invariant under rigid motions (strain energy, springs; not gravity)");
  std::string round_off, unresolved;
  const auto summaries = measure_summaries();
  for (std::size_t k = 0; k < measures.size(); ++k) {
    if (summaries[k].round_off) round_off += (round_off.empty() ? "" : ", ") + measures[k].id;
    if (!summaries[k].resolved)
      unresolved += (unresolved.empty() ? "" : ", ") + measures[k].id + " (" +
                    join(summaries[k].unresolved_schemes) + ")";
  }
  if (!round_off.empty())
    out.push_back("at round-off in every run (conserved, or zero): " + round_off +
                  "; no order for them");
  if (check_reference && reference_check.ok() && !measures.empty())
    out.push_back(
        unresolved.empty()
            ? fmt::format("reference check (em at dt = {:g}): every measure's reference error is "
                          "below a fifth of the smallest error of the runs",
                          reference_check.dt)
            : fmt::format("reference check (em at dt = {:g}): NOT RESOLVED by the reference (its "
                          "error, the check's difference from it, is above a fifth of the "
                          "smallest error of the scheme's runs): {}",
                          reference_check.dt, unresolved));
  return out;
}

std::optional<double> Study::reference_error_estimate() const {
  if (!reference.ok()) return std::nullopt;
  if (check_reference) {
    if (!reference_check.ok() || !std::isfinite(reference_check.error)) return std::nullopt;
    return reference_check.error;
  }
  // With impacts em is not of order 2: no estimate.
  if (contact) return std::nullopt;
  const StudyRun* finest = nullptr;
  for (const auto& r : runs)
    if (r.scheme == "em" && r.ok() && positive(r.error) && (!finest || r.dt < finest->dt))
      finest = &r;
  if (!finest || !(finest->dt > reference.dt)) return std::nullopt;
  // e(h) = C (h^2 - h_ref^2) measured against the reference; its own error is C h_ref^2.
  const double h2 = finest->dt * finest->dt, r2 = reference.dt * reference.dt;
  return finest->error * r2 / (h2 - r2);
}

std::vector<Study::MeasureSummary> Study::measure_summaries() const {
  std::vector<MeasureSummary> out(measures.size());
  for (std::size_t k = 0; k < measures.size(); ++k) {
    MeasureSummary& m = out[k];
    m.floor = 1e-10 * measures[k].scale;
    const auto error_of = [k](const StudyRun& r) {
      return r.ok() && k < r.measure_errors.size() ? r.measure_errors[k] : std::nan("");
    };
    bool any = false;
    for (const auto& r : runs) {
      const double e = error_of(r);
      if (!std::isfinite(e)) continue;
      any = true;
      if (e > m.floor && !(e >= m.smallest_error)) m.smallest_error = e;
    }
    m.round_off = any && !std::isfinite(m.smallest_error);
    if (check_reference) m.reference_error = error_of(reference_check);
    m.resolved = m.round_off || !std::isfinite(m.reference_error) ||
                 !std::isfinite(m.smallest_error) || m.reference_error <= 0.2 * m.smallest_error;
    for (const auto& scheme : schemes) {
      std::vector<double> h, e;
      double smallest = std::numeric_limits<double>::infinity();
      for (const auto& r : runs)
        if (r.scheme == scheme) {
          h.push_back(r.axis());
          e.push_back(error_of(r));
          if (e.back() > m.floor) smallest = std::min(smallest, e.back());
        }
      m.orders.push_back(fitted_order(h, e, m.floor));
      if (!m.resolved && std::isfinite(smallest) && m.reference_error > 0.2 * smallest)
        m.unresolved_schemes.push_back(scheme);
    }
  }
  return out;
}

double max_node_distance(const Vec& a, const Vec& b, int dimension) {
  double d = 0.0;
  const Eigen::Index dim = dimension;
  for (Eigen::Index n = 0; n + dim <= std::min(a.size(), b.size()); n += dim)
    d = std::max(d, (a.segment(n, dim) - b.segment(n, dim)).norm());
  return d;
}

double bounding_box_diagonal(const Vec& q, int dimension) {
  const Eigen::Index dim = dimension;
  if (q.size() < dim) return 0.0;
  Vec lo = q.head(dim), hi = q.head(dim);
  for (Eigen::Index n = dim; n + dim <= q.size(); n += dim) {
    lo = lo.cwiseMin(q.segment(n, dim));
    hi = hi.cwiseMax(q.segment(n, dim));
  }
  return (hi - lo).norm();
}

std::optional<double> observed_order(double e1, double e2, double h1, double h2) {
  if (!positive(e1) || !positive(e2) || !positive(h1) || !positive(h2) || h1 == h2)
    return std::nullopt;
  return std::log(e1 / e2) / std::log(h1 / h2);
}

void evaluate_study(Study& study) {
  const Vec& q_ref = study.reference.q_end;
  const bool have_reference = study.reference.ok() && q_ref.size() > 0;
  const auto measure = [&](StudyRun& r) {
    r.error = r.error_rel = std::numeric_limits<double>::quiet_NaN();
    r.measure_errors.assign(study.measures.size(), std::numeric_limits<double>::quiet_NaN());
    if (!have_reference || !r.ok()) return;
    if (r.q_end.size() == q_ref.size()) {
      r.error = max_node_distance(r.q_end, q_ref, study.dimension);
      if (study.size > 0) r.error_rel = r.error / study.size;
    }
    for (std::size_t k = 0; k < study.measures.size(); ++k) {
      const MeasureSpec& spec = study.measures[k];
      r.measure_errors[k] = measure_error(spec, measure_value(spec, r.measured),
                                          measure_value(spec, study.reference.measured));
    }
  };
  if (study.check_reference) measure(study.reference_check);
  const StudyRun* previous = nullptr;
  for (auto& r : study.runs) {
    measure(r);
    r.order.reset();
    if (previous && previous->scheme == r.scheme && previous->ok() && r.ok())
      r.order = observed_order(previous->error, r.error, previous->axis(), r.axis());
    previous = &r;
  }
}

std::string study_csv(const Study& study) {
  std::string out =
      "role,scheme,dt,tol,steps,iterations,cpu_seconds,error,error_rel,order,"
      "energy_rel_error_max,linear_momentum_error_max,angular_momentum_rel_error_max,"
      "constraint_residual_max,status";
  for (const auto& m : study.measures) out += "," + csv_field(m.id);
  out += "\n";
  for (const auto& r : study.runs) out += csv_row(study, r);
  const auto summaries = study.measure_summaries();
  for (std::size_t s = 0; s < study.schemes.size(); ++s) out += csv_order_row(study, s, summaries);
  if (study.check_reference) out += csv_row(study, study.reference_check);
  out += csv_row(study, study.reference);
  return out;
}

Json to_json(const Study& study) {
  Json j;
  j["scene"] = study.scene;
  j["source"] = study.source;
  j["t_end"] = study.t_end;
  j["dimension"] = study.dimension;
  j["scene_size"] = study.size;
  j["contact"] = study.contact;
  j["complete"] = study.complete;
  j["schemes"] = study.schemes;
  j["dts"] = study.dts;
  j["tols"] = study.tols;
  j["reference_error_estimate"] = number_or_null(study.reference_error_estimate());
  j["notes"] = study.notes();
  j["reference"] = run_json(study, study.reference);
  j["reference_check"] =
      study.check_reference ? run_json(study, study.reference_check) : Json(nullptr);
  Json runs = Json::array();
  for (const auto& r : study.runs) runs.push_back(run_json(study, r));
  j["runs"] = runs;
  // Per scheme, the observed orders between successive steps (tolerances).
  Json orders = Json::object();
  for (const auto& scheme : study.schemes) {
    Json list = Json::array();
    bool first = true;
    for (const auto& r : study.runs) {
      if (r.scheme != scheme) continue;
      if (!first) list.push_back(number_or_null(r.order));
      first = false;
    }
    orders[scheme] = list;
  }
  j["orders"] = orders;
  // The measures: what they are, the reference's value and own error, the
  // fitted order per scheme.
  Json groups = Json::array();
  for (const auto& g : study.groups) groups.push_back(g.name);
  j["groups"] = groups;
  Json times = Json::array();
  for (const auto& t : study.times) times.push_back({{"time", t.time}, {"role", t.role}});
  j["times"] = times;
  const auto summaries = study.measure_summaries();
  Json measures = Json::array();
  for (std::size_t k = 0; k < study.measures.size(); ++k) {
    const MeasureSpec& spec = study.measures[k];
    const Study::MeasureSummary& m = summaries[k];
    Json e;
    e["id"] = spec.id;
    e["family"] = spec.family;
    e["label"] = spec.label;
    e["time"] = spec.time;
    e["scale"] = spec.scale;
    e["reference_value"] = spec.kind == MeasureKind::Positions
                               ? Json(nullptr)
                               : vec_json(measure_value(spec, study.reference.measured));
    e["reference_error"] = number_or_null(m.reference_error);
    e["smallest_error"] = number_or_null(m.smallest_error);
    e["round_off"] = m.round_off;
    e["resolved"] = m.resolved;
    e["unresolved_schemes"] = m.unresolved_schemes;
    Json o = Json::object();
    for (std::size_t s = 0; s < study.schemes.size(); ++s)
      o[study.schemes[s]] = number_or_null(m.orders[s]);
    e["orders"] = o;
    measures.push_back(e);
  }
  j["measures"] = measures;
  return j;
}

void print_study_table(std::ostream& out, const Study& study) {
  const auto line = [&out](const std::string& scheme, const std::string& axis,
                           const std::string& steps, const std::string& iterations,
                           const std::string& cpu, const std::string& error, const std::string& rel,
                           const std::string& order, const std::string& energy,
                           const std::string& lin, const std::string& ang,
                           const std::string& status) {
    fmt::print(out, "  {:<11}{:<16}{:>8}{:>11}{:>10}{:>12}{:>12}{:>7}{:>12}{:>12}{:>12}  {}\n",
               scheme, axis, steps, iterations, cpu, error, rel, order, energy, lin, ang, status);
  };
  line("scheme", "dt / tol", "steps", "iter.", "CPU s", "error", "rel. error", "order",
       "energy err", "lin. mom.", "ang. mom.", "status");
  for (const StudyRun* r : table_rows(study)) {
    const std::string scheme = role_label(*r);
    const bool ref = r->reference || r->reference_check;
    const std::string axis = ref ? fmt::format("em dt {:g}", r->dt) : axis_label(*r);
    if (!r->ran) {
      line(scheme, axis, "-", "-", "-", "-", "-", "-", "-", "-", "-", r->status);
      continue;
    }
    line(scheme, axis, std::to_string(r->steps), std::to_string(r->iterations),
         fmt::format("{:.3f}", r->cpu_seconds), r->reference ? "-" : short_sci(r->error),
         r->reference ? "-" : short_sci(r->error_rel), short_order(r->order),
         short_sci(r->energy_rel_error_max), short_sci(r->linear_momentum_error_max),
         short_sci(r->angular_momentum_rel_error_max), r->status);
  }
  if (!study.measures.empty()) {
    // The measures: the reference's error (the check's), each scheme's order.
    const auto summaries = study.measure_summaries();
    std::size_t width = 8;
    for (const auto& m : study.measures) width = std::max(width, m.label.size() + 2);
    fmt::print(out, "\n  {:<{}}{:>12}", "measure", width, "ref. error");
    for (const auto& s : study.schemes) fmt::print(out, "  {:>16}", s + " order");
    fmt::print(out, "\n");
    for (std::size_t k = 0; k < study.measures.size(); ++k) {
      const auto& m = summaries[k];
      fmt::print(out, "  {:<{}}{:>12}", study.measures[k].label, width,
                 short_sci(m.reference_error));
      for (const auto& o : m.orders)
        fmt::print(out, "  {:>16}", m.round_off ? std::string("round-off") : short_order(o));
      fmt::print(out, "{}\n",
                 m.resolved
                     ? std::string()
                     : "  (not resolved by the reference: " + join(m.unresolved_schemes) + ")");
    }
  }
  for (const auto& note : study.notes()) fmt::print(out, "  note: {}\n", note);
}

void write_study_tables(const std::string& dir, const Study& study) {
  write_atomically((fs::path(dir) / "study.csv").string(), study_csv(study), "study table");
  write_atomically((fs::path(dir) / "study.json").string(), to_json(study).dump(2) + "\n",
                   "study summary");
}

}  // namespace emdae
