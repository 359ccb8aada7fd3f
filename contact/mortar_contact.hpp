// Two-body frictionless mortar contact as a set of unilateral constraints:
// one candidate per slave node, its function the normalized weighted gap of
// mortar.hpp over the segment pairs that the search finds for the step.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "contact/mortar.hpp"
#include "contact/search.hpp"
#include "core/system.hpp"
#include "core/unilateral.hpp"

namespace emdae {

/// A chain of straight segments on a body's boundary; each edge (a, b) holds
/// system node indices and has the body on its left.
struct ContactSurface {
  std::string name;
  std::vector<std::array<int, 2>> edges;
};

struct ContactOptions {
  /// Search margin in units of the mean master segment length, added to the
  /// distance the surfaces can close within a step (2 max|v| dt).
  double search_margin = 1.0;
  /// Both surfaces massless, their mass moved within their bodies
  /// (core/modified_mass.hpp); contact/contact_pair.hpp applies it.
  bool modified_mass = false;
  /// Penalty parameter epsilon (pressure per unit penetration); 0: the
  /// contact conditions hold exactly (Lagrange multipliers). With epsilon >
  /// 0 every slave node A carries the potential epsilon w_A / 2 min(Phi_A,
  /// 0)^2, the mortar form of epsilon / 2 int min(g, 0)^2: pressure p_A =
  /// epsilon max(-Phi_A, 0), penetration p / epsilon.
  double penalty = 0.0;
  /// Pairs weighed by their distance as well as by how they face
  /// (contact/mortar.hpp, "The distance fade"); false: by how they face only,
  /// as before 2026-11-27 (the tests compare the two).
  bool distance_fade = true;
};

class MortarContact final : public UnilateralConstraints {
 public:
  MortarContact(const System& system, ContactSurface slave, ContactSurface master, std::string name,
                ContactOptions options = {});

  std::string name() const override { return name_; }
  int size() const override { return static_cast<int>(slave_nodes_.size()); }
  void prepare(const Vec& q, const Vec& v, double dt) override;
  const Term* term(int i) const override { return terms_[static_cast<std::size_t>(i)].get(); }
  /// Phi_i(q) (with the coverage barrier of mortar.hpp), or +infinity when
  /// nothing of the node's slave segments lies opposite a master segment.
  double gap(int i, const Vec& q) const override;
  /// The normalized weighted gap g_A / W_A alone (no coverage barrier), or
  /// +infinity where gap() is.
  double overlap_gap(int i, const Vec& q) const override;
  /// Each slave node's closest point on the master chain and each master
  /// node's on the slave chain: a node is behind a chain where it lies on
  /// the body's side of the closest edge's interior (edges have the body on
  /// their left) or behind the closest vertex's pseudo-normal (the sum of
  /// its two edges' outward normals); at a chain's open end it is not
  /// decided (counted as outside). Returns the largest such distance.
  /// Each chain is taken with the surfaces joined to it (add_joined_surface).
  /// A node behind the other chain that lies in none of the other body's
  /// elements (the Q1 elements connected to its surface, in the current
  /// configuration) has gone through that body: SurfaceDepth::through is
  /// how far past the nearest of them it lies along the direction of its
  /// depth (from its closest point on the surface), of the coarser mesh.
  SurfaceDepth surface_depth(const Vec& q) const override;
  /// The straight paths of each slave node against the moving master chain
  /// and of each master node against the slave chain (every position linear
  /// in time over the step): where a path crosses an edge from in front to
  /// behind, its depth behind that edge's line when the path next crosses
  /// out of the chain, or at q1. Relative as surface_depth's.
  SweptDepth swept_depth(const Vec& q0, const Vec& q1) const override;
  /// Another contact surface's edges: where they share a node with the
  /// slave or the master chain, or with what was joined to it before, they
  /// join that chain for surface_depth. A block's side declared as a slave
  /// of its own beside its bottom: alone, an open side face is a half-plane,
  /// and a node under the bottom face lies behind it. Returns whether
  /// anything joined (callers repeat until nothing does: joins are
  /// transitive).
  bool add_joined_surface(const std::vector<std::array<int, 2>>& edges);
  std::string describe(int i) const override;
  /// epsilon w_A when the contact is penalized, else 0.
  double penalty(int i) const override;

