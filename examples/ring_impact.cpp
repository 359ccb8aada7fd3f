// The paper's two-ring impact, built and run through the library.
//
// Sample run:   ./build/release/examples/ring_impact [OUT_DIR]
//
// Description. Hesch & Betsch (mortar energy-momentum, §5.2): two St.
// Venant-Kirchhoff rings, inner radius 47, outer 50, 64 x 1 Q1 elements
// each, E = 100, nu = 0.1, rho = 0.001, fly at each other with speed 10 and
// collide off-centre; frictionless mortar contact of the left ring's outer
// surface on the right one's. It is the scene examples/ring_impact.toml,
// which `emdae` runs without arguments: this program is what the scene
// reader does with that file, written out.
//
//        left (speed 10 ->)              right (<- speed 10)
//          .--.                               .--.
//         (    )        120 apart            (    )   20 higher
//          '--'                               '--'
//
// The energy-momentum scheme conserves energy, linear and angular momentum
// for any step size, also through the impact, because every node that comes
// into contact is caught at the instant its gap closes. The program prints
// the figures that show it and exits non-zero when they are not what the
// scheme promises: it doubles as a regression test.
#include <cstdio>
#include <string>

#include "contact/contact_pair.hpp"
#include "core/model.hpp"
#include "run/run.hpp"

using namespace emdae;

int main(int argc, char** argv) {
  // 1. The model: two bodies, each a mesh and a material. add_body turns a
  //    mesh into nodes, Q1 element terms and the consistent mass, and keeps
  //    the mesh's named sets: a ring has the node and edge sets "inner" and
  //    "outer", which the model calls "left.outer", "right.outer", ...
  Model model(2);
  const Material svk = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.1, 0.001);
  BodyOptions to_the_right, to_the_left;
  to_the_right.velocity = {10.0, 0.0};
  to_the_left.velocity = {-10.0, 0.0};
  model.add_body("left", ring_mesh({-110.0, 0.0}, 47.0, 50.0, 64, 1), svk, to_the_right);
  model.add_body("right", ring_mesh({110.0, 20.0}, 47.0, 50.0, 64, 1), svk, to_the_left);

  // 2. Contact between two named surfaces is one call: the mortar gaps of
  //    the slave's nodes on the master surface, written in invariants so
  //    that the discrete gradient conserves energy and momenta.
  add_mortar_contact(model, "left.outer", "right.outer", "rings");

  // 3. The run: the scheme and its settings, the time span, where to write.
  //    A gap tolerance of 1e-10 (the Newton tolerance) is what a node may
  //    still be open by when it counts as in contact; every bit of it costs
  //    lambda times the gap in energy.
  RunSettings settings;
  settings.name = "ring_impact";
  settings.scheme = "em";
  settings.schemes.newton.tolerance = 1e-10;
  settings.schemes.newton.max_iterations = 25;
  settings.time.dt = 0.01;
  settings.time.t_end = 20.0;
  settings.output.vtu_every = 0;  // no ParaView fields: history, summary, report
  settings.out_dir = argc > 1 ? argv[1] : "out/ring_impact-cpp";

  // 4. Run it. Without an observer nothing is printed while it runs; the
  //    summary holds every figure of summary.json.
  const RunResult result = run(model, settings);
  const Summary& s = result.summary;
  std::printf("status %s after %ld steps; contact from t = %.4g to %.4g\n", s.status.c_str(),
              s.steps, s.contact && s.contact->first ? *s.contact->first : -1.0,
              s.contact && s.contact->last ? *s.contact->last : -1.0);
  std::printf("energy error %.3e, linear momentum %.3e, angular momentum %.3e\n",
              s.energy_rel_error_max, s.linear_momentum_error_max.value_or(-1.0),
              s.angular_momentum_rel_error_max.value_or(-1.0));
  std::printf("written to %s/{history.csv,summary.json,report.html,contact.csv}\n",
              settings.out_dir.c_str());

  // 5. What the scheme promises, through the impact: energy to the Newton
  //    tolerance, both momenta to round-off.
  const bool ok = result.finished() && s.contact && s.contact->first &&
                  s.energy_rel_error_max < 1e-8 &&
                  s.linear_momentum_error_max.value_or(1) < 1e-10 &&
                  s.angular_momentum_rel_error_max.value_or(1) < 1e-10;
  return ok ? 0 : 1;
}
