// The sections that set up the run rather than the model: [scene], [time],
// [scheme] (with [scheme.ida] and [scheme.galpha]), [statics], [output],
// [tolerances]. They fill RunSettings (run/run.hpp) under the same names.
#include <algorithm>
#include <cctype>
#include <cmath>

#include "integrators/contact_step.hpp"
#include "scene/scene_reader.hpp"

namespace emdae::scene_reader {

void Builder::parse_scene(const Fields& f) {
  f.only({"name", "description", "dimension"});
  if (const auto name = f.optional_string("name")) {
    // The name becomes a folder (out/<name>-<scheme>): keep it a plain word.
    const bool plain = !name->empty() && std::all_of(name->begin(), name->end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    }) && (*name)[0] != '.';
    if (!plain)
      f.fail_key("name", "must be a plain name (letters, digits, '_', '-', '.'), received " +
                             show(*f.find("name")));
    settings().name = *name;
  }
  settings().description = f.optional_string("description").value_or("");
  const long dim = f.integer("dimension", 2);
  if (dim != 2 && dim != 3)
    f.fail_key("dimension", "must be 2 or 3, received " + show(*f.find("dimension")));
  scene_.model = std::make_unique<Model>(static_cast<int>(dim));
}

void Builder::parse_limits(const Fields& f) {
  f.only({"max_steps", "max_memory_mb"});
  Scene::Estimate& e = scene_.estimate;
  e.max_steps = f.integer_in("max_steps", 10'000'000, 1, 1'000'000'000'000);
  e.max_memory_bytes =
      static_cast<double>(f.integer_in("max_memory_mb", 4096, 1, 1'000'000'000)) * (1 << 20);
}

namespace {

// "t_end / dt = 1e+09 steps": a count in a message.
std::string count_text(double n) {
  return n < 1e7 ? fmt::format("{:.0f}", n) : fmt::format("{:.3g}", n);
}

}  // namespace

void Builder::parse_time(const Fields& f) {
  f.only({"dt", "t_end", "min_dt"});
  TimeSettings& t = settings().time;
  t.dt = f.positive("dt", "the time step, a positive number");
  t.t_end = f.positive("t_end", "the end time, a positive number");
  if (t.t_end < t.dt)
    f.fail_key("t_end", "must be at least dt = " + show_number(t.dt) + ", received " +
                            show(*f.find("t_end")));
  if (const auto min_dt = f.optional_positive("min_dt")) {
    if (*min_dt > t.dt)
      f.fail_key("min_dt", "must not exceed dt = " + show_number(t.dt) + ", received " +
                               show(*f.find("min_dt")));
    t.min_dt = *min_dt;
  }
  // The steps a run would take, before it runs (a step of 1e-300 would never end).
  const double steps = std::ceil(t.t_end / t.dt - 1e-9);
  Scene::Estimate& e = scene_.estimate;
  if (!(steps <= static_cast<double>(e.max_steps)))
    f.fail_key("dt", fmt::format("t_end / dt = {} / {} is {} steps, more than limits.max_steps = "
                                 "{} (raise it with --set limits.max_steps=N), received {}",
                                 show_number(t.t_end), show_number(t.dt), count_text(steps),
                                 e.max_steps, show(*f.find("dt"))));
  e.steps = static_cast<long>(steps);
}

namespace {

// [scheme.ida]: IDA's error tolerances and highest BDF order.
void read_ida(const Fields& f, IdaSettings& ida) {
  ida.rtol = f.optional_positive("rtol").value_or(ida.rtol);
  ida.atol = f.optional_positive("atol").value_or(ida.atol);
  if (f.has("max_order")) {
    const long order = f.integer("max_order", ida.max_order);
    if (order < 1 || order > 5)
      f.fail_key("max_order", "must be 1..5 (BDF orders), received " + std::to_string(order));
    ida.max_order = static_cast<int>(order);
  }
}

// [scheme.galpha]: the spectral radius at infinity of Chung & Hulbert.
void read_galpha(const Fields& f, GeneralizedAlphaSettings& galpha) {
  if (const auto rho = f.optional_number("rho_inf")) {
    if (*rho < 0 || *rho > 1)
      f.fail_key("rho_inf", "must be in [0, 1], received " + show(*f.find("rho_inf")));
    galpha = GeneralizedAlphaSettings::chung_hulbert(*rho);
  }
}

}  // namespace

void Builder::parse_scheme(const Fields& f) {
  // The flat rtol, atol, max_order and rho_inf are the keys of the tables
  // [scheme.ida] and [scheme.galpha] as they were first written: still read.
  f.only({"name", "newton_tolerance", "newton_max_iterations", "line_search", "linear_solver",
          "jacobian_reuse", "impact", "locate_impacts", "gap_tolerance", "ida", "galpha", "rtol",
          "atol", "max_order", "rho_inf"});
  if (const auto name = f.optional_string("name")) {
    const auto known = known_schemes();
    if (std::find(known.begin(), known.end(), *name) == known.end()) {
      f.fail_key("name", "unknown scheme, received " + show(*f.find("name")) +
                             hint(*name, known, "known schemes"));
    }
    settings().scheme = *name;
    scheme_name_where_ = f.where(*f.find("name"));
  }
  SchemeSettings& ss = settings().schemes;
  // Each scheme's own table is read whatever the scheme: a scene carries the
  // settings of every scheme it is compared with.
  const auto own_table = [&](const char* scheme, const std::vector<std::string>& keys,
                             const auto& read) {
    for (const auto& k : keys)
      if (f.has(k) && f.has(scheme))
        f.fail_key(k, fmt::format("given twice: here and as scheme.{}.{}, received {}", scheme, k,
                                  show(*f.find(k))));
    if (f.has(scheme)) {
      const Fields t = f.table(scheme, "the settings of scheme " + std::string(scheme),
                               std::string("[scheme.") + scheme + "]");
      t.only(keys);
      read(t);
    }
    read(f);  // the flat keys
    // A flat key does nothing for another scheme: say so, since a --scheme
    // on the command line can make a scene's settings moot.
    for (const auto& k : keys)
      if (f.has(k) && settings().scheme != scheme)
        warn(f.where(*f.find(k)),
             fmt::format("scheme.{} is only used by scheme {}, not {} (as scheme.{}.{} it is "
                         "kept for {} without a warning)",
                         k, scheme, settings().scheme, scheme, k, scheme));
  };
  own_table("ida", {"rtol", "atol", "max_order"}, [&](const Fields& t) { read_ida(t, ss.ida); });
  own_table("galpha", {"rho_inf"}, [&](const Fields& t) { read_galpha(t, ss.galpha); });
  if (const auto impact = f.optional_string("impact")) {
    const auto known = known_impact_treatments();
    if (std::find(known.begin(), known.end(), *impact) == known.end())
      f.fail_key("impact", "unknown impact treatment, received " + show(*f.find("impact")) +
                               hint(*impact, known, "known treatments"));
    ss.contact.impact = parse_impact_treatment(*impact);
  }
  // The older spelling: locate_impacts = true | false is impact = "locate" | "none".
  if (f.has("locate_impacts")) {
    if (f.has("impact"))
      f.fail_key("locate_impacts", "give either scheme.impact or scheme.locate_impacts, not both");
    ss.contact.impact =
        f.boolean("locate_impacts", true) ? ImpactTreatment::Locate : ImpactTreatment::None;
  }
  ss.contact.gap_tolerance =
      f.optional_non_negative("gap_tolerance").value_or(ss.contact.gap_tolerance);
  ss.newton.tolerance = f.optional_positive("newton_tolerance").value_or(1e-10);
  ss.newton.max_iterations = static_cast<int>(f.integer_in("newton_max_iterations", 20, 1, 1000));
  ss.newton.line_search = f.boolean("line_search", false);
  // "auto" (the default) or a count: NewtonSettings::jacobian_reuse.
  const toml::node* reuse = f.find("jacobian_reuse");
  if (!reuse || (reuse->is_string() && *reuse->value<std::string>() == "auto"))
    ss.newton.jacobian_reuse = NewtonSettings::kAutoReuse;
  else if (reuse->is_string())
    f.fail_key("jacobian_reuse",
               "must be \"auto\" or an integer in [1, 100], received " + show(*reuse));
  else
    ss.newton.jacobian_reuse = static_cast<int>(f.integer_in("jacobian_reuse", 1, 1, 100));
  if (const auto solver = f.optional_string("linear_solver")) {
    const auto backend = linear_solver_from_name(*solver);
    if (!backend)
      f.fail_key("linear_solver", "unknown linear solver, received " +
                                      show(*f.find("linear_solver")) +
                                      hint(*solver, linear_solver_names(), "known linear solvers"));
    ss.newton.linear_solver = *backend;
  }
}

void Builder::parse_statics(const Fields& f) {
  f.only({"enabled", "hold_rotation", "pseudo_dt", "tolerance", "max_steps", "newton_tolerance",
          "increments", "load_time"});
  const bool static_only = settings().static_only;
  EquilibriumSettings& st = settings().statics;
  // Writing the section means wanting it; enabled = false switches it off
  // (e.g. --set statics.enabled=false) without deleting it.
  st.enabled = f.boolean("enabled", true);
  if (static_only && !st.enabled)
    f.fail_key("enabled",
               "a scene without [time] is a static analysis: its [statics] cannot be switched "
               "off (add [time] for a dynamic run), received false");
  StaticSettings& s = st.settings;
  const NewtonSettings& newton = settings().schemes.newton;
  s.pseudo_dt = f.optional_positive("pseudo_dt").value_or(s.pseudo_dt);
  s.tolerance = f.optional_positive("tolerance").value_or(s.tolerance);
  s.max_steps = static_cast<int>(f.integer_in("max_steps", s.max_steps, 1, 100000));
  s.newton = newton;
  s.newton.tolerance = f.optional_positive("newton_tolerance").value_or(newton.tolerance);
  s.increments = static_cast<int>(f.integer_in("increments", 1, 1, 100000));
  if (settings().static_only) scene_.estimate.steps = s.increments;
  const double load_time = f.optional_non_negative("load_time").value_or(0.0);
  s.load_time = load_time;
  // Increments at one time would all solve the same problem.
  if (s.increments > 1 && !(load_time > 0))
    f.fail_key("increments",
               fmt::format("more than one increment needs a load_time > 0 over which the "
                           "loads and prescribed motions grow (increment k is solved at "
                           "load_time k / increments), received {}",
                           s.increments));
  // The dynamics start from the equilibrium, at its load time.
  const double t_end = settings().time.t_end;
  if (!static_only && f.has("load_time") && !(load_time < t_end))
    f.fail_key("load_time",
               "must be before time.t_end = " + show_number(t_end) +
                   " (the dynamics start from the equilibrium at load_time), received " +
                   show(*f.find("load_time")));
  if (const auto* n = f.find("hold_rotation")) {
    const auto* a = n->as_array();
    if (!a)
      f.fail_at(*n, "hold_rotation",
                "must be a list of node sets [\"body.set\", ...], received " + show_typed(*n));
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string set = set_ref(f, "hold_rotation", *a->get(i), Model::SetKind::Nodes);
      if (model().nodes(set).size() < 2)
        f.fail_at(*n, "hold_rotation",
                  "holding a rotation needs a set of at least two nodes, received " + show(*n));
      st.hold_rotation.push_back(set);
    }
  }
}

void Builder::parse_output(const Fields& f) {
  f.only({"every", "vtu_every", "vtu_format", "snapshots", "animation_frames", "track"});
  const long every = f.integer("every", 1);
  if (every < 1) f.fail_key("every", "must be at least 1, received " + std::to_string(every));
  settings().output.every = static_cast<int>(std::min<long>(every, 1L << 30));
  const long vtu_every = f.integer("vtu_every", -1);
  if (f.has("vtu_every") && vtu_every < 0)
    f.fail_key("vtu_every",
               "must be 0 (no fields) or at least 1, received " + std::to_string(vtu_every));
  settings().output.vtu_every = vtu_every;
  if (const auto format = f.optional_string("vtu_format")) {
    try {
      settings().output.vtu_format = parse_vtu_format(*format);
    } catch (const std::invalid_argument&) {
      f.fail_key("vtu_format", "must be \"binary\" or \"ascii\", received " +
                                   show(*f.find("vtu_format")) +
                                   hint(*format, {"binary", "ascii"}, "formats"));
    }
  }
  if (f.has("snapshots")) {
    const std::vector<double> times =
        f.numbers("snapshots", "times at which the report draws the bodies");
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (times[i] < 0)
        f.fail_key("snapshots", fmt::format("must not hold negative times, received {}", times[i]));
      if (i > 0 && times[i] <= times[i - 1]) f.fail_key("snapshots", "must be increasing times");
      // A time after the run's end would never be drawn (as the drawings'
      // own test: within round-off of t_end is at t_end).
      const double t_end = settings().time.t_end;
      if (!settings().static_only && times[i] > t_end + 1e-9 * std::max(1.0, std::abs(t_end)))
        f.fail_key("snapshots", fmt::format("must not hold times after time.t_end = {} (the run "
                                            "ends there and draws nothing later), received {}",
                                            show_number(t_end), show_number(times[i])));
    }
    settings().output.snapshots = times;
  }
  settings().output.animation_frames = static_cast<int>(
      f.integer_in("animation_frames", settings().output.animation_frames, 0, 200));
  // Node sets whose nodes' trajectories are written with the particles'.
  if (const auto* n = f.find("track")) {
    const auto* a = n->as_array();
    if (!a)
      f.fail_at(*n, "track",
                "must be a list of node sets [\"body.set\", ...], received " + show_typed(*n));
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string set = set_ref(f, "track", *a->get(i), Model::SetKind::Nodes);
      auto& track = settings().output.track;
      if (std::find(track.begin(), track.end(), set) != track.end())
        f.fail_at(*a->get(i), "track", "names node set '" + set + "' twice");
      track.push_back(set);
    }
  }
}

