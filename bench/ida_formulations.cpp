// Which form of the index-3 mechanical DAE to hand to IDA: measured.
//
// integrators/ida_stepper.hpp gives the reasons for the stabilized index-2
// form of Gear, Gupta and Leimkuhler (GGL); this program measures it against
// the alternatives, all with IDA 6.4 on the same System objects:
//
//  ggl      the project's IdaStepper as it is: y = (q, v, lambda, mu), rows
//           q' - v + G^T mu, M v' + grad V + G^T lambda, Phi, G v; KLU with
//           its analytic Jacobian; lambda, mu out of the error test.
//  index1   y = (q, v, lambda), rows q' - v, M v' + grad V + G^T lambda and
//           the acceleration-level constraint G v' + (v^T Hess Phi_l v)_l;
//           lambda algebraic (IDASetId, IDASetSuppressAlg), dense linear
//           solver with IDA's difference-quotient Jacobian. No projection.
//  index1p  the same, with (q, v) projected onto Phi = 0, G v = 0 at every
//           output time (IDA is stopped there, IDASetStopTime) and IDA
//           restarted from the projected state (IDAReInit): IDA has no
//           projection hook, so this is the only way. The projection and
//           the new lambda, v' are consistent_start(), the same routine
//           IdaStepper starts from. Each restart takes IDA's own first step.
//  index1p/h  the same, each restart taking IdaStepper's first step (below).
//  index1p1 projected every 100th output (every time unit) only, IdaStepper's
//           first step: fewer restarts, more drift in between.
//  index3   rows q' - v, M v' + grad V + G^T lambda, Phi; lambda algebraic,
//           v in the error test; dense DQ Jacobian.
//  index3v  the same with v out of the error test as well (the usual advice
//           for index 3, Brenan, Campbell & Petzold ch. 6).
// Except for index1p, every start takes IdaStepper's first step, from the
// accelerations, h0 = (max_i |a_i| / (rtol |q_i| + atol))^(-1/2), at most
// the output interval (IDA's own, min(1e-3 |tout - t|, 1 / (2 ||y'||_WRMS)),
// is ~1e-5 for outputs 0.01 apart, and ~tol below tol 1e-5). With one
// start that makes the forms differ in their equations only; with a restart
// at every output the choice decides the outcome, hence both index1p rows.
//
// Physics (grad V, G, v^T Hess Phi v, Phi) comes from the Term/gradient API
// (Assembler, term_gradient with the Hessian, as consistent_start forms
// v^T Hess Phi v); nothing is written per system.
//
// Systems: the Cartesian pendulum of tests/pendulum.hpp and the double
// pendulum of tests/particle_systems.hpp, with their independent GSL
// references (tests/pendulum.hpp). For each form and rtol = atol in 1e-4,
// 1e-6, 1e-8, 1e-10, one run over [0, 100] with output every 0.01 (IDA's
// interpolation, IDA_NORMAL to each output time; index1p* stop at their
// projections):
//   error   max nodal |q - q_ref| at t = 1
//   Phi, Gv max |Phi|, max |G v| over the outputs (after the projection for
//           index1p*: what a caller receives; before it in the notes)
//   dH      max |H(t) - H(0)| over the outputs
//   steps   IDA's internal steps; res: residual evaluations of the nonlinear
//           solver (IDAGetNumResEvals; for ggl its Newton iterations, which
//           IdaStepper exposes: SUNDIALS' Newton solver evaluates the
//           residual once per iteration, checked on the other forms); res DQ:
//           those of the difference-quotient Jacobians; Jac: Jacobian
//           evaluations; starts: IDAInit + IDAReInit calls
//   CPU s   process CPU time of the integration calls (with the projections)
//
// Usage: ida_formulations [--markdown FILE] [--quick]
//   --markdown FILE  also writes the table to FILE: between the lines
//                    "<!-- ida_formulations:begin -->" and "... :end -->" if
//                    FILE has them (docs/ida-formulations.md), else the
//                    whole file
//   --quick          tolerances 1e-4 and 1e-8 over [0, 10] (a smoke run)
#include <gsl/gsl_errno.h>
#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "core/quantities.hpp"
#include "integrators/ida_stepper.hpp"
#include "particle_systems.hpp"
#include "pendulum.hpp"

