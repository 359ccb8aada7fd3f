// The model: what a scene declares, as C++ objects, and the System it makes.
//
// A Model owns its System and knows what the System alone forgets: the
// particles by name; the FE bodies with their meshes, materials and
// consistent nodal masses; their named node and edge sets ("body.set");
// the Dirichlet sets and the loads, each with its time function. Every
// physical quantity a scene implies is computed here, once: a body force
// m_A b and gravity m_A g on the consistent nodal masses, a traction lumped
// on the edge nodes, a prescribed displacement x0 + u g(t) with its rate
// u g'(t).
//
//   Model model(2);
//   const Material steel = make_material(MaterialModel::SaintVenantKirchhoff, 100, 0.1, 1e-3);
//   model.add_body("left", ring_mesh({-10.1, 0}, 8, 10, 32, 2), steel);
//   model.add_body("right", ring_mesh({10.1, 3}, 8, 10, 32, 2), steel);
//   add_mortar_contact(model, "left.outer", "right.outer");   // contact/contact_pair.hpp
//
// examples/ring_impact.cpp builds and runs the paper's ring impact this way.
//
// A call that cannot be carried out throws ModelError and leaves the model
// as it was. Its key() names the argument at fault under the name the scene
// files use for it (docs/scenes.md), so that the scene reader can point at
// the line: "length", "nodes", "between", ...
#pragma once

#include <array>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/load.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/modified_mass.hpp"
#include "core/particles.hpp"
#include "core/system.hpp"

namespace emdae {

/// A call on a Model that cannot be carried out: key() is the argument at
/// fault (the scene key of the same name), what() why.
class ModelError : public std::invalid_argument {
 public:
  ModelError(std::string key, const std::string& what)
      : std::invalid_argument(what), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

/// A named point mass and the node it became.
struct Particle {
  std::string name;
  int node = -1;
  bool fixed = false;
  double mass = 0.0;
  Vec position, velocity;
};

/// A plane-strain Q1 body: its mesh, material and where its nodes went.
struct Body {
  std::string name;
  Mesh mesh;
  Material material;
  BodyInfo info;
  /// Consistent nodal masses m_A = int rho N_A dV per mesh node (row sums of
  /// the consistent mass matrix, whether or not the body's mass is lumped).
  std::vector<double> node_mass;

  double mass() const;
  /// The system node of mesh node a.
  int node(int a) const { return info.node_offset + a; }
};

/// Which components of a node set's dofs a Dirichlet condition holds.
enum class Components { XY, X, Y };

/// A Dirichlet set: fixed, or moved by u g(t) from its initial position.
struct DirichletSet {
  std::string nodes;  // "body.set"
  Components components = Components::XY;
  bool fixed = true;
  Vec displacement;  // u, when not fixed
  TimeFunction g = TimeFunction::constant(1.0);
  int n_nodes = 0, n_dofs = 0;

  /// "fixed (x, y)", "displacement [1, 0] (x) x ramp(0, 1) to 1".
  std::string describe() const;
};

/// A pair of surfaces in contact (contact/contact_pair.hpp makes them).
struct ContactPair {
  std::string name, slave, master;  // "body.set"
  int slave_segments = 0, master_segments = 0;
  int candidates = 0;          // unilateral candidates (slave nodes)
  int set = 0;                 // index in System::unilateral()
  bool modified_mass = false;  // both surfaces massless (Model::modify_mass)
};

/// An external load and the time function that scales it.
struct ModelLoad {
  enum class Type { Torque, BodyForce, Traction };
  std::string name;
  Type type = Type::Torque;
  std::string on;                                // "body.set", or the body for a body force
  Vec magnitude;                                 // torque: one value; otherwise the vector
  TimeFunction g = TimeFunction::constant(1.0);  // the dimensionless factor

  /// "torque 10000", "acceleration [0, -9.81]", "traction [0, -1]".
  std::string describe_magnitude() const;
};

class Model {
 public:
  explicit Model(int dim = 2);
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  int dim() const { return system_->dim(); }
  System& system() { return *system_; }
  const System& system() const { return *system_; }

