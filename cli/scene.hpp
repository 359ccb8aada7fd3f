// Scene files: THE one place they are read.
//
// A scene is a TOML file declaring what a run needs, section by section:
//
//   [scene]        name, description, dimension (2 | 3, default 2)
//   [time]         dt (> 0), t_end (>= dt), min_dt (optional, <= dt)
//   [scheme]       name (see known_schemes(), default "em"), newton_tolerance,
//                  newton_max_iterations, line_search
//   [gravity]      acceleration = [gx, gy(, gz)]: dead load m g on every free particle
//   [[particles]]  name, mass, position, velocity (default 0), fixed (default false)
//   [[springs]]    between = ["a", "b"], stiffness, rest_length, law ("linear" | "green")
//   [[links]]      between = ["a", "b"], length: rigid distance constraint
//   [[anchors]]    particle, point, length: rigid link to a fixed point
//   [output]       every (history row every N steps, default 1)
//   [tolerances]   energy_rel, linear_momentum, angular_momentum_rel, constraint
//
// Everything is validated before anything is built or written: a SceneError
// names the place (FILE:LINE:COLUMN, or the --set that gave the value), the
// key and the value received, e.g.
//
//   pendulum.toml:3:6: key 'time.dt': must be positive, received -0.1
//
// Unknown keys are errors with a "did you mean" suggestion, so a typo never
// silently falls back to a default. Each section has its own parse function
// in scene.cpp, listed in one table there: a new section (FE bodies, contact
// pairs, loads) is one entry and one function.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/system.hpp"
#include "integrators/driver.hpp"
#include "integrators/newton.hpp"
#include "verify/summary.hpp"

namespace emdae {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct OutputSettings {
  int every = 1;  // a history row every `every` accepted steps (and the last)
};

/// A named particle of the scene and the node it became.
struct SceneParticle {
  std::string name;
  int node = -1;
  bool fixed = false;
};

struct Scene {
  std::string name, description, source_path;
  int dimension = 2;
  std::unique_ptr<System> system;
  TimeSettings time;
  std::string scheme = "em";
  NewtonSettings newton;
  OutputSettings output;
  Tolerances tolerances;
  std::vector<SceneParticle> particles;
  /// Things that are allowed but probably not meant (with their location).
  std::vector<std::string> warnings;
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