namespace {

using namespace emdae;

double cpu_seconds() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

struct Form {
  const char* name;
  bool ggl = false;             // IdaStepper; the rest are ReducedRun's
  bool index3 = false;          // row Phi instead of G v' + v^T Hess Phi v
  bool v_in_error_test = true;  // (lambda never is)
  int project_every = 0;        // outputs from one projection to the next, 0: none
  bool ida_first_step = false;  // IDA's own first step at (re)starts, not IdaStepper's
};
const Form kForms[] = {
    {"ggl", true},
    {"index1", false, false, true, 0},
    {"index1p", false, false, true, 1, true},
    {"index1p/h", false, false, true, 1},
    {"index1p1", false, false, true, 100},
    {"index3", false, true, true, 0},
    {"index3v", false, true, false, 0},
};

struct Cost {
  long steps = 0, res = 0, res_dq = 0, jacs = 0, starts = 0;
  long iters = 0;  // nonlinear iterations (to check res == iters)
};

// max |Phi| and max |G v| at (q, v, t).
std::pair<double, double> constraint_drift(Assembler& a, const Vec& q, const Vec& v, double t) {
  Vec phi;
  a.constraint_values(q, t, phi);
  Triplets g;
  a.add_constraint_jacobian(q, t, g, 0, 0);
  Vec gv = Vec::Zero(a.n_constraints());
  for (const auto& e : g) gv[e.row()] += e.value() * v[e.col()];
  return {phi.lpNorm<Eigen::Infinity>(), gv.lpNorm<Eigen::Infinity>()};
}

// IdaStepper's first step: the first BDF1 step's local error h^2/2 |a| at the
// error weights.
double first_step(const ConsistentStart& c, double tol, double interval) {
  const double r = (c.a.array().abs() / (tol * c.q.array().abs() + tol)).maxCoeff();
  return r > 0 ? std::min(interval, 1.0 / std::sqrt(r)) : 0.0;
}

// One integration, advanced from output to output.
class Run {
 public:
  virtual ~Run() = default;
  /// (q, v) at tout; throws std::runtime_error when the integrator fails.
  virtual void advance(double tout, Vec& q, Vec& v) = 0;
  virtual Cost cost() const = 0;
  virtual std::string note() const { return {}; }
};

class GglRun final : public Run {
 public:
  GglRun(const System& s, double tol) : ida_(s, IdaSettings{tol, tol}), st_(initial_state(s)) {}
  void advance(double tout, Vec& q, Vec& v) override {
    const StepStats r = ida_.step(st_, tout - st_.t);
    if (!r.converged) throw std::runtime_error(r.message);
    q = st_.q;
    v = st_.v;
  }
  Cost cost() const override {
    Cost c;
    c.steps = ida_.n_internal_steps();
    c.res = c.iters = ida_.n_nonlinear_iterations();
    c.jacs = ida_.n_jacobian_evaluations();
    c.starts = ida_.n_initializations();
    return c;
  }

