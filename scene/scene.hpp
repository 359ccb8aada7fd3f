// Scene files: THE one place they are read.
//
// A scene is a TOML file declaring what a run needs, section by section
// (docs/scenes.md lists every key with its unit, default and range):
//
//   [scene]        name, description, dimension (2 | 3, default 2)
//   [time]         dt (> 0), t_end (>= dt), min_dt (optional, <= dt); without
//                  [time], a scene with [statics] is a static analysis
//   [scheme]       name (see known_schemes(), default "em"), newton_tolerance,
//                  newton_max_iterations, line_search; locate_impacts,
//                  gap_tolerance (contact, shared by the schemes)
//   [scheme.ida]   rtol, atol, max_order
//   [scheme.galpha] rho_inf
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
//                  fields of FE bodies every N steps; default about 100 files, 0: none),
//                  vtu_format ("binary": compressed, the default; "ascii")
//                  track = ["body.set", ...] (node sets whose trajectories are
//                  written with the particles')
//   [limits]       max_steps (default 1e7), max_memory_mb (default 4096): a run
//                  that would need more is refused before anything is built
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
// silently falls back to a default.
//
// The reader only translates: every section becomes calls on a Model
// (core/model.hpp; contact/contact_pair.hpp) and fields of RunSettings
// (run/run.hpp), which compute what the scene implies. Its pieces:
// toml_fields.hpp (the typed getters that name the place), scene_overrides.cpp
// (--set), scene_reader.cpp (the table of sections), and one builder file per
// group of sections (scene_settings.cpp, scene_particles.cpp, scene_bodies.cpp).
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/model.hpp"
#include "run/run.hpp"

namespace emdae {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A scene: the model it declares and the settings of its run.
struct Scene {
  std::unique_ptr<Model> model;
  /// Name, source, scheme and the settings of every scheme, time, statics,
  /// output and tolerances; settings.out_dir is left to the caller.
  RunSettings settings;
  /// Things that are allowed but probably not meant (with their location).
  std::vector<std::string> warnings;
  /// What a run of the scene would need, estimated before anything is built,
  /// against the limits of [limits] (the scene is refused past them).
  struct Estimate {
    long steps = 0;             // time steps (static analysis: load increments)
    double memory_bytes = 0.0;  // the model, its Jacobian and factors
    long max_steps = 0;
    double max_memory_bytes = 0.0;
  } estimate;

  System& system() { return model->system(); }
  const System& system() const { return model->system(); }
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
