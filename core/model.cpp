#include "core/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/fe_element.hpp"

namespace emdae {

namespace {

// 20.0 reads "20.0", not "20": a length, not a count.
std::string number(double x) {
  std::string s = fmt::format("{}", x);
  if (std::isfinite(x) && s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// The length of a rigid link between `between`: `length` when given, which
// must then be the initial distance (the steppers assume Phi(q_0) = 0: a
// length that disagrees would be an unannounced jump at the first step),
// else the initial distance.
double rigid_length(double length, double initial, const std::string& between) {
  if (!(length > 0) && !(initial > 0))
    throw ModelError(
        "length", "missing, and " + between + " start at the same point: give length explicitly");
  if (length > 0 && std::abs(length - initial) > 1e-9 * length)
    throw ModelError("length", "differs from the initial distance " + number(initial) + " of " +
                                   between +
                                   " (the initial positions must satisfy the constraint)");
  return length > 0 ? length : initial;
}

std::vector<int> component_list(Components c) {
  if (c == Components::X) return {0};
  if (c == Components::Y) return {1};
  return {0, 1};
}

}  // namespace

std::string DirichletSet::describe() const {
  const std::string axes =
      components == Components::XY ? "x, y" : (components == Components::X ? "x" : "y");
  if (fixed) return "fixed (" + axes + ")";
  return fmt::format("displacement [{}, {}] ({}) x {}", displacement[0], displacement[1], axes,
                     g.describe());
}

std::string ModelLoad::describe_magnitude() const {
  if (type == Type::Torque) return fmt::format("torque {}", magnitude[0]);
  return fmt::format("{} [{}, {}]", type == Type::BodyForce ? "acceleration" : "traction",
                     magnitude[0], magnitude[1]);
}

double Body::mass() const {
  double m = 0.0;
  for (double x : node_mass) m += x;
  return m;
}

Model::Model(int dim) : system_(std::make_unique<System>(dim)) {}

// --- particles and their terms ---------------------------------------------------

const Particle& Model::add_particle(const std::string& name, double mass, const Vec& position,
                                    const Vec& velocity, bool fixed) {
  if (name.empty()) throw ModelError("name", "must not be empty");
  if (particle_index_.count(name)) throw ModelError("name", "duplicate particle name");
  if (position.size() != dim())
    throw ModelError("position", fmt::format("must have {} components", dim()));
  if (!(mass > 0)) throw ModelError("mass", "must be positive");
  Particle p{name, -1, fixed, mass, position, velocity.size() ? velocity : Vec::Zero(dim())};
  if (fixed && p.velocity.norm() > 0)
    throw ModelError("velocity",
                     "a fixed particle cannot move (drop the velocity or fixed = true)");
  p.node = system_->add_node(p.position, p.velocity);
  system_->add_mass(p.node, p.node, p.mass);
  if (fixed) system_->fix_node(p.node);
  particle_index_[name] = particles_.size();
  particles_.push_back(std::move(p));
  return particles_.back();
}

const Particle& Model::particle(const std::string& name) const {
  return checked_particle(name, "particle");
}

const Particle& Model::checked_particle(const std::string& name, const std::string& key) const {
  const auto it = particle_index_.find(name);
  if (it == particle_index_.end()) throw ModelError(key, "unknown particle '" + name + "'");
  return particles_[it->second];
}

void Model::add_spring(const std::string& a, const std::string& b, double stiffness,
                       double rest_length, SpringLaw law) {
  const Particle& p = checked_particle(a, "between");
  const Particle& q = checked_particle(b, "between");
  if (p.node == q.node) throw ModelError("between", "a spring needs two different particles");
  if (!(stiffness > 0)) throw ModelError("stiffness", "must be positive");
  const double initial = (p.position - q.position).norm();
  if (!(rest_length > 0) && !(initial > 0))
    throw ModelError("rest_length", "missing, and '" + a + "' and '" + b +
                                        "' start at the same point: give rest_length explicitly");
  system_->add_potential(make_spring(*system_, p.node, q.node, stiffness,
                                     rest_length > 0 ? rest_length : initial, law));
}

void Model::add_link(const std::string& a, const std::string& b, double length) {
  const Particle& p = checked_particle(a, "between");
  const Particle& q = checked_particle(b, "between");
  if (p.node == q.node) throw ModelError("between", "a link needs two different particles");
  const std::string between = "'" + a + "' and '" + b + "'";
  if (p.fixed && q.fixed)
    throw ModelError("between", "a link between two fixed particles constrains nothing");
  // A second link on the same pair is redundant: the constraint Jacobian
  // would be rank deficient and every Newton solve singular.
  const auto pair = std::minmax(p.node, q.node);
  if (links_.count(pair)) throw ModelError("between", "a second rigid link between " + between);
  const double l = rigid_length(length, (p.position - q.position).norm(), between);
  links_[pair] = true;
  system_->add_constraint(make_link(*system_, p.node, q.node, l));
}

const Particle& Model::anchorable(const std::string& particle) const {
  const Particle& p = checked_particle(particle, "particle");
  if (p.fixed) throw ModelError("particle", "an anchor on a fixed particle constrains nothing");
  if (anchored_.count(p.node))
    throw ModelError("particle", "'" + particle +
                                     "' is anchored already (a second rigid link would be "
                                     "redundant)");
  return p;
}

void Model::add_anchor(const std::string& particle, const Vec& point, double length) {
  const Particle& p = anchorable(particle);
  const double l =
      rigid_length(length, (p.position - point).norm(), "'" + particle + "' and its anchor point");
  anchored_.insert(p.node);
  system_->add_constraint(make_anchor_link(*system_, p.node, point, l));
}

void Model::add_moving_anchor(const std::string& particle, const AnchorPath& path, double length) {
  const Particle& p = anchorable(particle);
  const double l = rigid_length(length, (p.position - path.position(0.0)).norm(),
                                "'" + particle + "' and its anchor point at t = 0");
  anchored_.insert(p.node);
  system_->add_constraint(make_moving_anchor_link(*system_, p.node, path, l));
}

void Model::add_anchors(const std::string& nodes, const Vec& point) {
  const System& s = *system_;
  const std::vector<int> list = this->nodes(nodes);
  // Checked whole before anything is added.
  for (int node : list) {
    const std::string what = "node " + std::to_string(node) + " of " + nodes;
    if (anchored_.count(node))
      throw ModelError("nodes", what +
                                    " is anchored already (a second rigid link would be "
                                    "redundant)");
    for (int c = 0; c < dim(); ++c)
      if (s.is_prescribed()[static_cast<std::size_t>(s.dof(node, c))])
        throw ModelError(
            "nodes",
            what +
                " is prescribed by a Dirichlet set ([[dirichlet]]): an anchor would be redundant");
    if (!((s.initial_positions().segment(s.dof(node, 0), dim()) - point).norm() > 0))
      throw ModelError("point", what + " lies on the anchor point: no distance to keep");
  }
  for (int node : list) {
    const Vec x = s.initial_positions().segment(s.dof(node, 0), dim());
    anchored_.insert(node);
    system_->add_constraint(make_anchor_link(*system_, node, point, (x - point).norm()));
  }
}

void Model::add_gravity(const Vec& g) {
  if (g.size() != dim())
    throw ModelError("acceleration", fmt::format("must have {} components", dim()));
  // Zero gravity adds nothing, so that it does not break the symmetries.
  if (g.norm() == 0) return;
  for (const auto& p : particles_)
    if (!p.fixed) system_->add_potential(make_dead_load(*system_, p.node, p.mass * g));
  // Body nodes get their consistent share m_A g, as a potential (a dead load
  // is conservative); nodes prescribed in every direction get none.
  const auto& prescribed = system_->is_prescribed();
  for (const auto& b : bodies_)
    for (int a = 0; a < b.mesh.n_nodes(); ++a) {
      const int node = b.node(a);
      if (prescribed[static_cast<std::size_t>(system_->dof(node, 0))] &&
          prescribed[static_cast<std::size_t>(system_->dof(node, 1))])
        continue;
      system_->add_potential(
          make_dead_load(*system_, node, b.node_mass[static_cast<std::size_t>(a)] * g));
    }
}

// --- FE bodies and their sets ---------------------------------------------------

const Body& Model::add_body(const std::string& name, Mesh mesh, const Material& material,
                            const BodyOptions& options) {
  // The name is the first half of "body.set" references.
  if (name.empty() || name.find('.') != std::string::npos)
    throw ModelError("name", "must be non-empty and without '.'");
  for (const auto& other : bodies_)
    if (other.name == name) throw ModelError("name", "duplicate body name");
  Body b{name, std::move(mesh), material, {}, {}};
  BodyOptions named = options;
  named.name = name;
  try {
    b.info = emdae::add_body(*system_, b.mesh, material, named);
  } catch (const std::invalid_argument& e) {
    throw ModelError("", e.what());
  }
  // The consistent nodal masses int rho N_A dV: a body force b puts m_A b on
  // node A (the consistent load vector), gravity likewise.
  b.node_mass.assign(static_cast<std::size_t>(b.mesh.n_nodes()), 0.0);
  for (int e = 0; e < b.mesh.n_elements(); ++e) {
    const Eigen::Matrix4d me = q1_mass_matrix(b.mesh.quad_nodes(e), material.density);
    const auto& quad = b.mesh.quads[static_cast<std::size_t>(e)];
    for (int a = 0; a < 4; ++a) b.node_mass[static_cast<std::size_t>(quad[a])] += me.row(a).sum();
  }
  bodies_.push_back(std::move(b));
  return bodies_.back();
}

const Body& Model::body(const std::string& name) const {
  for (const auto& b : bodies_)
    if (b.name == name) return b;
  std::vector<std::string> names;
  for (const auto& b : bodies_) names.push_back(b.name);
  throw ModelError("body", "unknown body '" + name + "' (bodies: " + join(names) + ")");
}

std::pair<const Body*, std::string> Model::find_set(const std::string& set, SetKind kind,
                                                    const std::string& key) const {
  const char* kind_name = kind == SetKind::Nodes ? "node set" : "edge set";
  const auto dot = set.find('.');
  if (dot == std::string::npos)
    throw ModelError(key, std::string(kind == SetKind::Nodes ? "must name a " : "must name an ") +
                              kind_name + " as \"body.set\"");
  const std::string body = set.substr(0, dot), name = set.substr(dot + 1);
  const auto it =
      std::find_if(bodies_.begin(), bodies_.end(), [&](const Body& b) { return b.name == body; });
  if (it == bodies_.end()) throw ModelError(key, "unknown body '" + body + "'");
  const bool found =
      kind == SetKind::Nodes ? it->mesh.node_sets.count(name) : it->mesh.edge_sets.count(name);
  if (!found) throw ModelError(key, "body '" + body + "' has no " + kind_name + " '" + name + "'");
  return {&*it, name};
}

std::vector<int> Model::nodes(const std::string& set) const {
  const auto [body, name] = find_set(set, SetKind::Nodes);
  std::vector<int> out;
  for (int a : body->mesh.node_sets.at(name)) out.push_back(body->node(a));
  return out;
}

std::vector<std::array<int, 2>> Model::edges(const std::string& set) const {
  const auto [body, name] = find_set(set, SetKind::Edges, "on");
  std::vector<std::array<int, 2>> out;
  for (const auto& e : body->mesh.edge_sets.at(name))
    out.push_back({body->node(e[0]), body->node(e[1])});
  return out;
}

// --- contact ------------------------------------------------------------------------

const ContactPair& Model::add_contact(ContactPair pair,
                                      std::unique_ptr<UnilateralConstraints> set) {
  for (const auto& other : contacts_)
    if (other.name == pair.name) throw ModelError("name", "duplicate contact name");
  pair.set = static_cast<int>(system_->unilateral().size());
  pair.candidates = set->size();
  system_->add_unilateral(std::move(set));
  contacts_.push_back(std::move(pair));
  return contacts_.back();
}

ModifiedMass Model::modify_mass(const std::string& surface, bool apply) {
  const auto [body, set] = find_set(surface, SetKind::Edges, "surface");
  std::vector<int> nodes = this->nodes(surface), others;
  std::sort(nodes.begin(), nodes.end());
  for (int a = 0; a < body->mesh.n_nodes(); ++a)
    if (!std::binary_search(nodes.begin(), nodes.end(), body->node(a)))
      others.push_back(body->node(a));
  ModifiedMass out;
  try {
    out = emdae::modify_mass(*system_, nodes, others, apply);
  } catch (const std::invalid_argument& e) {
    throw ModelError("surface", e.what());
  }
  if (!apply) return out;
  // The body's node masses are now the system's (lumped, moved).
  Body& b = const_cast<Body&>(*body);
  const Vec& m = system_->lumped_mass();
  for (int a = 0; a < b.mesh.n_nodes(); ++a)
    b.node_mass[static_cast<std::size_t>(a)] = m[system_->dof(b.node(a), 0)];
  return out;
}

// --- Dirichlet sets -----------------------------------------------------------------

void Model::fix(const std::string& nodes, Components components) {
  prescribe(nodes, components, true, Vec(), TimeFunction::constant(1.0));
}

void Model::prescribe_displacement(const std::string& nodes, const Vec& u, const TimeFunction& g,
                                   Components components) {
  if (u.size() != 2) throw ModelError("displacement", "must have 2 components");
  prescribe(nodes, components, false, u, g);
}

void Model::prescribe(const std::string& nodes, Components components, bool fixed, const Vec& u,
                      const TimeFunction& g) {
  const std::vector<int> list = this->nodes(nodes);
  DirichletSet d{nodes, components, fixed, u, g, 0, 0};
  // Checked whole before anything is prescribed. Two fixings of a shared
  // corner agree; anything else contradicts.
  for (int node : list)
    for (int c : component_list(components)) {
      const auto it = prescribed_by_.find(system_->dof(node, c));
      if (it != prescribed_by_.end() && !(dirichlet_[it->second].fixed && fixed))
        throw ModelError("nodes", "node " + std::to_string(node) + " of " + nodes +
                                      " is already prescribed by the Dirichlet set on " +
                                      dirichlet_[it->second].nodes);
    }
  const Vec& x0 = system_->initial_positions();
  for (int node : list) {
    ++d.n_nodes;
    for (int c : component_list(components)) {
      const int dof = system_->dof(node, c);
      if (prescribed_by_.count(dof)) continue;  // fixed twice: once is enough
      prescribed_by_[dof] = dirichlet_.size();
      ++d.n_dofs;
      if (fixed) {
        system_->prescribe({dof, {}, {}});
      } else {
        const double start = x0[dof], amount = u[c];
        system_->prescribe({dof, [g, start, amount](double t) { return start + amount * g(t); },
                            [g, amount](double t) { return amount * g.slope(t); }});
      }
    }
  }
  dirichlet_.push_back(std::move(d));
}

// --- loads ------------------------------------------------------------------------------

void Model::add_torque(const std::string& name, const std::string& on, double torque,
                       const TimeFunction& g) {
  find_set(on, SetKind::Nodes, "on");
  std::vector<int> list = nodes(on);
  if (list.size() < 2) throw ModelError("on", "a torque needs a set of at least two nodes");
  // make_torque takes T(t) itself: the factor scaled by the magnitude.
  system_->add_load(make_torque(std::move(list), g.scaled(torque), name));
  loads_.push_back({name, ModelLoad::Type::Torque, on, Vec::Constant(1, torque), g});
}

void Model::add_body_force(const std::string& name, const std::string& body_name,
                           const Vec& acceleration, const TimeFunction& g) {
  const Body& b = body(body_name);
  if (acceleration.size() != 2) throw ModelError("acceleration", "must have 2 components");
  std::vector<int> dofs;
  Vec forces(2 * b.mesh.n_nodes());
  for (int a = 0; a < b.mesh.n_nodes(); ++a)
    for (int c = 0; c < 2; ++c) {
      dofs.push_back(system_->dof(b.node(a), c));
      forces[2 * a + c] = b.node_mass[static_cast<std::size_t>(a)] * acceleration[c];
    }
  system_->add_load(make_nodal_load(std::move(dofs), std::move(forces), g, name));
  loads_.push_back({name, ModelLoad::Type::BodyForce, body_name, acceleration, g});
}

void Model::add_traction(const std::string& name, const std::string& on, const Vec& traction,
                         const TimeFunction& g) {
  const auto [body, set] = find_set(on, SetKind::Edges, "on");
  if (traction.size() != 2) throw ModelError("traction", "must have 2 components");
  // Constant traction on a straight edge: half of t L on each end node.
  std::map<int, Eigen::Vector2d> nodal;
  for (const auto& e : body->mesh.edge_sets.at(set)) {
    const double length = (body->mesh.nodes[static_cast<std::size_t>(e[1])] -
                           body->mesh.nodes[static_cast<std::size_t>(e[0])])
                              .norm();
    for (int a : e) {
      auto [it, inserted] = nodal.emplace(body->node(a), Eigen::Vector2d::Zero());
      it->second += 0.5 * length * Eigen::Vector2d(traction[0], traction[1]);
    }
  }
  std::vector<int> dofs;
  Vec forces(2 * static_cast<Eigen::Index>(nodal.size()));
  Eigen::Index i = 0;
  for (const auto& [node, force] : nodal)
    for (int c = 0; c < 2; ++c) {
      dofs.push_back(system_->dof(node, c));
      forces[i++] = force[c];
    }
  system_->add_load(make_nodal_load(std::move(dofs), std::move(forces), g, name));
  loads_.push_back({name, ModelLoad::Type::Traction, on, traction, g});
}

bool Model::loads_vanish(double a, double b) const {
  return std::all_of(loads_.begin(), loads_.end(),
                     [&](const ModelLoad& l) { return l.g.vanishes_on(a, b); });
}

void Model::validate() const {
  if (particles_.empty() && bodies_.empty())
    throw ModelError("bodies",
                     "missing: the scene has no [[bodies]] and no [[particles]], "
                     "nothing to integrate");
  if (bodies_.empty() &&
      std::none_of(particles_.begin(), particles_.end(), [](const auto& p) { return !p.fixed; }))
    throw ModelError("particles", "every particle is fixed: nothing to integrate");
  if (static_cast<int>(system_->prescribed().size()) == system_->n_dofs())
    throw ModelError("dirichlet", "every node is prescribed: nothing to integrate");
  try {
    system_->validate();
  } catch (const std::invalid_argument& e) {
    throw ModelError("", e.what());
  }
}

}  // namespace emdae