  const ContactSurface& slave_surface() const { return slave_; }
  const ContactSurface& master_surface() const { return master_; }
  int slave_node(int i) const { return slave_nodes_[static_cast<std::size_t>(i)]; }
  /// Mortar weight int N_A dGamma of slave node i in the reference configuration.
  double weight(int i) const { return weights_[static_cast<std::size_t>(i)]; }
  /// Its mortar weight at q: int N_A dgamma over the node's mortar segments
  /// (the part of its slave segments opposite the master) in the current
  /// configuration, with the segments as of the last prepare(), and int N_A n
  /// dgamma (n the outward unit normal); zero when nothing lies opposite.
  MortarGapTerm::CurrentWeight current_weight(int i, const Vec& q) const;
  /// Segment pairs found by the last prepare(), and box tests it made.
  long n_pairs() const { return n_pairs_; }
  long n_box_tests() const { return box_tests_; }

 private:
  /// MortarGapTerm::engaged_value of candidate i at q (global), +infinity
  /// without a function.
  double engaged_value(int i, const Vec& q, bool with_barrier) const;

  std::string name_;
  ContactSurface slave_, master_;
  ContactOptions options_;
  std::vector<int> slave_nodes_;
  std::vector<int> master_nodes_;  // for surface_depth()
  // The chains surface_depth() measures against: the own edges and those
  // of joined surfaces (add_joined_surface).
  std::vector<std::array<int, 2>> slave_joined_, master_joined_;
  // The Q1 elements (corner nodes, in order) of the body each surface lies
  // on, and those at each of its nodes: a node behind the other surface
  // and outside all of them went through it, by how far past the nearest
  // it lies along its depth's direction. Empty: not an FE body.
  struct BodyElements {
    std::vector<std::array<int, 4>> quads;
    std::unordered_map<int, std::vector<int>> at_node;
    /// How far p lies past the quads at q along the unit vector `inward`
    /// (into the body through the surface it lies behind): 0 in one of them
    /// (on its boundary counts; those at `near` are tried first), else its
    /// offset from the nearest point of the nearest quad, along `inward`,
    /// or 0. Quads with `own` as a corner do not count.
    double outside(const Vec& q, const Eigen::Vector2d& p, const Eigen::Vector2d& inward,
                   const std::array<int, 2>& near, int own) const;
  };
  BodyElements slave_body_, master_body_;
  std::vector<std::array<int, 2>> node_edges_;  // slave edges at each slave node (-1: none)
  std::vector<double> weights_;
  double mean_master_length_ = 0.0;
  std::vector<std::unique_ptr<MortarGapTerm>> terms_;
  BucketGrid grid_;
  long n_pairs_ = 0;
  long box_tests_ = 0;  // in the last prepare(), all against all or through the grid
  // Up to this many box tests all against all, more through the grid.
  static constexpr std::size_t kDirectBoxTests = 1024;
};

/// The contact pressure at one active slave node A of a MortarContact. Its
/// multiplier lambda_A belongs to the normalized weighted gap Phi_A = g_A /
/// W_A (mortar.hpp), W_A the reference weight, and g_A = int N_A g dgamma is
/// an integral over the current surface. The force lambda_A dPhi_A/dq on
/// slave node B is then, where the gap is closed, p_A int N_A N_B n dgamma
/// with p_A = -lambda_A / W_A: p = sum_A N_A p_A is the contact pressure as a
/// force per current length (positive: compressive), and the node's share of
/// the normal force (summed over B) is f_A = p_A w_A, w_A = int N_A dgamma
/// its current weight over its mortar segments; as a vector, the force the
/// master exerts on the slave through node A's multiplier is -p_A int N_A n
/// dgamma (n the slave's outward normal). (Summing -lambda_A = p_A W_A
/// instead misses the surface's stretch: 2 % on Hertz.) At an equilibrium
/// these are the static multipliers; after a time step of em or midpoint they
/// are the constant contact force of that step.
struct SlavePressure {
  int set = 0;                       // index in System::unilateral()
  int candidate = 0;                 // index in the set (MortarContact::slave_node(candidate))
  int node = 0;                      // system node
  double gap = 0.0;                  // Phi_A(q) (+infinity when nothing lies opposite any more)
  double weight = 0.0;               // w_A, current configuration, over the mortar segments
  double force = 0.0;                // p_A w_A
  double resultant[2] = {0.0, 0.0};  // -p_A int N_A n dgamma: on the slave
  double pressure = 0.0;             // p_A = -lambda_A / W_A, force per current length
};

/// The pressures of every active candidate of every MortarContact of
/// `system`, sorted by set, then candidate; `lambda` and `active` as in a
/// State (the contact multipliers after the system's n_constraints() own).
std::vector<SlavePressure> slave_pressures(const System& system, const Vec& q, const Vec& lambda,
                                           const std::vector<int>& active);

}  // namespace emdae
