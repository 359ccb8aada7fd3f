// Scene files: THE one place they are read.
//
// A scene is a TOML file declaring what a run needs, section by section
// (docs/scenes.md lists every key with its unit, default and range):
//
//   [scene]        name, description, dimension (2 | 3, default 2)
//   [time]         dt (> 0), t_end (>= dt), min_dt (optional, <= dt); without
//                  [time], a scene with [statics] is a static analysis
//   [scheme]       name (see known_schemes(), default "em"), newton_tolerance,
//                  newton_max_iterations, line_search; rtol, atol (ida);
//                  rho_inf (galpha); locate_impacts, gap_tolerance (contact)
//   [[particles]]  name, mass, position, velocity (default 0), fixed (default false)
//   [[springs]]    between = ["a", "b"], stiffness, rest_length, law ("linear" | "green")
//   [[links]]      between = ["a", "b"], length: rigid distance constraint
//   [[anchors]]    particle, point, length: rigid link to a fixed point
//   [[bodies]]     name, mesh = {type = "ring" | "rectangle" | "gmsh", ...}, material =
//                  {model, young, poisson, density}, velocity, angular_velocity,
//                  lumped_mass: a plane-strain Q1 body (2D only); a rectangle may be
//                  graded towards a point (grading, grading_centre)
//   [[contacts]]   name, slave = "body.set", master = "body.set" (edge sets),
//                  search_margin: frictionless mortar contact
//   [[dirichlet]]  nodes = "body.set", fixed = true | displacement = [ux, uy]
//                  with time_function, components ("xy" | "x" | "y")
//   [gravity]      acceleration = [gx, gy(, gz)]: dead load m g on every free
//                  particle and body node
//   [[loads]]      type = "torque" | "body_force" | "traction", on/body, the
//                  magnitude (torque, acceleration, traction), time_function
//   [statics]      enabled, hold_rotation = ["body.set", ...], pseudo_dt,
//                  tolerance, max_steps, newton_tolerance, increments,
//                  load_time: equilibrium first (or only, without [time])
//   [output]       every (history row every N steps, default 1), vtu_every (VTU
//                  fields of FE bodies every N steps; default about 100 files, 0: none)
//   [tolerances]   energy_rel, energy_balance_rel, linear_momentum,
//                  angular_momentum_rel, angular_momentum_balance_rel,
//                  constraint, gap_violation, penetration, contact_pressure_spread
//
// Sets of FE bodies are named "body.set": the mesh generators' node and edge
// sets ("inner", "outer" of a ring; "left", "right", "bottom", "top" of a
// rectangle). Time functions are dimensionless factors on a load's magnitude:
// {type = "constant", value}, {type = "ramp", start, end, value},
// {type = "hat", start, end, peak}, {type = "table", times, values}.
//
// Everything is validated before anything is built or written: a SceneError
// names the place (FILE:LINE:COLUMN, or the --set that gave the value), the
// key and the value received, e.g.
//
//   pendulum.toml:3:6: key 'time.dt': must be positive, received -0.1
//   ring_impact.toml:31:9: key 'bodies[1].material.poisson': must be in (-1, 0.5), received 0.5
//
// Unknown keys are errors with a "did you mean" suggestion, so a typo never
// silently falls back to a default. Each section has its own parse function
// in scene.cpp, listed in one table there: a new section is one entry and
// one function.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/load.hpp"
#include "core/mesh.hpp"
#include "core/system.hpp"
#include "integrators/driver.hpp"
#include "integrators/newton.hpp"
#include "integrators/statics.hpp"
#include "integrators/stepper.hpp"
#include "verify/summary.hpp"

