// The scene reader's builder: one parse function per section, in the table
// of scene_reader.cpp; each translates its table into calls on the Model and
// fields of the RunSettings. Internal to the scene reader.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "scene/toml_fields.hpp"

namespace emdae::scene_reader {

class Builder {
 public:
  Builder(Scene& scene, const Locator& loc) : scene_(scene), loc_(loc) {}

  // scene_settings.cpp
  void parse_scene(const Fields& f);
  void parse_limits(const Fields& f);
  void parse_time(const Fields& f);
  void parse_scheme(const Fields& f);
  void parse_statics(const Fields& f);
  void parse_output(const Fields& f);
  void parse_tolerances(const Fields& f);
  // scene_particles.cpp
  void parse_particle(const Fields& f);
  void parse_spring(const Fields& f);
  void parse_link(const Fields& f);
  void parse_anchor(const Fields& f);
  void parse_gravity(const Fields& f);
  // scene_bodies.cpp
  void parse_body(const Fields& f);
  void parse_contact(const Fields& f);
  void parse_dirichlet(const Fields& f);
  void parse_load(const Fields& f);

  void finish();
  /// Refuses bodies in contact pairs that overlap at the start (without
  /// [statics] to push them apart): such a run "conserves" nothing.
  void refuse_overlap();
  /// Refuses modified masses that leave a massless node with fewer than two
  /// free nodes with mass in its elements: em and midpoint hand its forces
  /// to those nodes (integrators/step_problem.cpp) and could not start.
  void refuse_unsupported_massless();
  /// The scene has [statics] and no [time]: a static analysis.
  void set_static_only() { scene_.settings.static_only = true; }

 private:
  Model& model() { return *scene_.model; }
  const Model& model() const { return *scene_.model; }
  RunSettings& settings() { return scene_.settings; }
  void warn(const std::string& where, const std::string& what) {
    scene_.warnings.push_back(where + ": " + what);
  }
  /// Runs a call on the model; a ModelError fails at the key it names, with
  /// the value received (or at the entry, for key "").
  template <class Call>
  void model_call(const Fields& f, Call&& call) {
    try {
      call();
    } catch (const ModelError& e) {
      fail_model(f, e);
    }
  }
  [[noreturn]] void fail_model(const Fields& f, const ModelError& e) const;
  /// The particle named by the string node `n` of key `k`.
  const Particle& particle(const Fields& f, std::string_view k, const toml::node& n) const;
  /// The set "body.set" named by the string node `n` of key `k`.
  std::string set_ref(const Fields& f, std::string_view k, const toml::node& n,
                      Model::SetKind kind) const;
  std::string set_ref(const Fields& f, std::string_view k, Model::SetKind kind,
                      const std::string& expected) const {
    return set_ref(f, k, f.require(k, expected), kind);
  }
  /// A length, optional, > 0 when given.
  double optional_length(const Fields& f, std::string_view k) const {
    return f.optional_positive(k).value_or(0.0);
  }
  /// The time function under key k (constant 1 when absent).
  TimeFunction time_function(const Fields& f, std::string_view k) const;
  /// A name that is unique among `taken`, or the default.
  std::string unique_name(const Fields& f, std::vector<std::string>& taken,
                          const std::string& fallback, const char* what) const;
  Mesh mesh(const Fields& f);
  /// Adds `elements` Q1 elements to the memory estimate; fails at key k of
  /// `m` when the estimate passes limits.max_memory_mb.
  void charge_elements(const Fields& m, std::string_view k, double elements);
  Mesh generated_mesh(const Fields& m);
  Material material(const Fields& f) const;

  Scene& scene_;
  const Locator& loc_;
  // Where particles and bodies were declared, for "first defined at".
  std::map<std::string, std::string> particle_where_, body_where_;
  std::vector<std::string> contact_names_, load_names_;
  std::map<std::string, std::string> contact_where_;
  // Each contact pair's surfaces (edges as sorted global node pairs, sorted)
  // and where its keys are, for the redundant-pair check and the
  // modified-mass keys.
  struct ContactSurfaces {
    std::string name, slave, master, slave_where, mass_where;
    std::vector<std::pair<int, int>> slave_edges, master_edges;
    bool modified_mass = false;
  };
  std::vector<ContactSurfaces> contact_surfaces_;
  /// Refuses a pair whose slave surface shares a segment with an earlier
  /// pair's on a master surface that shares one too (or the earlier pair
  /// swapped): their constraints repeat each other and the contact system
  /// is singular.
  void refuse_redundant_pair(const Fields& f, ContactSurfaces& pair) const;
  // Where scheme.name was given (a static analysis does not use it).
  std::string scheme_name_where_;
};

}  // namespace emdae::scene_reader
