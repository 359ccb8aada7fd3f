// Terms for a user's own potential or constraint.
//
// Two ways in:
//  - make_invariant_term: the user names quadratic invariants pi_k = 1/2 q^T A_k q
//    + b_k^T q + c_k and the reduced function f~(pi); the energy-momentum
//    stepper then conserves whatever symmetry the invariants have.
//  - make_function_term: the user gives f(q, t) with gradient and Hessian and
//    no invariants; the discrete gradient falls back to Gonzalez's in q-space
//    (energy conserved for time-independent f, momentum not guaranteed). This
//    is how the classic multibody DAE test problems, or a driven constraint
//    depending on t, enter.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/term.hpp"

namespace emdae {

struct FunctionOfQ {
  std::function<double(const Vec& q, double t)> value;
  std::function<Vec(const Vec& q, double t)> gradient;
  std::function<Mat(const Vec& q, double t)> hessian;
  // Optional, for a time-dependent f (a driven constraint): the partial
  // derivatives in t at fixed q, df/dt, grad_q df/dt and d2f/dt2. Give all
  // three or none; without them IDA and generalized-alpha difference f in t,
  // which limits IDA to tolerances of about 1e-9 (Term::value_t()).
  std::function<double(const Vec& q, double t)> value_t;
  std::function<Vec(const Vec& q, double t)> gradient_t;
  std::function<double(const Vec& q, double t)> value_tt;
};

std::unique_ptr<Term> make_function_term(std::vector<int> dofs, FunctionOfQ f, std::string name,
                                         bool time_dependent = false);

struct QuadraticInvariant {
  Mat a;  // symmetric, n_local x n_local
  Vec b;  // n_local
  double c = 0.0;
};

struct FunctionOfPi {
  std::function<double(const Vec& pi, double t)> value;
  std::function<Vec(const Vec& pi, double t)> gradient;
  std::function<Mat(const Vec& pi, double t)> hessian;
  // Optional, as in FunctionOfQ: d f~/dt, grad_pi d f~/dt and d2 f~/dt2 at
  // fixed pi (all three or none).
  std::function<double(const Vec& pi, double t)> value_t;
  std::function<Vec(const Vec& pi, double t)> gradient_t;
  std::function<double(const Vec& pi, double t)> value_tt;
};

std::unique_ptr<Term> make_invariant_term(std::vector<int> dofs,
                                          std::vector<QuadraticInvariant> invariants,
                                          FunctionOfPi f, std::string name, Symmetry symmetry,
                                          bool time_dependent = false);

}  // namespace emdae
