#include "core/user_term.hpp"

#include <stdexcept>

namespace emdae {

namespace {

// value, gradient and hessian always; the time derivatives all or none, and
// only for a time-dependent term. Returns whether they are given.
template <class F>
bool require(const F& f, const std::string& name, bool time_dependent) {
  if (!f.value || !f.gradient || !f.hessian)
    throw std::invalid_argument("user term '" + name + "' needs value, gradient and hessian");
  const int n_rates = !!f.value_t + !!f.gradient_t + !!f.value_tt;
  if (n_rates != 0 && n_rates != 3)
    throw std::invalid_argument("user term '" + name +
                                "': give all of value_t, gradient_t and value_tt, or none");
  if (n_rates == 3 && !time_dependent)
    throw std::invalid_argument("user term '" + name +
                                "' has time derivatives but is not marked time_dependent");
  return n_rates == 3;
}

class FunctionTerm final : public CoordinateTerm {
 public:
  FunctionTerm(std::vector<int> dofs, FunctionOfQ f, std::string name, bool time_dependent)
      : CoordinateTerm(std::move(dofs)),
        f_(std::move(f)),
        name_(std::move(name)),
        time_dependent_(time_dependent),
        has_rates_(require(f_, name_, time_dependent)) {}
  double block_value(int, const VecRef& q, double t) const override { return f_.value(q, t); }
  void block_gradient(int, const VecRef& q, double t, Eigen::Ref<Vec> g) const override {
    g = f_.gradient(q, t);
  }
  void block_hessian(int, const VecRef& q, double t, Eigen::Ref<Mat> h) const override {
    h = f_.hessian(q, t);
  }
  bool depends_on_time() const override { return time_dependent_; }
  bool has_time_derivatives() const override { return has_rates_; }
  double block_value_t(int, const VecRef& x, double t) const override { return f_.value_t(x, t); }
  void block_gradient_t(int, const VecRef& x, double t, Eigen::Ref<Vec> g) const override {
    g = f_.gradient_t(x, t);
  }
  double block_value_tt(int, const VecRef& x, double t) const override { return f_.value_tt(x, t); }
  std::string describe() const override { return "user function '" + name_ + "'"; }

 private:
  FunctionOfQ f_;
  std::string name_;
  bool time_dependent_;
  bool has_rates_;
};

class InvariantFunctionTerm final : public QuadraticFormTerm {
 public:
  InvariantFunctionTerm(std::vector<int> dofs, std::vector<QuadraticInvariant> inv, FunctionOfPi f,
                        std::string name, Symmetry symmetry, bool time_dependent)
      : QuadraticFormTerm(std::move(dofs), static_cast<int>(inv.size())),
        f_(std::move(f)),
        name_(std::move(name)),
        symmetry_(symmetry),
        time_dependent_(time_dependent),
        has_rates_(require(f_, name_, time_dependent)) {
    for (auto& i : inv) add_invariant(std::move(i.a), std::move(i.b), i.c);
  }
  double block_value(int, const VecRef& pi, double t) const override { return f_.value(pi, t); }
  void block_gradient(int, const VecRef& pi, double t, Eigen::Ref<Vec> g) const override {
    g = f_.gradient(pi, t);
  }
  void block_hessian(int, const VecRef& pi, double t, Eigen::Ref<Mat> h) const override {
    h = f_.hessian(pi, t);
  }
  bool depends_on_time() const override { return time_dependent_; }
  bool has_time_derivatives() const override { return has_rates_; }
  double block_value_t(int, const VecRef& x, double t) const override { return f_.value_t(x, t); }
  void block_gradient_t(int, const VecRef& x, double t, Eigen::Ref<Vec> g) const override {
    g = f_.gradient_t(x, t);
  }
  double block_value_tt(int, const VecRef& x, double t) const override { return f_.value_tt(x, t); }
  Symmetry symmetry() const override { return symmetry_; }
  std::string describe() const override { return "user invariant function '" + name_ + "'"; }

 private:
  FunctionOfPi f_;
  std::string name_;
  Symmetry symmetry_;
  bool time_dependent_;
  bool has_rates_;
};

}  // namespace

std::unique_ptr<Term> make_function_term(std::vector<int> dofs, FunctionOfQ f, std::string name,
                                         bool time_dependent) {
  return std::make_unique<FunctionTerm>(std::move(dofs), std::move(f), std::move(name),
                                        time_dependent);
}

std::unique_ptr<Term> make_invariant_term(std::vector<int> dofs,
                                          std::vector<QuadraticInvariant> invariants,
                                          FunctionOfPi f, std::string name, Symmetry symmetry,
                                          bool time_dependent) {
  if (invariants.empty()) throw std::invalid_argument("user term '" + name + "' has no invariants");
  return std::make_unique<InvariantFunctionTerm>(std::move(dofs), std::move(invariants),
                                                 std::move(f), std::move(name), symmetry,
                                                 time_dependent);
}

}  // namespace emdae
