// Scene files: every malformed input gets a SceneError naming the place
// (FILE:LINE), the key and the value received; every example scene loads and
// builds what it says; command-line overrides are validated like the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "integrators/stepper.hpp"
#include "malformed_scene.hpp"
#include "scene/scene.hpp"
#include "temp_dir.hpp"
#include "verify/recorder.hpp"
#include "verify/vtu.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

using test_systems::TempDir;

const std::string kTime = "[time]\ndt = 0.01\nt_end = 0.1\n\n";
const std::string kParticles =
    "[[particles]]\n"
    "name = \"a\"\n"
    "mass = 1.0\n"
    "position = [0.0, 0.0]\n"
    "\n"
    "[[particles]]\n"
    "name = \"b\"\n"
    "mass = 1.0\n"
    "position = [1.0, 0.0]\n"
    "\n";
const std::string kValid = kTime + kParticles;

std::string known_list() {
  std::string k;
  for (const auto& s : known_schemes()) k += (k.empty() ? "" : ", ") + s;
  return k;
}

// 1-based line of the first line of `content` containing `marker`.

using test_systems::Malformed;

std::vector<Malformed> malformed_scenes() {
  const std::string p = kParticles;
  return {
      {"negative_dt",
       "[time]\ndt = -0.1\nt_end = 1.0\n" + p,
       "dt = -0.1",
       {"key 'time.dt'", "must be positive", "received -0.1"}},
      {"zero_dt", "[time]\ndt = 0\nt_end = 1.0\n" + p, "dt = 0", {"key 'time.dt'", "received 0"}},
      {"t_end_below_dt",
       "[time]\ndt = 0.1\nt_end = 0.05\n" + p,
       "t_end",
       {"key 'time.t_end'", "at least dt = 0.1", "received 0.05"}},
      {"min_dt_above_dt",
       "[time]\ndt = 0.1\nt_end = 1\nmin_dt = 0.5\n" + p,
       "min_dt",
       {"key 'time.min_dt'", "received 0.5"}},
      // A drawing after the end of the run would never be made: an outside
      // test found such times silently ignored.
      {"snapshot_after_t_end",
       "[time]\ndt = 0.1\nt_end = 1.0\n" + p + "[output]\nsnapshots = [0.5, 2.0]\n",
       "snapshots",
       {"key 'output.snapshots'", "after time.t_end = 1.0", "received 2.0"}},
      {"dt_is_string",
       "[time]\ndt = \"fast\"\nt_end = 1\n" + p,
       "dt =",
       {"key 'time.dt'", "must be a number", "received string \"fast\""}},
      {"dt_missing", "[time]\nt_end = 1\n" + p, "[time]", {"key 'time.dt'", "missing"}},
      {"time_missing", p, "", {"key 'time'", "missing"}},
      {"unknown_key",
       "[time]\ndtt = 0.1\nt_end = 1\n" + p,
       "dtt",
       {"key 'time.dtt'", "unknown key", "did you mean 'dt'?", "received 0.1"}},
      {"unknown_section",
       kValid + "[gravty]\nacceleration = [0.0, -1.0]\n",
       "[gravty]",
       {"key 'gravty'", "did you mean 'gravity'?"}},
      {"unknown_scheme",
       kValid + "[scheme]\nname = \"rk45\"\n",
       "rk45",
       {"key 'scheme.name'", "unknown scheme", "received \"rk45\"", known_list()}},
      {"misspelt_scheme",
       kValid + "[scheme]\nname = \"midpont\"\n",
       "midpont",
       {"key 'scheme.name'", "did you mean 'midpoint'?", "received \"midpont\""}},
      {"unknown_particle",
       kValid + "[[springs]]\nbetween = [\"a\", \"c\"]\nstiffness = 1.0\n",
       "between",
       {"key 'springs[0].between'", "unknown particle", "received \"c\""}},
      {"unknown_anchor_particle",
       kValid + "[[anchors]]\nparticle = \"z\"\npoint = [0.0, 1.0]\n",
       "\"z\"",
       {"key 'anchors[0].particle'", "unknown particle", "received \"z\""}},
      {"position_too_long",
       kValid + "[[particles]]\nname = \"c\"\nmass = 1.0\nposition = [0.0, 0.0, 1.0]\n",
       "[0.0, 0.0, 1.0]",
       {"key 'particles[2].position'", "2 numbers", "received [0.0, 0.0, 1.0]"}},
      {"velocity_is_string",
       kValid +
           "[[particles]]\nname = \"c\"\nmass = 1.0\nposition = [0.0, 2.0]\nvelocity = \"up\"\n",
       "velocity",
       {"key 'particles[2].velocity'", "received string \"up\""}},
      {"duplicate_particle",
       kValid + "[[particles]]\nname = \"a\"\nmass = 1.0\nposition = [2.0, 0.0]\n",
       "name = \"a\"\nmass = 1.0\nposition = [2.0",
       {"key 'particles[2].name'", "duplicate particle name", "received \"a\"", "{path}:5:"}},
      {"zero_mass",
       kValid + "[[particles]]\nname = \"c\"\nmass = 0\nposition = [2.0, 0.0]\n",
       "mass = 0",
       {"key 'particles[2].mass'", "must be positive", "received 0"}},
      {"negative_mass",
       kValid + "[[particles]]\nname = \"c\"\nmass = -2.5\nposition = [2.0, 0.0]\n",
       "mass = -2.5",
       {"key 'particles[2].mass'", "received -2.5"}},
      {"mass_missing",
       kTime + "[[particles]]\nname = \"a\"\nposition = [0.0, 0.0]\n",
       "[[particles]]",
       {"key 'particles[0].mass'", "missing"}},
      {"self_link",
       kValid + "[[links]]\nbetween = [\"a\", \"a\"]\n",
       "between",
       {"key 'links[0].between'", "two different particles", "received [\"a\", \"a\"]"}},
      {"link_length_mismatch",
       kValid + "[[links]]\nbetween = [\"a\", \"b\"]\nlength = 2.0\n",
       "length = 2.0",
       {"key 'links[0].length'", "initial distance 1.0", "received 2.0"}},
      {"duplicate_link",
       kValid + "[[links]]\nbetween = [\"a\", \"b\"]\n\n[[links]]\nbetween = [\"b\", \"a\"]\n",
       "[\"b\", \"a\"]",
       {"key 'links[1].between'", "second rigid link", "received [\"b\", \"a\"]"}},
      {"between_not_a_pair",
       kValid + "[[springs]]\nbetween = [\"a\"]\nstiffness = 1.0\n",
       "between",
       {"key 'springs[0].between'", "two particle names", "received array [\"a\"]"}},
      {"spring_law_unknown",
       kValid + "[[springs]]\nbetween = [\"a\", \"b\"]\nstiffness = 1.0\nlaw = \"grean\"\n",
       "grean",
       {"key 'springs[0].law'", "did you mean 'green'?", "received \"grean\""}},
      {"spring_key_misspelt",
       kValid + "[[springs]]\nbetween = [\"a\", \"b\"]\nstifness = 1.0\n",
       "stifness",
       {"key 'springs[0].stifness'", "did you mean 'stiffness'?", "received 1.0"}},
      {"spring_stiffness_missing",
       kValid + "[[springs]]\nbetween = [\"a\", \"b\"]\n",
       "[[springs]]",
       {"key 'springs[0].stiffness'", "missing"}},
      {"dimension_four",
       "[scene]\ndimension = 4\n" + kValid,
       "dimension",
       {"key 'scene.dimension'", "2 or 3", "received 4"}},
      {"iterations_float",
       kValid + "[scheme]\nnewton_max_iterations = 2.5\n",
       "newton_max",
       {"key 'scheme.newton_max_iterations'", "integer", "received float 2.5"}},
      {"iterations_zero",
       kValid + "[scheme]\nnewton_max_iterations = 0\n",
       "newton_max",
       {"key 'scheme.newton_max_iterations'", "received 0"}},
      {"line_search_string",
       kValid + "[scheme]\nline_search = \"yes\"\n",
       "line_search",
       {"key 'scheme.line_search'", "true or false", "received string \"yes\""}},
      {"particles_not_array",
       kTime + "[particles]\nname = \"a\"\n",
       "[particles]",
       {"key 'particles'", "array of tables", "received a table"}},
      {"gravity_nan",
       kValid + "[gravity]\nacceleration = [nan, 0.0]\n",
       "acceleration",
       {"key 'gravity.acceleration'", "finite", "received [nan, 0.0]"}},
      {"gravity_wrong_length",
       kValid + "[gravity]\nacceleration = [0.0, -9.81, 0.0]\n",
       "acceleration",
       {"key 'gravity.acceleration'", "received [0.0, -9.81, 0.0]"}},
      {"output_every_zero",
       kValid + "[output]\nevery = 0\n",
       "every",
       {"key 'output.every'", "received 0"}},
      {"output_vtu_format_unknown",
       kValid + "[output]\nvtu_format = \"asci\"\n",
       "vtu_format",
       {"key 'output.vtu_format'", "\"binary\" or \"ascii\"", "received \"asci\"",
        "did you mean 'ascii'?"}},
      {"linear_solver_unknown",
       kValid + "[scheme]\nlinear_solver = \"umfpak\"\n",
       "umfpak",
       {"key 'scheme.linear_solver'", "unknown linear solver", "received \"umfpak\"",
        "did you mean 'umfpack'?"}},
      {"jacobian_reuse_zero",
       kValid + "[scheme]\njacobian_reuse = 0\n",
       "jacobian_reuse",
       {"key 'scheme.jacobian_reuse'", "received 0"}},
      {"jacobian_reuse_word",
       kValid + "[scheme]\njacobian_reuse = \"sometimes\"\n",
       "jacobian_reuse",
       {"key 'scheme.jacobian_reuse'", "\"auto\" or an integer", "received \"sometimes\""}},
      {"linear_solver_not_string",
       kValid + "[scheme]\nlinear_solver = 2\n",
       "linear_solver",
       {"key 'scheme.linear_solver'", "must be a string", "received integer 2"}},
      {"output_vtu_format_not_string",
       kValid + "[output]\nvtu_format = 1\n",
       "vtu_format",
       {"key 'output.vtu_format'", "must be a string", "received integer 1"}},
      {"tolerance_negative",
       kValid + "[tolerances]\nenergy_rel = -1e-9\n",
       "energy_rel",
       {"key 'tolerances.energy_rel'", "received -1e-09"}},
      {"scene_name_path",
       "[scene]\nname = \"../x\"\n" + kValid,
       "name",
       {"key 'scene.name'", "plain name", "received \"../x\""}},
      {"particle_key_misspelt",
       kTime + "[[particles]]\nname = \"a\"\nmas = 1.0\nposition = [0.0, 0.0]\n",
       "mas =",
       {"key 'particles[0].mas'", "did you mean 'mass'?", "received 1.0"}},
      {"anchor_on_fixed",
       kTime + "[[particles]]\nname = \"a\"\nposition = [0.0, 0.0]\nfixed = true\n" +
           "[[particles]]\nname = \"b\"\nmass = 1.0\nposition = [1.0, 0.0]\n" +
           "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n",
       "particle = \"a\"",
       {"key 'anchors[0].particle'", "fixed", "received \"a\""}},
      {"anchor_path_periodic_open",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0, 2.0], x = [0.0, 0.1, 0.2], interpolation = \"periodic\" "
           "}\n",
       "path = {",
       {"key 'anchors[0].path.x'", "equal first and last values", "received [0.0, 0.1, 0.2]"}},
      {"anchor_path_interpolation_unknown",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0, 2.0], y = [0.0, 0.1, 0.2], interpolation = \"spline\" }\n",
       "path = {",
       {"key 'anchors[0].path.interpolation'", "unknown interpolation", "received \"spline\""}},
      {"anchor_path_short_values",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0, 2.0], x = [0.0, 0.1] }\n",
       "path = {",
       {"key 'anchors[0].path.x'", "as many entries as times (3)"}},
      {"anchor_path_times_not_increasing",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0, 1.0], x = [0.0, 0.1, 0.2] }\n",
       "path = {",
       {"key 'anchors[0].path.times'", "increase strictly", "received [0.0, 1.0, 1.0]"}},
      {"anchor_path_too_few_times",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0], x = [0.0, 0.1] }\n",
       "path = {",
       {"key 'anchors[0].path.times'", "at least 3 times for cubic", "received [0.0, 1.0]"}},
      {"anchor_path_not_a_table",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\npath = [0.0, 1.0]\n",
       "path = [",
       {"key 'anchors[0].path'", "must be a table", "received array [0.0, 1.0]"}},
      {"anchor_path_z_in_2d",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\n" +
           "path = { times = [0.0, 1.0, 2.0], z = [0.0, 0.1, 0.2] }\n",
       "path = {",
       {"key 'anchors[0].path.z'", "unknown key", "received [0.0, 0.1, 0.2]"}},
      {"anchor_path_length_not_the_distance",
       kValid + "[[anchors]]\nparticle = \"a\"\npoint = [0.0, 1.0]\nlength = 2.0\n" +
           "path = { times = [0.0, 1.0, 2.0], x = [0.0, 0.1, 0.2] }\n",
       "length = 2.0",
       {"key 'anchors[0].length'", "received 2.0"}},
      {"all_fixed",
       kTime + "[[particles]]\nname = \"a\"\nposition = [0.0, 0.0]\nfixed = true\n",
       "[[particles]]",
       {"key 'particles'", "every particle is fixed"}},
      // The place named is the first particle of the file, whatever its name.
      {"all_fixed_first_declared",
       kTime + "[[particles]] # z\nname = \"z\"\nposition = [0.0, 0.0]\nfixed = true\n" +
           "[[particles]]\nname = \"a\"\nposition = [1.0, 0.0]\nfixed = true\n",
       "[[particles]] # z",
       {"key 'particles'", "every particle is fixed"}},
      {"coincident_spring",
       kValid + "[[particles]]\nname = \"c\"\nmass = 1.0\nposition = [0.0, 0.0]\n" +
           "[[springs]]\nbetween = [\"a\", \"c\"]\nstiffness = 1.0\n",
       "[[springs]]",
       {"key 'springs[0].rest_length'", "same point"}},
      {"syntax_error", "[time\ndt = 0.1\n", "[time", {"TOML syntax error"}},
      {"redefined_key",
       "[time]\ndt = 0.1\ndt = 0.2\nt_end = 1\n" + p,
       "dt = 0.2",
       {"cannot redefine"}},
      {"empty_file", "", "", {"empty"}},
      {"only_comments", "# nothing here\n\n", "", {"empty"}},
      {"binary_file",
       std::string("\x7f"
                   "ELF\x02\x01\x01\0\0\0\0",
                   12) +
           "junk",
       "ELF",
       {"not a text file"}},
      {"not_utf8", "[scene]\nname = \"caf\xe9\"\n", "name", {"not UTF-8"}},
  };
}