void Builder::parse_tolerances(const Fields& f) {
  f.only({"energy_rel", "energy_balance_rel", "linear_momentum", "angular_momentum_rel",
          "angular_momentum_balance_rel", "constraint", "gap_violation", "penetration",
          "contact_pressure_spread", "surface_depth", "surface_through", "swept_depth",
          "det_f_min"});
  // A static analysis has no time history whose energy or momenta could drift.
  if (settings().static_only)
    for (const char* k : {"energy_rel", "energy_balance_rel", "linear_momentum",
                          "angular_momentum_rel", "angular_momentum_balance_rel"})
      if (f.has(k))
        f.fail_key(k,
                   "a static analysis (no [time]) has no energy or momentum to check (its "
                   "checks: constraint, gap_violation, penetration, contact_pressure_spread), "
                   "received " +
                       show(*f.find(k)));
  Tolerances& t = settings().tolerances;
  t.energy_rel = f.optional_positive("energy_rel");
  t.energy_balance_rel = f.optional_positive("energy_balance_rel");
  t.linear_momentum = f.optional_positive("linear_momentum");
  t.angular_momentum_rel = f.optional_positive("angular_momentum_rel");
  t.angular_momentum_balance_rel = f.optional_positive("angular_momentum_balance_rel");
  t.constraint = f.optional_positive("constraint");
  t.gap_violation = f.optional_positive("gap_violation");
  t.penetration = f.optional_positive("penetration");
  t.contact_pressure_spread = f.optional_positive("contact_pressure_spread");
  t.surface_depth = f.optional_positive("surface_depth");
  if (t.surface_depth && model().contacts().empty())
    f.fail_key("surface_depth",
               "the scene has no [[contacts]] whose surfaces could be checked, received " +
                   show(*f.find("surface_depth")));
  for (const char* k : {"surface_through", "swept_depth"}) {
    auto& limit = std::string(k) == "swept_depth" ? t.swept_depth : t.surface_through;
    limit = f.optional_positive(k);
    if (limit && model().contacts().empty())
      f.fail_key(k, "the scene has no [[contacts]] whose surfaces could be checked, received " +
                        show(*f.find(k)));
  }
  if (t.swept_depth && settings().static_only)
    f.fail_key("swept_depth",
               "a static analysis (no [time]) has no steps whose paths could be swept, received " +
                   show(*f.find("swept_depth")));
  t.det_f_min = f.optional_number("det_f_min");
  if (t.det_f_min && model().bodies().empty())
    f.fail_key("det_f_min",
               "the scene has no [[bodies]] whose elements could be checked, received " +
                   show(*f.find("det_f_min")));
  if (t.det_f_min && !(*t.det_f_min >= 0.0 && *t.det_f_min < 1.0))
    f.fail_key("det_f_min",
               "must be in [0, 1): det F at an element corner must stay above it, received " +
                   show(*f.find("det_f_min")));
  if (t.contact_pressure_spread && model().contacts().empty())
    f.fail_key("contact_pressure_spread",
               "the scene has no [[contacts]] whose pressure could be checked, received " +
                   show(*f.find("contact_pressure_spread")));
}

}  // namespace emdae::scene_reader