  // --- particles and their terms -------------------------------------------
  /// A point mass; a fixed one never moves (its mass is then immaterial).
  const Particle& add_particle(const std::string& name, double mass, const Vec& position,
                               const Vec& velocity = Vec(), bool fixed = false);
  const Particle& particle(const std::string& name) const;
  const std::vector<Particle>& particles() const { return particles_; }
  /// A spring between two particles; rest_length <= 0: their initial distance.
  void add_spring(const std::string& a, const std::string& b, double stiffness,
                  double rest_length = 0.0, SpringLaw law = SpringLaw::Linear);
  /// A rigid link; length <= 0: the initial distance, which a given length
  /// must equal (the steppers start from Phi(q_0) = 0).
  void add_link(const std::string& a, const std::string& b, double length = 0.0);
  /// A rigid link of a particle to a fixed point.
  void add_anchor(const std::string& particle, const Vec& point, double length = 0.0);
  /// A rigid link of a particle to a point moving on `path` (a driven
  /// support); length <= 0: the distance to path.position(0).
  void add_moving_anchor(const std::string& particle, const AnchorPath& path, double length = 0.0);
  /// A rigid link of every node of a node set to a fixed point, each at its
  /// initial distance: radial rollers about the point.
  void add_anchors(const std::string& nodes, const Vec& point);
  /// Dead loads m g on every free particle and every body node not held in
  /// all directions (consistent nodal masses); zero gravity adds nothing.
  void add_gravity(const Vec& acceleration);

  /// The modified mass of a surface (core/modified_mass.hpp): the nodes of
  /// edge set `surface` ("body.set") lose their mass to the other nodes of
  /// the body, keeping its total mass and centre of mass, and become
  /// massless. The body's node masses (used by gravity and body forces
  /// added afterwards) follow. Throws ModelError (key "surface") and then
  /// changes nothing; with apply = false it only checks.
  ModifiedMass modify_mass(const std::string& surface, bool apply = true);

  // --- FE bodies and their sets ----------------------------------------------
  const Body& add_body(const std::string& name, Mesh mesh, const Material& material,
                       const BodyOptions& options = {});
  const std::vector<Body>& bodies() const { return bodies_; }
  const Body& body(const std::string& name) const;
  /// System nodes of the node set "body.set", in the mesh's order.
  std::vector<int> nodes(const std::string& set) const;
  /// Edges (system nodes) of the edge set "body.set".
  std::vector<std::array<int, 2>> edges(const std::string& set) const;
  /// The body of "body.set" and the set's name; throws ModelError under
  /// `key` naming what is known when there is no such set.
  enum class SetKind { Nodes, Edges };
  std::pair<const Body*, std::string> find_set(const std::string& set, SetKind kind,
                                               const std::string& key = "nodes") const;

  // --- contact ------------------------------------------------------------------
  /// Adds the unilateral constraints of a contact pair to the system.
  const ContactPair& add_contact(ContactPair pair, std::unique_ptr<UnilateralConstraints> set);
  const std::vector<ContactPair>& contacts() const { return contacts_; }

  // --- Dirichlet sets ------------------------------------------------------
  /// Holds the set's components at their initial positions.
  void fix(const std::string& nodes, Components components = Components::XY);
  /// Moves the set's components by u g(t) from their initial positions.
  void prescribe_displacement(const std::string& nodes, const Vec& u, const TimeFunction& g,
                              Components components = Components::XY);
  const std::vector<DirichletSet>& dirichlet() const { return dirichlet_; }

  // --- loads -----------------------------------------------------------------
  /// A pure torque T g(t) on a node set (at least two nodes).
  void add_torque(const std::string& name, const std::string& on, double torque,
                  const TimeFunction& g = TimeFunction::constant(1.0));
  /// A force per unit mass b g(t) on a body (on its consistent nodal masses).
  void add_body_force(const std::string& name, const std::string& body, const Vec& acceleration,
                      const TimeFunction& g = TimeFunction::constant(1.0));
  /// A force per unit reference length t g(t) on an edge set, half of t L
  /// of each edge on each of its end nodes.
  void add_traction(const std::string& name, const std::string& on, const Vec& traction,
                    const TimeFunction& g = TimeFunction::constant(1.0));
  const std::vector<ModelLoad>& loads() const { return loads_; }
  /// True when every load's time function is zero on all of [a, b] (exact:
  /// they are piecewise linear): a step over which the energy must be
  /// conserved. True without loads.
  bool loads_vanish(double a, double b) const;

  /// Throws ModelError when there is nothing to integrate (no free node) or
  /// the system cannot be integrated (System::validate()).
  void validate() const;

 private:
  const Particle& checked_particle(const std::string& name, const std::string& key) const;
  // The particle an anchor may hold: known, not fixed, not anchored yet
  // (ModelError with key "particle" otherwise).
  const Particle& anchorable(const std::string& particle) const;
  void prescribe(const std::string& nodes, Components components, bool fixed, const Vec& u,
                 const TimeFunction& g);

  std::unique_ptr<System> system_;
  std::vector<Particle> particles_;
  std::map<std::string, std::size_t> particle_index_;
  std::vector<Body> bodies_;
  std::map<std::pair<int, int>, bool> links_;  // node pairs with a rigid link
  std::set<int> anchored_;
  std::map<int, std::size_t> prescribed_by_;  // dof -> index in dirichlet_
  std::vector<DirichletSet> dirichlet_;
  std::vector<ModelLoad> loads_;
  std::vector<ContactPair> contacts_;
};

}  // namespace emdae
