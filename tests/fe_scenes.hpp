// Scene texts with FE bodies shared by the FE scene suites (test_scene_fe,
// test_examples_fe_run): a small valid scene and the pieces its variations
// are made of.
#pragma once

#include <string>

namespace emdae::test_systems {

inline const std::string kTime = "[time]\ndt = 0.01\nt_end = 0.1\n\n";

inline std::string ring(const std::string& name, double x, const std::string& extra = "") {
  return "[[bodies]]\nname = \"" + name + "\"\n" + extra +
         "[bodies.mesh]\ntype = \"ring\"\ncentre = [" + std::to_string(x) +
         ", 0.0]\ninner_radius = 8.0\nouter_radius = 10.0\naround = 16\nthrough = 1\n"
         "[bodies.material]\nmodel = \"svk\"\nyoung = 100.0\npoisson = 0.1\ndensity = 0.001\n\n";
}

inline const std::string kRings = ring("a", -10.5, "velocity = [1.0, 0.0]\n") + ring("b", 10.5);
inline const std::string kContact = "[[contacts]]\nslave = \"a.outer\"\nmaster = \"b.outer\"\n\n";
inline const std::string kValid = kTime + kRings + kContact;
inline const std::string kTorque =
    "[[loads]]\ntype = \"torque\"\non = \"a.inner\"\ntorque = 5.0\n"
    "time_function = { type = \"hat\", start = 0.0, end = 0.05 }\n\n";

// A small static analysis ([statics], no [time]): a block pressed on another.
inline const std::string kStatic =
    "[[bodies]]\nname = \"lower\"\n"
    "mesh = { type = \"rectangle\", origin = [0.0, 0.0], width = 2.0, height = 1.0, nx = 2, "
    "ny = 1 }\nmaterial = { young = 100.0, poisson = 0.3, density = 1.0 }\n\n"
    "[[bodies]]\nname = \"upper\"\n"
    "mesh = { type = \"rectangle\", origin = [0.0, 1.0], width = 2.0, height = 1.0, nx = 3, "
    "ny = 1 }\nmaterial = { young = 100.0, poisson = 0.3, density = 1.0 }\n\n"
    "[[contacts]]\nname = \"interface\"\nslave = \"upper.bottom\"\nmaster = \"lower.top\"\n\n"
    "[[dirichlet]]\nnodes = \"lower.bottom\"\nfixed = true\ncomponents = \"y\"\n\n"
    "[[dirichlet]]\nnodes = \"upper.top\"\ndisplacement = [0.0, -0.01]\ncomponents = \"y\"\n"
    "time_function = { type = \"ramp\", start = 0.0, end = 1.0 }\n\n"
    "[statics]\nload_time = 1.0\n";

// `text` with the first `from` replaced by `to`.
inline std::string with(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

}  // namespace emdae::test_systems