class MalformedScene : public ::testing::TestWithParam<Malformed> {};

TEST_P(MalformedScene, ErrorNamesFileLineKeyAndValue) {
  TempDir dir;
  test_systems::expect_located_scene_error(dir, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Scenes, MalformedScene, ::testing::ValuesIn(malformed_scenes()),
                         [](const auto& param_info) { return param_info.param.name; });

TEST(Scene, MalformedCasesAreMany) {
  EXPECT_GE(malformed_scenes().size(), 20u);
}

TEST(Scene, MissingFileNamesThePath) {
  const std::string path = (fs::temp_directory_path() / "emdae_no_such_scene.toml").string();
  try {
    load_scene(path);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
}

TEST(Scene, DirectoryIsNotAScene) {
  TempDir dir;
  EXPECT_THROW(load_scene(dir.path().string()), SceneError);
}

// --- what a valid scene builds ----------------------------------------------------

TEST(Scene, DefaultsApply) {
  TempDir dir;
  const auto scene = load_scene(dir.write("min.toml", kValid));
  EXPECT_EQ(scene->settings.name, "min");  // the file's stem without [scene] name
  EXPECT_EQ(scene->model->dim(), 2);
  EXPECT_EQ(scene->settings.scheme, "em");
  EXPECT_DOUBLE_EQ(scene->settings.time.dt, 0.01);
  EXPECT_DOUBLE_EQ(scene->settings.time.t_end, 0.1);
  EXPECT_EQ(scene->settings.time.min_dt, 0.0);
  EXPECT_DOUBLE_EQ(scene->settings.schemes.newton.tolerance, 1e-10);
  EXPECT_EQ(scene->settings.schemes.newton.max_iterations, 20);
  EXPECT_FALSE(scene->settings.schemes.newton.line_search);
  EXPECT_EQ(scene->settings.schemes.newton.jacobian_reuse, NewtonSettings::kAutoReuse);
  EXPECT_EQ(scene->settings.output.every, 1);
  EXPECT_EQ(scene->settings.output.vtu_format, VtuFormat::Binary);
  EXPECT_FALSE(scene->settings.tolerances.any());
  EXPECT_EQ(scene->system().n_nodes(), 2);
  EXPECT_EQ(scene->system().n_constraints(), 0);
  EXPECT_TRUE(scene->system().potentials().empty());
  EXPECT_TRUE(scene->warnings.empty());
  EXPECT_TRUE(scene->system().initial_velocities().isZero());
}

TEST(Scene, JacobianReuseIsAutoOrACount) {
  TempDir dir;
  const auto word =
      load_scene(dir.write("a.toml", kValid + "[scheme]\njacobian_reuse = \"auto\"\n"));
  EXPECT_EQ(word->settings.schemes.newton.jacobian_reuse, NewtonSettings::kAutoReuse);
  const auto count = load_scene(dir.write("c.toml", kValid + "[scheme]\njacobian_reuse = 3\n"));
  EXPECT_EQ(count->settings.schemes.newton.jacobian_reuse, 3);
}

TEST(Scene, EmptyListOfSpringsIsAllowed) {
  TempDir dir;
  const auto scene = load_scene(dir.write("e.toml", "springs = []\n" + kValid));
  EXPECT_TRUE(scene->system().potentials().empty());
}

TEST(Scene, SnapshotsUpToTheEndOfTheRunAreAccepted) {
  TempDir dir;
  const std::string path =
      dir.write("s.toml", "[time]\ndt = 0.1\nt_end = 1.0\n" + kParticles +
                              "[output]\nsnapshots = [0.0, 0.5, 1.0000000001]\n");
  EXPECT_EQ(load_scene(path)->settings.output.snapshots.size(), 3u);
}

TEST(Scene, IntegersAreAcceptedAsNumbers) {
  TempDir dir;
  const auto scene =
      load_scene(dir.write("ints.toml", "[time]\ndt = 1\nt_end = 10\n" + kParticles));
  EXPECT_EQ(scene->settings.time.dt, 1.0);
  EXPECT_EQ(scene->settings.time.t_end, 10.0);
}

TEST(Scene, RestLengthAndLinkLengthDefaultToInitialDistance) {
  TempDir dir;
  const auto scene = load_scene(dir.write(
      "lengths.toml", kValid + "[[particles]]\nname = \"c\"\nmass = 2.0\nposition = [1.0, 2.0]\n"
                               "[[springs]]\nbetween = [\"a\", \"c\"]\nstiffness = 3.0\n"
                               "[[links]]\nbetween = [\"a\", \"b\"]\n"));
  const System& s = scene->system();
  ASSERT_EQ(s.potentials().size(), 1u);
  ASSERT_EQ(s.constraints().size(), 1u);
  // At rest length and with the link satisfied, energy and residual vanish.
  const Vec q = s.initial_positions();
  EXPECT_NEAR(potential_energy(s, q, 0.0), 0.0, 1e-14);
  EXPECT_NEAR(constraint_residual(s, q, 0.0), 0.0, 1e-14);
}

TEST(Scene, GravityLoadsOnlyFreeParticles) {
  TempDir dir;
  const auto scene = load_scene(
      dir.write("g.toml", kTime + "[gravity]\nacceleration = [0.0, -9.81]\n" +
                              "[[particles]]\nname = \"p\"\nposition = [0.0, 0.0]\nfixed = true\n" +
                              "[[particles]]\nname = \"q\"\nmass = 2.0\nposition = [1.0, 0.0]\n"));
  EXPECT_EQ(scene->system().potentials().size(), 1u);
  EXPECT_EQ(scene->system().prescribed().size(), 2u);
  EXPECT_FALSE(scene->system().symmetry().translation);
}

TEST(Scene, ZeroGravityKeepsSymmetry) {
  TempDir dir;
  const auto scene =
      load_scene(dir.write("g0.toml", kValid + "[gravity]\nacceleration = [0.0, 0.0]\n"));
  EXPECT_TRUE(scene->system().potentials().empty());
  EXPECT_TRUE(scene->system().symmetry().translation);
}

TEST(Scene, InconsistentLinkVelocityWarns) {
  TempDir dir;
  const auto scene = load_scene(dir.write(
      "warn.toml", kTime + "[[particles]]\nname = \"a\"\nmass = 1.0\nposition = [0.0, 0.0]\n" +
                       "[[particles]]\nname = \"b\"\nmass = 1.0\nposition = [1.0, 0.0]\n" +
                       "velocity = [1.0, 0.0]\n[[links]]\nbetween = [\"a\", \"b\"]\n"));
  ASSERT_EQ(scene->warnings.size(), 1u);
  EXPECT_NE(scene->warnings[0].find("warn.toml:"), std::string::npos);
}

TEST(Scene, TextWithSourceName) {
  const auto scene = load_scene_text(kValid, "<built-in>");
  EXPECT_EQ(scene->settings.source, "<built-in>");
  try {
    load_scene_text("[time]\ndt = -1\nt_end = 1\n" + kParticles, "<built-in>");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("<built-in>:2:"), std::string::npos) << e.what();
  }
}

// --- overrides -------------------------------------------------------------------

TEST(SceneOverrides, ReplaceAndAddValues) {
  TempDir dir;
  const std::string path = dir.write("o.toml", kValid);
  const auto scene = load_scene(
      path, {"time.dt=0.005", "scheme.name=midpoint", "particles[1].mass=3",
             "gravity.acceleration=[0, -1]", "output.every = 5", "output.vtu_format=ascii"});
  EXPECT_DOUBLE_EQ(scene->settings.time.dt, 0.005);
  EXPECT_EQ(scene->settings.scheme, "midpoint");
  EXPECT_DOUBLE_EQ(scene->system().lumped_mass()[2], 3.0);
  EXPECT_EQ(scene->system().potentials().size(), 2u);
  EXPECT_EQ(scene->settings.output.every, 5);
  EXPECT_EQ(scene->settings.output.vtu_format, VtuFormat::Ascii);
}

TEST(SceneOverrides, AreValidatedAndNamed) {
  TempDir dir;
  const std::string path = dir.write("o.toml", kValid);
  const auto message = [&](const std::string& assignment) {
    try {
      load_scene(path, {assignment});
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = message("time.dt=-0.1");
  EXPECT_NE(m.find("--set time.dt=-0.1: key 'time.dt': must be positive, received -0.1"),
            std::string::npos)
      << m;
  m = message("time.dtt=0.1");
  EXPECT_NE(m.find("did you mean 'dt'?"), std::string::npos) << m;
  m = message("particles[7].mass=1");
  EXPECT_NE(m.find("'particles' has 2 entries"), std::string::npos) << m;
  m = message("particles.mass=1");
  EXPECT_NE(m.find("particles[0].mass"), std::string::npos) << m;
  m = message("no_equals_sign");
  EXPECT_NE(m.find("expected key=value"), std::string::npos) << m;
  m = message("time.dt=");
  EXPECT_NE(m.find("missing value"), std::string::npos) << m;
  m = message("time.dt=abc");
  EXPECT_NE(m.find("received string \"abc\""), std::string::npos) << m;
  try {
    load_scene(path, std::vector<SceneOverride>{{"time.dt=0", "--dt 0"}});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--dt 0: key 'time.dt'", 0), 0u) << e.what();
  }
}

// A value from the command line that makes another key of the file wrong:
// the file's line of that key is blamed, and the message says which value
// came from where (an outside test found the --set unnamed).
TEST(SceneOverrides, AValueThatMakesAFileValueWrongIsNamed) {
  TempDir dir;
  const std::string path = dir.write("o.toml", kValid);
  const auto message = [&](const std::vector<SceneOverride>& overrides) {
    try {
      load_scene(path, overrides);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // t_end = 0.1 in the file, on line 3, is below a dt of 0.5.
  std::string m = message({{"scheme.name=midpoint", ""}, {"time.dt=0.5", ""}});
  EXPECT_NE(m.find(path + ":3:"), std::string::npos) << m;
  EXPECT_NE(m.find("key 'time.t_end'"), std::string::npos) << m;
  EXPECT_NE(m.find("(time.dt came from --set time.dt=0.5)"), std::string::npos) << m;
  EXPECT_EQ(m.find("scheme.name"), std::string::npos) << "not a part of it: " << m;
  m = message({{"time.dt=0.5", "--dt 0.5"}});
  EXPECT_NE(m.find("(time.dt came from --dt 0.5)"), std::string::npos) << m;
  // Another table, named in the message.
  m = message({{"limits.max_steps=5", ""}});
  EXPECT_NE(m.find("key 'time.dt'"), std::string::npos) << m;
  EXPECT_NE(m.find("(limits.max_steps came from --set limits.max_steps=5)"), std::string::npos)
      << m;
  // An error of the file alone names no override.
  const std::string bad = dir.write("bad.toml", kValid + "[output]\nevery = 0\n");
  try {
    load_scene(bad, std::vector<SceneOverride>{{"scheme.name=midpoint", ""}});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()).find("came from"), std::string::npos) << e.what();
  }
}

TEST(Scene, ClosestMatch) {
  EXPECT_EQ(closest_match("dtt", {"dt", "t_end", "min_dt"}), "dt");
  EXPECT_EQ(closest_match("lenght", {"length", "between"}), "length");
  EXPECT_EQ(closest_match("DT", {"dt", "t_end"}), "dt");
  EXPECT_EQ(closest_match("xyzzy", {"dt", "t_end"}), "");
  EXPECT_EQ(closest_match("newton_tol", {"name", "newton_tolerance"}), "newton_tolerance");
}

// --- the example scenes ----------------------------------------------------------

std::string example(const std::string& name) {
  return std::string(EMDAE_EXAMPLES_DIR) + "/" + name + ".toml";
}

TEST(Examples, DoublePendulum) {
  const auto scene = load_scene(example("double_pendulum"));
  const System& s = scene->system();
  EXPECT_EQ(scene->settings.name, "double_pendulum");
  EXPECT_EQ(s.dim(), 2);
  EXPECT_EQ(s.n_nodes(), 2);
  EXPECT_EQ(s.n_dofs(), 4);
  EXPECT_EQ(s.n_constraints(), 2);       // anchor + link
  EXPECT_EQ(s.potentials().size(), 2u);  // gravity on both
  EXPECT_TRUE(s.prescribed().empty());
  EXPECT_FALSE(s.symmetry().translation);
  EXPECT_EQ(scene->settings.scheme, "em");
  EXPECT_TRUE(scene->warnings.empty());
}

TEST(Examples, ElasticPendulum) {
  const auto scene = load_scene(example("elastic_pendulum"));
  const System& s = scene->system();
  EXPECT_EQ(s.dim(), 2);
  EXPECT_EQ(s.n_nodes(), 2);
  EXPECT_EQ(s.prescribed().size(), 2u);  // the pivot
  EXPECT_EQ(s.n_constraints(), 0);
  EXPECT_EQ(s.potentials().size(), 2u);                        // spring + gravity on the bob
  EXPECT_FALSE(s.potentials()[0]->quadratic_in_invariants());  // the "linear" law
}

TEST(Examples, FourParticle) {
  const auto scene = load_scene(example("four_particle"));
  const System& s = scene->system();
  EXPECT_EQ(s.dim(), 3);
  EXPECT_EQ(s.n_nodes(), 4);
  EXPECT_EQ(s.n_dofs(), 12);
  EXPECT_EQ(s.n_constraints(), 2);
  EXPECT_EQ(s.potentials().size(), 4u);
  EXPECT_TRUE(s.symmetry().translation);
  EXPECT_TRUE(s.symmetry().rotation);
  EXPECT_TRUE(scene->warnings.empty());  // rigid-motion velocities keep the links
  // Spinning and drifting: both momenta non-zero.
  const State st = initial_state(s);
  const Quantities q = measure(s, st.q, st.v, 0.0);
  EXPECT_GT(q.linear_momentum.norm(), 0.1);
  EXPECT_GT(q.angular_momentum.norm(), 0.1);
  EXPECT_TRUE(scene->settings.tolerances.any());
}

TEST(Examples, StiffPendulum) {
  const auto scene = load_scene(example("stiff_pendulum"));
  const System& s = scene->system();
  EXPECT_EQ(s.n_nodes(), 2);
  EXPECT_EQ(s.potentials().size(), 2u);
  // k L / (m g) = 1e6 and dt far beyond the spring's period 2 pi sqrt(m/k).
  const double k = 9.81e6, m = 1.0;
  const double pi = 3.141592653589793;
  EXPECT_GT(scene->settings.time.dt, 10 * 2 * pi * std::sqrt(m / k));
  // The spring's energy at a small radial stretch delta is k/2 delta^2.
  const Term& spring = *s.potentials()[0];
  ASSERT_EQ(spring.n_local(), 4);
  Vec local(4);
  const Vec q0 = s.initial_positions();
  for (int i = 0; i < 4; ++i) local[i] = q0[spring.dofs()[static_cast<std::size_t>(i)]];
  const double delta = 1e-4;
  const Eigen::Vector2d r = (local.tail<2>() - local.head<2>()).normalized();
  local.tail<2>() += delta * r;
  EXPECT_NEAR(spring.value(local, 0.0), 0.5 * k * delta * delta, 1e-6 * k * delta * delta);
}

}  // namespace
}  // namespace emdae
