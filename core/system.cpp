#include "core/system.hpp"

#include <stdexcept>
#include <string>

namespace emdae {

System::System(int dim) : dim_(dim) {
  if (dim != 2 && dim != 3)
    throw std::invalid_argument("System: dimension must be 2 or 3, received " +
                                std::to_string(dim));
}

int System::add_node(const Vec& position, const Vec& velocity) {
  if (position.size() != dim_ || velocity.size() != dim_)
    throw std::invalid_argument("System::add_node: position and velocity need " +
                                std::to_string(dim_) + " components");
  const int node = n_nodes();
  x0_.conservativeResize(x0_.size() + dim_);
  v0_.conservativeResize(v0_.size() + dim_);
  x0_.tail(dim_) = position;
  v0_.tail(dim_) = velocity;
  is_prescribed_.resize(static_cast<std::size_t>(n_dofs()), false);
  is_massless_.resize(static_cast<std::size_t>(n_dofs()), false);
  assembled_ = false;
  return node;
}

void System::set_initial_velocity(int node, const Vec& velocity) {
  v0_.segment(node * dim_, dim_) = velocity;
}

void System::add_mass(int a, int b, double m) {
  node_mass_.emplace_back(a, b, m);
  if (a != b) node_mass_.emplace_back(b, a, m);
  assembled_ = false;
}

void System::lump_mass(const std::vector<int>& nodes) {
  std::vector<bool> in(static_cast<std::size_t>(n_nodes()), false);
  for (int node : nodes) in[static_cast<std::size_t>(node)] = true;
  std::vector<double> row(static_cast<std::size_t>(n_nodes()), 0.0);
  std::vector<Eigen::Triplet<double, long>> kept;
  kept.reserve(node_mass_.size());
  for (const auto& e : node_mass_) {
    if (in[static_cast<std::size_t>(e.row())] && in[static_cast<std::size_t>(e.col())])
      row[static_cast<std::size_t>(e.row())] += e.value();
    else
      kept.push_back(e);
  }
  for (int node : nodes)
    if (row[static_cast<std::size_t>(node)] != 0.0)
      kept.emplace_back(node, node, row[static_cast<std::size_t>(node)]);
  node_mass_ = std::move(kept);
  assembled_ = false;
}

void System::add_mass_group(const std::vector<int>& nodes, const std::vector<int>& recipients) {
  mass_groups_.push_back({nodes, recipients});
  for (int node : nodes) {
    if (node < 0 || node >= n_nodes())
      throw std::invalid_argument("System::add_mass_group: no node " + std::to_string(node));
    if (is_massless_[static_cast<std::size_t>(dof(node, 0))]) continue;
    for (int d = 0; d < dim_; ++d) is_massless_[static_cast<std::size_t>(dof(node, d))] = true;
    ++n_massless_;
  }
  assembled_ = false;
}

namespace {

Symmetry both(Symmetry a, Symmetry b) {
  return {a.translation && b.translation, a.rotation && b.rotation};
}

}  // namespace

void System::add_potential(std::unique_ptr<Term> term) {
  term_symmetry_ = both(term_symmetry_, term->symmetry());
  potentials_.push_back(std::move(term));
}
void System::add_constraint(std::unique_ptr<Term> term) {
  term_symmetry_ = both(term_symmetry_, term->symmetry());
  constraints_.push_back(std::move(term));
}

void System::add_unilateral(std::unique_ptr<UnilateralConstraints> set) {
  unilateral_.push_back(std::move(set));
}

void System::add_load_forces(const Vec& q, double t, Vec& f, Triplets* jac,
                             double jac_factor) const {
  for (const auto& load : loads_) load->add_force(q, t, f, jac, jac_factor, is_prescribed_);
}

int System::n_unilateral() const {
  int n = 0;
  for (const auto& u : unilateral_) n += u->size();
  return n;
}

std::pair<int, int> System::unilateral_candidate(int id) const {
  for (std::size_t k = 0; k < unilateral_.size(); ++k) {
    if (id < unilateral_[k]->size()) return {static_cast<int>(k), id};
    id -= unilateral_[k]->size();
  }
  throw std::out_of_range("no unilateral candidate " + std::to_string(id));
}

const Term* System::unilateral_term(int id) const {
  const auto [set, i] = unilateral_candidate(id);
  return unilateral_[static_cast<std::size_t>(set)]->term(i);
}

double System::unilateral_gap(int id, const Vec& q) const {
  const auto [set, i] = unilateral_candidate(id);
  return unilateral_[static_cast<std::size_t>(set)]->gap(i, q);
}

double System::unilateral_overlap_gap(int id, const Vec& q) const {
  const auto [set, i] = unilateral_candidate(id);
  return unilateral_[static_cast<std::size_t>(set)]->overlap_gap(i, q);
}

double System::unilateral_penalty(int id) const {
  const auto [set, i] = unilateral_candidate(id);
  return unilateral_[static_cast<std::size_t>(set)]->penalty(i);
}

bool System::has_penalty_contact() const {
  for (int id = 0; id < n_unilateral(); ++id)
    if (unilateral_penalty(id) > 0.0) return true;
  return false;
}

std::unique_ptr<Term> System::pop_constraint() {
  if (constraints_.empty()) throw std::logic_error("System::pop_constraint: no constraint");
  std::unique_ptr<Term> t = std::move(constraints_.back());
  constraints_.pop_back();
  term_symmetry_ = Symmetry{};
  for (const auto* list : {&potentials_, &constraints_})
    for (const auto& term : *list) term_symmetry_ = both(term_symmetry_, term->symmetry());
  return t;
}

void System::prescribe(PrescribedDof p) {
  if (p.dof < 0 || p.dof >= n_dofs())
    throw std::invalid_argument("System::prescribe: no dof " + std::to_string(p.dof));
  if (is_prescribed_[static_cast<std::size_t>(p.dof)]) return;
  is_prescribed_[static_cast<std::size_t>(p.dof)] = true;
  prescribed_.push_back(std::move(p));
}

void System::fix_node(int node) {
  for (int d = 0; d < dim_; ++d) prescribe({dof(node, d), {}, {}});
}

const SparseMatrix& System::mass() const {
  if (!assembled_) {
    std::vector<Eigen::Triplet<double, long>> t;
    t.reserve(node_mass_.size() * static_cast<std::size_t>(dim_));
    for (const auto& e : node_mass_) {
      if (n_massless_ > 0 &&
          (is_massless_[static_cast<std::size_t>(dof(static_cast<int>(e.row()), 0))] ||
           is_massless_[static_cast<std::size_t>(dof(static_cast<int>(e.col()), 0))]))
        continue;
      for (int d = 0; d < dim_; ++d)
        t.emplace_back(e.row() * dim_ + d, e.col() * dim_ + d, e.value());
    }
    mass_.resize(n_dofs(), n_dofs());
    mass_.setFromTriplets(t.begin(), t.end());
    lumped_ = mass_ * Vec::Ones(n_dofs());
    assembled_ = true;
  }
  return mass_;
}

const Vec& System::lumped_mass() const {
  mass();
  return lumped_;
}

Symmetry System::symmetry() const {
  if (!prescribed_.empty()) return {false, false};
  return term_symmetry_;
}

void System::validate() const {
  const Vec& m = lumped_mass();
  for (int i = 0; i < n_dofs(); ++i)
    if (!(m[i] > 0.0) && !is_massless_[static_cast<std::size_t>(i)])
      throw std::invalid_argument("node " + std::to_string(i / dim_) +
                                  " has no positive mass (lumped mass " + std::to_string(m[i]) +
                                  ")");
  for (const auto* list : {&potentials_, &constraints_})
    for (const auto& term : *list)
      for (int d : term->dofs())
        if (d < 0 || d >= n_dofs())
          throw std::invalid_argument(term->describe() + " refers to dof " + std::to_string(d) +
                                      " of a system with " + std::to_string(n_dofs()) + " dofs");
}

}  // namespace emdae