 private:
  IdaStepper ida_;
  State st_;
};

// --- index 1 (with or without projection) and index 3 ------------------------

struct Free {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
  void operator()(N_Vector v) const { N_VDestroy(v); }
  void operator()(SUNMatrix a) const { SUNMatDestroy(a); }
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
  void operator()(void* mem) const { IDAFree(&mem); }
};
template <class T>
using Owned = std::unique_ptr<std::remove_pointer_t<T>, Free>;

template <class T>
T made(T p, const char* call) {
  if (!p) throw std::runtime_error(std::string(call) + " returned NULL");
  return p;
}
// A SUNDIALS return flag, named by IDA's (or its linear solver interface's)
// vocabulary when it is one of theirs.
void check(int flag, const char* call, char* (*namer)(long) = IDAGetReturnFlagName) {
  if (flag >= 0) return;
  char* flag_name = namer ? namer(flag) : nullptr;
  const std::string what = std::string(call) + " failed: " + (flag_name ? flag_name : "flag") +
                           " (" + std::to_string(flag) + ")";
  std::free(flag_name);
  throw std::runtime_error(what);
}

Eigen::Map<Vec> view(N_Vector v) {
  return {N_VGetArrayPointer(v), N_VGetLength(v)};
}

class ReducedRun final : public Run {
 public:
  ReducedRun(const System& s, const Form& form, double tol, double interval)
      : s_(s),
        form_(form),
        tol_(tol),
        interval_(interval),
        n_(s.n_dofs()),
        m_(s.n_constraints()),
        assembler_(s) {
    if (!s.prescribed().empty() || !s.loads().empty() || s.n_unilateral() > 0)
      throw std::invalid_argument("ReducedRun: no prescribed dofs, loads or contact");
    for (const auto& c : s.constraints())
      if (c->depends_on_time()) throw std::invalid_argument("ReducedRun: rheonomic constraint");
    SUNContext c = nullptr;
    check(SUNContext_Create(nullptr, &c), "SUNContext_Create", nullptr);
    ctx_.reset(c);
    const long size = 2 * n_ + m_;
    for (Owned<N_Vector>* p : {&yy_, &yp_, &id_})
      p->reset(made(N_VNew_Serial(size, ctx_.get()), "N_VNew_Serial"));
    view(id_.get()) << Vec::Ones(n_), Vec::Constant(n_, form.v_in_error_test ? 1.0 : 0.0),
        Vec::Zero(m_);
    a_.reset(made(SUNDenseMatrix(size, size, ctx_.get()), "SUNDenseMatrix"));
    ls_.reset(made(SUNLinSol_Dense(yy_.get(), a_.get(), ctx_.get()), "SUNLinSol_Dense"));
    start(0.0, s.initial_positions(), s.initial_velocities());
  }

  void advance(double tout, Vec& q, Vec& v) override {
    void* mem = mem_.get();
    // The output at the stop time set by start() (within round-off of it).
    const bool project = form_.project_every > 0 && std::abs(tout - t_stop_) <= 1e-9 * interval_;
    realtype tret = 0;
    message_.clear();
    const int flag = IDASolve(mem, tout, &tret, yy_.get(), yp_.get(), IDA_NORMAL);
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    if (flag < 0) {
      char* flag_name = IDAGetReturnFlagName(flag);
      const std::string what =
          std::string("IDASolve: ") + (flag_name ? flag_name : "?") + " (" + message_ + ")";
      std::free(flag_name);
      throw std::runtime_error(what);
    }
    const auto y = view(yy_.get());
    q = y.head(n_);
    v = y.segment(n_, n_);
    if (!project) return;
    const auto [phi, gv] = constraint_drift(assembler_, q, v, tout);
    phi_before_ = std::max(phi_before_, phi);
    gv_before_ = std::max(gv_before_, gv);
    const double c0 = cpu_seconds();
    start(tout, q, v);
    proj_cpu_ += cpu_seconds() - c0;
    q = y.head(n_);
    v = y.segment(n_, n_);
  }

  Cost cost() const override {
    Cost c = before_;
    add_counters(c);
    c.starts = starts_;
    return c;
  }

  std::string note() const override {
    if (form_.project_every == 0) return {};
    char buf[160];
    std::snprintf(
        buf, sizeof buf,
        "%ld projections (%.2f s CPU); at them, before projecting: max |Phi| %.1e, max |G v| %.1e",
        starts_ - 1, proj_cpu_, phi_before_, gv_before_);
    return buf;
  }

