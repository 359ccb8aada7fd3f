// The IDA stepper's state (IdaStepper::Impl), shared by its two source
// files: ida_stepper.cpp (the consistent start and the driver: allocation,
// (re)starts and the active set, load quadratures, contact events, step())
// and ida_residual.cpp (the GGL system that IDA calls back: the residual
// F(t, y, y'), its Jacobian, the contact root functions). Internal to
// integrators/; the contract is in ida_stepper.hpp.
#pragma once

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "integrators/ida_stepper.hpp"
#include "integrators/klu_solver.hpp"
#include "integrators/sundials_support.hpp"

namespace emdae {

namespace ida_detail {

inline Eigen::Map<Vec> view(N_Vector v) {
  return {N_VGetArrayPointer(v), N_VGetLength(v)};
}

inline double prescribed_position(const PrescribedDof& p, double t, double fixed) {
  return p.position ? p.position(t) : fixed;
}
inline double prescribed_velocity(const PrescribedDof& p, double t) {
  return p.velocity ? p.velocity(t) : 0.0;
}

}  // namespace ida_detail

struct IdaStepper::Impl {
  Impl(const System& system, IdaSettings settings)
      : s(system),
        set(settings),
        n(system.n_dofs()),
        m_sys(system.n_constraints()),
        n_cand(system.n_unilateral()),
        gap_tol(settings.gap_tolerance > 0 ? settings.gap_tolerance : 10 * settings.atol),
        assembler(system),
        disarmed(static_cast<std::size_t>(system.n_unilateral()), 0) {}

  const System& s;
  IdaSettings set;
  const int n, m_sys, n_cand;
  int m = 0, size = 0;  // constraints (the system's, then the active contacts), unknowns
  double gap_tol;
  Assembler assembler;  // potentials and mass only
  TermWorkspace ws;

  // Contact: the active candidates in the order of their multipliers, their
  // terms for the prepared step, and the candidates whose gap root is moved
  // to gap = -gap_tol (see ida_stepper.hpp: chattering guard).
  std::vector<int> active;
  std::vector<const Term*> extra;
  std::vector<char> disarmed;

  // Declared in creation order: destroyed in reverse, IDA memory first and
  // the context last.
  sundials::Context ctx;
  sundials::Vector yy, yp, id, yq, ypq;
  sundials::Vector atolv;  // absolute tolerances (the multipliers' held up)
  sundials::Matrix jmat;
  std::unique_ptr<KluSolver> klu;
  KluSolver::Counters klu_done;  // of the solvers of earlier (re)starts
  double pivot_fill = 1.0;       // what their last one measured of KLU's pivoting
  sundials::Memory<IDAFree> mem;

  bool need_restart = true;
  // The state handed out last; anything else is a state changed from outside.
  double t_out = 0.0;
  Vec q_out, v_out;
  std::vector<int> active_out;
  Vec q_start;  // positions of prescribed dofs without g(t) stay at these

  // A root returned by IDA and not yet acted upon (it may lie beyond the
  // output time of the call that found it: then it is handled at the start
  // of the next call, which continues from it).
  bool pending = false;
  double t_root = 0.0;
  Vec y_root;
  std::vector<int> roots_found;

  // Callback state: exceptions are parked here and rethrown after IDASolve.
  std::exception_ptr error;
  std::string last_message;

  // Scratch.
  Vec q, v, f, load, ql, vl, grad, gt, rq;
  Mat hess;
  Triplets trip, tmp;
  SparseMatrix jac;

  // Counters of earlier IDA lives (IDAReInit resets IDA's own).
  long n_inits = 0, steps_before = 0, jacs_before = 0, iters_before = 0;

  const Term& constraint(int l) const {
    return l < m_sys ? *s.constraints()[static_cast<std::size_t>(l)]
                     : *extra[static_cast<std::size_t>(l - m_sys)];
  }
  bool free_dof(int i) const { return !s.is_prescribed()[static_cast<std::size_t>(i)]; }
  bool is_active(int cand) const {
    return std::find(active.begin(), active.end(), cand) != active.end();
  }
  bool engaged(int cand, const Vec& x) const {
    return s.unilateral_term(cand) != nullptr && std::isfinite(s.unilateral_gap(cand, x));
  }
  void refresh_terms() {
    extra.clear();
    for (int cand : active) {
      const Term* t = s.unilateral_term(cand);
      if (!t) throw std::logic_error("IdaStepper: active candidate without a function");
      extra.push_back(t);
    }
  }

  // --- the GGL system IDA calls back (ida_residual.cpp) ---------------------
  void residual(double t, const Eigen::Map<Vec>& y, const Eigen::Map<Vec>& ydot, Eigen::Map<Vec> r,
                bool prescribed_rows = true);
  void jacobian(double t, double cj, const Eigen::Map<Vec>& y);
  void roots(double t, const Eigen::Map<Vec>& y, realtype* g);
  static int residual_cb(realtype t, N_Vector y, N_Vector ydot, N_Vector r, void* data);
  static int jacobian_cb(realtype t, realtype cj, N_Vector y, N_Vector, N_Vector, SUNMatrix a,
                         void* data, N_Vector, N_Vector, N_Vector);
  static int root_cb(realtype t, N_Vector y, N_Vector, realtype* g, void* data);
  static void error_cb(int, const char* module, const char* function, char* msg, void* data);

  // --- IDA's counters, over all its lives -----------------------------------
  long counter(int (*get)(void*, long*), const char* call) const {
    long value = 0;
    if (mem) sundials::check(get(mem.get(), &value), call);
    return value;
  }
  long steps() const { return steps_before + counter(IDAGetNumSteps, "IDAGetNumSteps"); }
  long jacs() const { return jacs_before + counter(IDAGetNumJacEvals, "IDAGetNumJacEvals"); }
  long iters() const {
    return iters_before + counter(IDAGetNumNonlinSolvIters, "IDAGetNumNonlinSolvIters");
  }
  // Before IDA's counters are reset (IDAReInit) or its memory freed.
  void retire_counters() {
    steps_before = steps();
    jacs_before = jacs();
    iters_before = iters();
  }

  void create_context() { ctx = sundials::make_context(); }

  // --- the driver (ida_stepper.cpp) -----------------------------------------
  void allocate(double t, const Vec& y0);
  double initial_step(const ConsistentStart& c, double interval) const;
  int settle(double t, const Vec& q0, const Vec& v0, std::vector<int> entering, ConsistentStart& c);
  int restart(double t, const Vec& q0, const Vec& v0, const std::vector<int>& entering,
              double interval);
  bool continues(const State& st) const;
  bool has_quadrature() const;
  void quadrature_point(double t, double& power, double& drive, Vec& impulse, Vec& angular);
  void integrate_loads(double a, double b, StepStats& stats);
  int handle_root(double interval);
};

}  // namespace emdae
