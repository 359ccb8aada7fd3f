#include "verify/contact_pressure.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "verify/atomic_file.hpp"
#include "verify/csv_field.hpp"

namespace emdae {

namespace {

std::string number(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  return fmt::format("{:.17g}", x);
}

}  // namespace

std::vector<std::string> contact_table_columns() {
  return {"pair", "node", "x", "y", "gap", "pressure", "weight", "force"};
}

std::vector<PairPressure> pair_pressures(const std::vector<std::string>& pairs,
                                         const std::vector<ContactNode>& nodes) {
  std::vector<PairPressure> out;
  for (const auto& name : pairs) {
    PairPressure p;
    p.pair = name;
    double sum = 0.0;
    for (const auto& n : nodes) {
      if (n.pair != name) continue;
      ++p.active_nodes;
      p.normal_force += n.force;
      p.resultant_x += n.resultant_x;
      p.resultant_y += n.resultant_y;
      sum += n.pressure;
      p.pressure_min = p.pressure_min ? std::min(*p.pressure_min, n.pressure) : n.pressure;
      p.pressure_max = p.pressure_max ? std::max(*p.pressure_max, n.pressure) : n.pressure;
    }
    if (p.active_nodes > 0) {
      p.pressure_mean = sum / p.active_nodes;
      if (std::abs(*p.pressure_mean) > 0)
        p.pressure_spread = (*p.pressure_max - *p.pressure_min) / std::abs(*p.pressure_mean);
    }
    out.push_back(p);
  }
  return out;
}

std::optional<double> max_pressure_spread(const std::vector<PairPressure>& pairs) {
  std::optional<double> out;
  for (const auto& p : pairs) {
    if (!p.pressure_spread) continue;
    // A NaN wins (once there, it stays): a broken run must not pass the check.
    const double s = *p.pressure_spread;
    if (!out || std::isnan(s) || s > *out) out = s;
  }
  return out;
}

void write_contact_table(const std::string& path, const std::vector<ContactNode>& nodes) {
  std::string text;
  const auto columns = contact_table_columns();
  for (std::size_t i = 0; i < columns.size(); ++i) text += (i ? "," : "") + columns[i];
  text += '\n';
  for (const auto& n : nodes)
    text += fmt::format("{},{},{},{},{},{},{},{}\n", csv_field(n.pair), n.node, number(n.x),
                        number(n.y), number(n.gap), number(n.pressure), number(n.weight),
                        number(n.force));
  write_atomically(path, text, "contact table");
}

}  // namespace emdae