 private:
  // F(t, y, y') of the index-1 or index-3 form.
  void residual(double t, const Eigen::Map<Vec>& y, const Eigen::Map<Vec>& yp, Eigen::Map<Vec> r) {
    q_ = y.head(n_);
    v_ = y.segment(n_, n_);
    acc_ = yp.segment(n_, n_);
    r.head(n_) = yp.head(n_) - v_;
    f_ = s_.mass() * acc_;
    assembler_.add_potential_forces(GradientKind::Exact, q_, q_, t, t, f_, nullptr);
    const bool index3 = form_.index3;
    for (int l = 0; l < m_; ++l) {
      const Term& c = assembler_.constraint(l);
      gather(c, q_, ql_);
      term_gradient(c, GradientKind::Exact, ql_, ql_, t, t, grad_, index3 ? nullptr : &hess_, ws_);
      const auto& dofs = c.dofs();
      for (std::size_t i = 0; i < dofs.size(); ++i)
        f_[dofs[i]] += y[2 * n_ + l] * grad_[static_cast<Eigen::Index>(i)];
      if (index3) {
        r[2 * n_ + l] = c.value(ql_, t);
      } else {  // G a + v^T Hess Phi_l v
        gather(c, v_, vl_);
        gather(c, acc_, al_);
        r[2 * n_ + l] = grad_.dot(al_) + vl_.dot(hess_ * vl_);
      }
    }
    r.segment(n_, n_) = f_;
  }

  static int residual_cb(realtype t, N_Vector y, N_Vector yp, N_Vector r, void* data) {
    auto* self = static_cast<ReducedRun*>(data);
    try {
      self->residual(t, view(y), view(yp), view(r));
      return view(r).allFinite() ? 0 : 1;  // recoverable: IDA retries with a smaller step
    } catch (...) {
      self->error_ = std::current_exception();
      return -1;
    }
  }

  static void error_cb(int, const char* module, const char* function, char* msg, void* data) {
    try {
      static_cast<ReducedRun*>(data)->message_ = std::string(module) + "::" + function + ": " + msg;
    } catch (...) {  // nothing crosses IDA; the flag is reported all the same
    }
  }

  void add_counters(Cost& c) const {
    if (!mem_) return;
    long v = 0;
    check(IDAGetNumSteps(mem_.get(), &v), "IDAGetNumSteps");
    c.steps += v;
    check(IDAGetNumResEvals(mem_.get(), &v), "IDAGetNumResEvals");
    c.res += v;
    check(IDAGetNumNonlinSolvIters(mem_.get(), &v), "IDAGetNumNonlinSolvIters");
    c.iters += v;
    check(IDAGetNumLinResEvals(mem_.get(), &v), "IDAGetNumLinResEvals", IDAGetLinReturnFlagName);
    c.res_dq += v;
    check(IDAGetNumJacEvals(mem_.get(), &v), "IDAGetNumJacEvals", IDAGetLinReturnFlagName);
    c.jacs += v;
  }

