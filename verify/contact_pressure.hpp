// The contact pressure of a run's last state: contact.csv (one row per active
// slave node) and the per-pair figures of summary.json ("contact_pressure").
//
// contact.csv columns (full precision, %.17g; "inf" for a gap with nothing
// opposite any more):
//
//   pair,node,x,y,gap,pressure,weight,force
//
// pair: the contact's name; node: the slave node's index in its body's mesh
// (also its point index within that body in the VTU fields); x, y: its
// current position; gap: Phi_A, its normalized weighted gap; pressure: p_A =
// -lambda_A / W_A, W_A its mortar weight in the reference configuration:
// the contact pressure as a force per current length (positive:
// compressive), the nodal value of p = sum N_A p_A, whose work against the
// current surface's shape functions gives the contact's nodal forces
// (contact/mortar_contact.hpp); weight: w_A = int N_A dgamma over the node's
// mortar segments in the current configuration; force: f_A = p_A w_A, the
// node's share of the normal force. Rows by pair (in the scene's order), then
// along the slave surface.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace emdae {

/// One active slave node: a row of contact.csv.
struct ContactNode {
  std::string pair;
  int node = 0;
  double x = 0.0, y = 0.0, gap = 0.0, pressure = 0.0, weight = 0.0, force = 0.0;
  // -p_A int N_A n dgamma, the force on the slave through this node (not in
  // contact.csv; summed into PairPressure::resultant).
  double resultant_x = 0.0, resultant_y = 0.0;
};

/// The figures of one contact pair; the pressure figures are empty without
/// an active node, the spread also when the mean pressure is zero.
struct PairPressure {
  std::string pair;
  int active_nodes = 0;
  double normal_force = 0.0;  // sum of f_A = p_A w_A (current weights)
  // The resultant contact force on the slave body, sum of -p_A int N_A n
  // dgamma: normal_force times the mean of -n; equal to it for a flat contact.
  double resultant_x = 0.0, resultant_y = 0.0;
  std::optional<double> pressure_min, pressure_max;
  std::optional<double> pressure_mean;    // over the active nodes
  std::optional<double> pressure_spread;  // (max - min) / |mean|
};

/// The figures of each pair in `pairs` (in that order) from its rows.
std::vector<PairPressure> pair_pressures(const std::vector<std::string>& pairs,
                                         const std::vector<ContactNode>& nodes);

/// The largest pressure spread over the pairs, empty when no pair has one.
std::optional<double> max_pressure_spread(const std::vector<PairPressure>& pairs);

/// Writes contact.csv to `path` atomically; throws std::runtime_error naming
/// the path when it cannot.
void write_contact_table(const std::string& path, const std::vector<ContactNode>& nodes);

/// The column names of contact.csv.
std::vector<std::string> contact_table_columns();

}  // namespace emdae