namespace emdae {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct OutputSettings {
  int every = 1;  // a history row every `every` accepted steps (and the last)
  // VTU fields of the bodies every `vtu_every` steps (and the first and last);
  // -1: automatic (about 100 files over the run), 0: none.
  long vtu_every = -1;
};

/// A named particle of the scene and the node it became.
struct SceneParticle {
  std::string name;
  int node = -1;
  bool fixed = false;
};

/// An FE body of the scene: where its nodes went and what it is made of.
struct SceneBody {
  std::string name;
  std::string mesh;      // e.g. "ring, 64 x 1 elements, radii 47 .. 50"
  std::string material;  // Material::describe()
  int node_offset = 0, n_nodes = 0, n_elements = 0;
  double mass = 0.0;
  std::vector<std::string> node_sets, edge_sets;
  // The reference mesh and the material themselves, for the VTU fields
  // (verify/vtu.hpp: VtuBody{name, geometry, node_offset, elastic}).
  Mesh geometry;
  Material elastic;
};

/// A contact pair and the size of its surfaces.
struct SceneContact {
  std::string name, slave, master;  // "body.set"
  int slave_segments = 0, master_segments = 0, candidates = 0;
  // modified_mass = true: both surfaces' nodes are massless, their mass
  // moved within each body (core/modified_mass.hpp).
  bool modified_mass = false;
  double moved_mass = 0.0;
};

/// A [[dirichlet]] entry, for `emdae check`.
struct SceneDirichlet {
  std::string nodes;  // "body.set"
  int n_nodes = 0, n_dofs = 0;
  std::string what;  // "fixed (x, y)", "displacement [1, 0] x ramp(0, 1)"
};

/// A [[loads]] entry: what it is and the time function scaling it.
struct SceneLoad {
  std::string name, type, on;  // on: "body.set" or the body
  std::string magnitude;       // e.g. "torque 10000", "traction [0, -1]"
  std::string time_function;   // e.g. "hat(0, 0.5, peak 1)"
  TimeFunction g = TimeFunction::constant(1.0);
};

/// [statics]: an equilibrium solve before the dynamics, or the whole run of
/// a static analysis (a scene without [time]).
struct SceneStatics {
  bool enabled = false;
  StaticSettings settings;                      // settings.load_time is always set (default 0)
  std::vector<std::string> hold_names;          // "body.set"
  std::vector<std::vector<int>> hold_rotation;  // their system nodes
};

struct Scene {
  std::string name, description, source_path;
  int dimension = 2;
  std::unique_ptr<System> system;
  /// No [time], [statics] given: the run is the static solve alone (time is
  /// then unused).
  bool static_only = false;
  TimeSettings time;
  std::string scheme = "em";
  NewtonSettings newton;
  SchemeSettings scheme_settings;
  OutputSettings output;
  Tolerances tolerances;
  std::vector<SceneParticle> particles;
  std::vector<SceneBody> bodies;
  std::vector<SceneContact> contacts;
  std::vector<SceneDirichlet> dirichlet;
  std::vector<SceneLoad> loads;
  SceneStatics statics;
  /// Things that are allowed but probably not meant (with their location).
  std::vector<std::string> warnings;

  /// True when every load's time function is zero on all of [a, b] (exact:
  /// the time functions are piecewise linear), so that the energy must be
  /// conserved over a step from a to b. True without loads.
  bool loads_vanish(double a, double b) const;
};

/// A value set from outside the file: "key=value" and where it came from
/// (shown in place of FILE:LINE:COLUMN; default "--set key=value").
struct SceneOverride {
  std::string assignment;
  std::string origin;
};

/// Reads and validates the scene file at `path`. `overrides` are assignments
/// "key=value" (e.g. "time.dt=0.005", "particles[1].mass=2") applied to the
/// file's contents before validation; the value is read as TOML, or as a
/// plain string when it is not valid TOML (so "scheme.name=midpoint" works).
/// Throws SceneError.
std::unique_ptr<Scene> load_scene(const std::string& path,
                                  const std::vector<std::string>& overrides = {});

std::unique_ptr<Scene> load_scene(const std::string& path,
                                  const std::vector<SceneOverride>& overrides);

/// The same for scene text already in memory; `source_name` stands for the
/// file in messages (e.g. the built-in default scene).
std::unique_ptr<Scene> load_scene_text(std::string_view text, const std::string& source_name,
                                       const std::vector<SceneOverride>& overrides = {});

/// Closest candidate to `word` by edit distance, or "" when none is close.
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace emdae