  // (Re)starts IDA at t from (q, v) projected onto Phi = 0, G v = 0, with
  // v' and lambda from the index-1 system (consistent_start).
  void start(double t, const Vec& q, const Vec& v) {
    const ConsistentStart c = consistent_start(s_, t, q, v);
    view(yy_.get()) << c.q, c.v, c.lambda;
    view(yp_.get()) << c.v, c.a, Vec::Zero(m_);
    if (!mem_) {
      mem_.reset(made(IDACreate(ctx_.get()), "IDACreate"));
      void* mem = mem_.get();
      check(IDASetErrHandlerFn(mem, &ReducedRun::error_cb, this), "IDASetErrHandlerFn");
      check(IDAInit(mem, &ReducedRun::residual_cb, t, yy_.get(), yp_.get()), "IDAInit");
      check(IDASStolerances(mem, tol_, tol_), "IDASStolerances");
      check(IDASetUserData(mem, this), "IDASetUserData");
      check(IDASetId(mem, id_.get()), "IDASetId");
      check(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg");
      check(IDASetMaxNumSteps(mem, 100000), "IDASetMaxNumSteps");
      check(IDASetLinearSolver(mem, ls_.get(), a_.get()), "IDASetLinearSolver",
            IDAGetLinReturnFlagName);
    } else {
      add_counters(before_);  // IDAReInit resets IDA's counters
      check(IDAReInit(mem_.get(), t, yy_.get(), yp_.get()), "IDAReInit");
    }
    const double h0 = form_.ida_first_step ? 0.0 : first_step(c, tol_, interval_);
    check(IDASetInitStep(mem_.get(), h0), "IDASetInitStep");
    if (form_.project_every > 0) {  // IDA must not step past the next projection
      t_stop_ = t + form_.project_every * interval_;
      check(IDASetStopTime(mem_.get(), t_stop_), "IDASetStopTime");
    }
    ++starts_;
  }

  const System& s_;
  const Form form_;
  double t_stop_ = 0.0;
  const double tol_, interval_;
  const int n_, m_;
  Assembler assembler_;
  TermWorkspace ws_;
  Vec q_, v_, acc_, f_, ql_, vl_, al_, grad_;
  Mat hess_;
  // Creation order: destroyed in reverse, IDA memory first, the context last.
  Owned<SUNContext> ctx_;
  Owned<N_Vector> yy_, yp_, id_;
  Owned<SUNMatrix> a_;
  Owned<SUNLinearSolver> ls_;
  Owned<void*> mem_;
  Cost before_;  // counters of IDA lives ended by IDAReInit
  long starts_ = 0;
  double proj_cpu_ = 0.0, phi_before_ = 0.0, gv_before_ = 0.0;
  std::exception_ptr error_;
  std::string message_;
};

// --- the study ------------------------------------------------------------------

struct Case {
  std::string name;
  std::function<std::shared_ptr<System>()> build;
  Vec q_ref;  // at t = 1
};

struct Row {
  std::string system, form, status = "ok", note;
  double tol = 0, error = std::nan(""), phi = 0, gv = 0, dh = 0, cpu = 0;
  Cost cost;
};

double max_nodal_distance(int dim, const Vec& a, const Vec& b) {
  double d = 0.0;
  for (Eigen::Index i = 0; i < a.size(); i += dim) d = std::max(d, (a - b).segment(i, dim).norm());
  return d;
}

Row run(const Case& c, const Form& form, double tol, double dt, int n_out) {
  auto s = c.build();
  Assembler assembler(*s);
  const double h0 = measure(*s, s->initial_positions(), s->initial_velocities(), 0.0).total();
  Row row;
  row.system = c.name;
  row.form = form.name;
  row.tol = tol;
  const int k_error = static_cast<int>(std::lround(1.0 / dt));
  std::unique_ptr<Run> r;
  double t = 0.0, c0 = cpu_seconds();
  try {
    if (form.ggl)
      r = std::make_unique<GglRun>(*s, tol);
    else
      r = std::make_unique<ReducedRun>(*s, form, tol, dt);
    row.cpu += cpu_seconds() - c0;
    Vec q, v;
    for (int k = 1; k <= n_out; ++k) {
      t = k * dt;
      c0 = cpu_seconds();
      r->advance(t, q, v);
      row.cpu += cpu_seconds() - c0;
      const auto [phi, gv] = constraint_drift(assembler, q, v, t);
      row.phi = std::max(row.phi, phi);
      row.gv = std::max(row.gv, gv);
      row.dh = std::max(row.dh, std::abs(measure(*s, q, v, t).total() - h0));
      if (k == k_error) row.error = max_nodal_distance(s->dim(), q, c.q_ref);
    }
  } catch (const std::exception& e) {
    row.cpu += cpu_seconds() - c0;
    if (t <= dt) row.phi = row.gv = row.dh = std::nan("");  // no output reached
    char buf[48];
    std::snprintf(buf, sizeof buf, "failed before the output at t = %.4g: ", t);
    row.status = buf + std::string(e.what());
  }
  if (r) {
    row.cost = r->cost();
    row.note = r->note();
    if (!form.ggl && row.cost.res != row.cost.iters)
      row.note += (row.note.empty() ? "" : "; ") + std::string("residual evaluations ") +
                  std::to_string(row.cost.res) + " != nonlinear iterations " +
                  std::to_string(row.cost.iters);
  }
  return row;
}

std::string sci(double x) {
  if (std::isnan(x)) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1e", x);
  return buf;
}

std::string table(const std::vector<Row>& rows, double t_end) {
  std::ostringstream o;
  char buf[400];
  std::vector<std::string> notes;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    if (i == 0 || r.system != rows[i - 1].system)
      o << (i ? "\n" : "") << "**" << r.system << "**\n\n"
        << "| form | tol | error t=1 | max Phi | max Gv | max dH | steps | res | res DQ | Jac | "
           "starts | CPU s |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::snprintf(buf, sizeof buf,
                  "| %s | %.0e | %s | %s | %s | %s | %ld | %ld | %ld | %ld | %ld | %.3f |\n",
                  r.form.c_str(), r.tol, sci(r.error).c_str(), sci(r.phi).c_str(),
                  sci(r.gv).c_str(), sci(r.dh).c_str(), r.cost.steps, r.cost.res, r.cost.res_dq,
                  r.cost.jacs, r.cost.starts, r.cpu);
    o << buf;
    std::snprintf(buf, sizeof buf, "%s %s %.0e: ", r.system.c_str(), r.form.c_str(), r.tol);
    if (r.status != "ok") notes.push_back(buf + r.status);
    if (!r.note.empty()) notes.push_back(buf + r.note);
  }
  std::snprintf(buf, sizeof buf,
                "\nOver t in [0, %g], output every 0.01; max Phi, Gv, dH: max |Phi|, |G v|, "
                "|H(t) - H(0)| over the outputs (those reached, for a run that failed; —: "
                "none).\n",
                t_end);
  o << buf;
  if (!notes.empty()) o << '\n';
  for (const auto& n : notes) o << "- " << n << '\n';
  return o.str();
}

