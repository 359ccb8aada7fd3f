// [[particles]], [[springs]], [[links]], [[anchors]] and [gravity]: calls on
// the Model (core/model.hpp), which makes the terms and checks them.
#include <algorithm>
#include <optional>

#include "scene/scene_reader.hpp"

namespace emdae::scene_reader {

void Builder::parse_particle(const Fields& f) {
  f.only({"name", "mass", "position", "velocity", "fixed"});
  const int dim = model().dim();
  const std::string name = f.string("name", "a unique name for the particle");
  if (const auto it = particle_where_.find(name); it != particle_where_.end())
    f.fail_key("name", "duplicate particle name, received \"" + name + "\" (first defined at " +
                           it->second + ")");
  const bool fixed = f.boolean("fixed", false);
  // A fixed particle's mass never enters the motion: it may be left out.
  const double mass =
      fixed && !f.has("mass") ? 1.0 : f.positive("mass", "the particle's mass, a positive number");
  const Vec position =
      f.vector("position", dim, fmt::format("the initial position, {} numbers", dim));
  const Vec velocity = f.optional_vector("velocity", dim).value_or(Vec::Zero(dim));
  model_call(f, [&] { model().add_particle(name, mass, position, velocity, fixed); });
  particle_where_[name] = f.where();
}

const Particle& Builder::particle(const Fields& f, std::string_view k, const toml::node& n) const {
  if (!n.is_string()) f.fail_at(n, k, "must name a particle (a string), received " + show_typed(n));
  const std::string& name = n.as_string()->get();
  if (!particle_where_.count(name)) {
    std::vector<std::string> names;
    for (const auto& p : model().particles()) names.push_back(p.name);
    f.fail_at(n, k, "unknown particle, received " + show(n) + hint(name, names, "particles"));
  }
  return model().particle(name);
}

namespace {

// The two entries of `between = ["a", "b"]`.
const toml::array& between(const Fields& f) {
  const auto& n = f.require("between", "the names of two particles, [\"a\", \"b\"]");
  const auto* a = n.as_array();
  if (!a || a->size() != 2)
    f.fail_at(n, "between", "must be a list of two particle names, received " + show_typed(n));
  return *a;
}

}  // namespace

void Builder::parse_spring(const Fields& f) {
  f.only({"between", "stiffness", "rest_length", "law"});
  const toml::array& ends = between(f);
  const Particle& p = particle(f, "between", *ends.get(0));
  const Particle& q = particle(f, "between", *ends.get(1));
  const std::string a = p.name, b = q.name;
  const double k = f.positive("stiffness", "the spring stiffness, a positive number");
  SpringLaw law = SpringLaw::Linear;
  if (const auto name = f.optional_string("law")) {
    if (*name == "green") {
      law = SpringLaw::Green;
    } else if (*name != "linear") {
      f.fail_key("law", "unknown spring law, received " + show(*f.find("law")) +
                            hint(*name, {"linear", "green"}, "laws"));
    }
  }
  const double rest = optional_length(f, "rest_length");
  if (p.fixed && q.fixed) warn(f.where(), "spring between two fixed particles has no effect");
  model_call(f, [&] { model().add_spring(a, b, k, rest, law); });
}

void Builder::parse_link(const Fields& f) {
  f.only({"between", "length"});
  const toml::array& ends = between(f);
  const Particle& p = particle(f, "between", *ends.get(0));
  const Particle& q = particle(f, "between", *ends.get(1));
  const std::string a = p.name, b = q.name;
  model_call(f, [&] { model().add_link(a, b, optional_length(f, "length")); });
  // Velocities that stretch a rigid link are projected away by the first
  // step; allowed, but almost certainly not what the scene meant.
  const Vec d = p.position - q.position, dv = p.velocity - q.velocity;
  if (std::abs(d.dot(dv)) > 1e-9 * d.norm() * (p.velocity.norm() + q.velocity.norm()))
    warn(f.where(),
         "initial velocities of '" + a + "' and '" + b + "' change the length of their rigid link");
}

// An anchor is a rigid link to a fixed point: of one particle, or of every
// node of a body's node set (each at its own initial distance: radial
// rollers about the point, which keep every constraint invariant under
// rotations about it; the bearing on rollers, examples/bearing_rollers.toml).
void Builder::parse_anchor(const Fields& f) {
  f.only({"particle", "nodes", "point", "length", "path"});
  const int dim = model().dim();
  if (f.has("particle") == f.has("nodes"))
    f.fail_key(f.has("nodes") ? "nodes" : "particle",
               "give either particle (one particle) or nodes (a body's node set), not " +
                   std::string(f.has("nodes") ? "both" : "neither"));
  const Vec point = f.vector("point", dim, fmt::format("the anchor point, {} numbers", dim));
  // Initial velocities that change an anchor's length are projected away.
  const auto check_velocity = [&](const Vec& x, const Vec& v, const std::string& what) {
    const Vec d = x - point;
    if (std::abs(d.dot(v)) > 1e-9 * d.norm() * v.norm())
      warn(f.where(), "initial velocity of " + what + " changes the length of its anchor link");
  };
  if (f.has("nodes")) {
    if (f.has("path"))
      f.fail_key("path",
                 "a moving anchor point is for a particle, not a node set ([[dirichlet]] "
                 "prescribes a node set's motion)");
    if (f.has("length"))
      f.fail_key("length",
                 "each node of a set keeps its initial distance; length is for a particle");
    const std::string set = set_ref(f, "nodes", Model::SetKind::Nodes, "");
    model_call(f, [&] { model().add_anchors(set, point); });
    const System& s = model().system();
    for (int node : model().nodes(set))
      check_velocity(s.initial_positions().segment(s.dof(node, 0), dim),
                     s.initial_velocities().segment(s.dof(node, 0), dim),
                     "node " + std::to_string(node) + " of " + set);
    return;
  }
  const Particle& p =
      particle(f, "particle", f.require("particle", "the name of the anchored particle"));
  if (f.has("path")) {
    // A driven support: the point moves by the displacement table u(t),
    // p(t) = point + u(t); the initial velocity must match the support's.
    const Fields t =
        f.table("path", "{times = [...], x = [...], y = [...], interpolation = \"cubic\"}",
                "an anchor path");
    const std::vector<std::string> axes = {"x", "y", "z"};
    std::vector<std::string> keys = {"times", "interpolation"};
    for (int d = 0; d < dim; ++d) keys.push_back(axes[static_cast<std::size_t>(d)]);
    t.only(keys);
    const std::vector<double> times = t.numbers("times", "increasing times, a list of numbers");
    for (std::size_t i = 1; i < times.size(); ++i)
      if (!(times[i] > times[i - 1]))
        t.fail_key("times", "must increase strictly, received " + show(*t.find("times")));
    std::vector<std::vector<double>> values;
    for (int d = 0; d < dim; ++d) {
      const std::string& k = axes[static_cast<std::size_t>(d)];
      values.push_back(t.has(k) ? t.numbers(k, "displacements at those times")
                                : std::vector<double>(times.size(), 0.0));
      if (values.back().size() != times.size())
        t.fail_key(k, fmt::format("must have as many entries as times ({}), received {}",
                                  times.size(), show(*t.find(k))));
    }
    auto interpolation = AnchorPath::Interpolation::Cubic;
    const std::vector<std::string> kinds = {"linear", "cubic", "periodic"};
    if (const auto kind = t.optional_string("interpolation")) {
      const auto it = std::find(kinds.begin(), kinds.end(), *kind);
      if (it == kinds.end())
        t.fail_key("interpolation", "unknown interpolation, received " +
                                        show(*t.find("interpolation")) +
                                        hint(*kind, kinds, "interpolations"));
      interpolation = static_cast<AnchorPath::Interpolation>(it - kinds.begin());
    }
    const std::size_t min_points = interpolation == AnchorPath::Interpolation::Linear ? 2 : 3;
    if (times.size() < min_points)
      t.fail_key("times", fmt::format("needs at least {} times for {} interpolation, received {}",
                                      min_points, kinds[static_cast<std::size_t>(interpolation)],
                                      show(*t.find("times"))));
    if (interpolation == AnchorPath::Interpolation::Periodic)
      for (int d = 0; d < dim; ++d)
        if (values[static_cast<std::size_t>(d)].front() !=
            values[static_cast<std::size_t>(d)].back())
          t.fail_key(axes[static_cast<std::size_t>(d)],
                     "a periodic path needs equal first and last values, received " +
                         show(*t.find(axes[static_cast<std::size_t>(d)])));
    std::optional<AnchorPath> path;
    model_call(f, [&] { path.emplace(point, times, values, interpolation); });
    model_call(f, [&] { model().add_moving_anchor(p.name, *path, optional_length(f, "length")); });
    const Vec d = p.position - path->position(0.0), dv = p.velocity - path->velocity(0.0);
    if (std::abs(d.dot(dv)) > 1e-9 * d.norm() * (dv.norm() + path->velocity(0.0).norm()))
      warn(f.where(),
           "initial velocity of '" + p.name + "' changes its distance to the moving anchor point");
    return;
  }
  model_call(f, [&] { model().add_anchor(p.name, point, optional_length(f, "length")); });
  check_velocity(p.position, p.velocity, "'" + p.name + "'");
}

void Builder::parse_gravity(const Fields& f) {
  f.only({"acceleration"});
  const int dim = model().dim();
  const Vec g = f.vector("acceleration", dim, fmt::format("the gravity vector, {} numbers", dim));
  model_call(f, [&] { model().add_gravity(g); });
}

}  // namespace emdae::scene_reader
