// What every use of SUNDIALS here shares: move-only owners of its objects
// and the checks of its return codes, which name the call (and, where the
// module can, the flag) in the exception they throw.
//
//   sundials::Context ctx = sundials::make_context();
//   sundials::Vector u = sundials::make_vector(n, ctx.get());
//   sundials::Memory<KINFree> kin(sundials::check_ptr(KINCreate(ctx.get()), "KINCreate"));
//   sundials::check(KINInit(kin.get(), residual, u.get()), "KINInit");
//
// Owners free in the reverse order of their declaration; an object that
// refers to another (a solver to its vectors) must be declared after it.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_matrix.h>

#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace emdae::sundials {

/// Throws std::runtime_error "CALL failed with flag N" for a negative flag.
inline void check(int flag, const char* call) {
  if (flag < 0)
    throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

/// The same with the flag's name from the module (IDAGetReturnFlagName,
/// IDAGetLinReturnFlagName, ...): "CALL failed: IDA_ERR_FAIL (-3)".
inline void check(int flag, const char* call, char* (*flag_name)(long int)) {
  if (flag >= 0) return;
  char* name = flag_name(flag);
  const std::string what = std::string(call) + " failed: " + (name ? name : "unknown flag") + " (" +
                           std::to_string(flag) + ")";
  std::free(name);
  throw std::runtime_error(what);
}

/// `p`, or std::runtime_error "CALL returned NULL".
template <class T>
T check_ptr(T p, const char* call) {
  if (!p) throw std::runtime_error(std::string(call) + " returned NULL");
  return p;
}

struct ContextFree {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorFree {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixFree {
  void operator()(SUNMatrix a) const { SUNMatDestroy(a); }
};
/// A solver's memory block, freed by its module's XFree(void**).
template <void (*Free)(void**)>
struct MemoryFree {
  void operator()(void* mem) const { Free(&mem); }
};

using Context = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorFree>;
using Matrix = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixFree>;
template <void (*Free)(void**)>
using Memory = std::unique_ptr<void, MemoryFree<Free>>;

inline Context make_context() {
  SUNContext c = nullptr;
  check(SUNContext_Create(nullptr, &c), "SUNContext_Create");
  return Context(c);
}

inline Vector make_vector(long n, SUNContext ctx) {
  return Vector(check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial"));
}

}  // namespace emdae::sundials