// Writes `text` between the markers of `path`, or as the whole file.
void write_markdown(const std::string& path, const std::string& text) {
  const std::string begin = "<!-- ida_formulations:begin -->",
                    end = "<!-- ida_formulations:end -->";
  std::string doc;
  {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    doc = ss.str();
  }
  const auto b = doc.find(begin), e = doc.find(end);
  if (b != std::string::npos && e != std::string::npos && b < e)
    doc = doc.substr(0, b + begin.size()) + "\n" + text + doc.substr(e);
  else
    doc = text;
  std::ofstream out(path);
  out << doc;
  if (!out) throw std::runtime_error("cannot write " + path);
  std::fprintf(stderr, "wrote %s\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::string markdown;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--markdown") && i + 1 < argc) {
      markdown = argv[++i];
    } else if (!std::strcmp(argv[i], "--quick")) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: %s [--markdown FILE] [--quick]\n", argv[0]);
      return 2;
    }
  }
  gsl_set_error_handler_off();
  try {
    const double dt = 0.01, t_end = quick ? 10.0 : 100.0;
    const int n_out = static_cast<int>(std::lround(t_end / dt));
    const std::vector<double> tols =
        quick ? std::vector<double>{1e-4, 1e-8} : std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10};
    const std::vector<Case> cases = {
        {"pendulum", test_systems::pendulum, test_systems::pendulum_reference(1.0).q},
        {"double pendulum",
         [] {
           // The model keeps its system alive: a pointer to the one, owning the other.
           std::shared_ptr<Model> model = test_systems::double_pendulum();
           return std::shared_ptr<System>(model, &model->system());
         },
         test_systems::double_pendulum_reference(1.0)},
    };
    std::vector<Row> rows;
    for (const auto& c : cases)
      for (const Form& f : kForms)
        for (double tol : tols) {
          rows.push_back(run(c, f, tol, dt, n_out));
          const Row& r = rows.back();
          std::fprintf(stderr, "  %s %s %.0e: error %.2e, %.2f s, %s\n", r.system.c_str(),
                       r.form.c_str(), tol, r.error, r.cpu, r.status.c_str());
        }
    const std::string text = table(rows, t_end);
    std::printf("%s", text.c_str());
    if (!markdown.empty()) write_markdown(markdown, text);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ida_formulations: %s\n", e.what());
    return 1;
  }
  return 0;
}
