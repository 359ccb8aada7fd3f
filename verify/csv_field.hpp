// One CSV field (RFC 4180), for the tables emdae writes: study.csv,
// contact.csv, trajectories.csv.
#pragma once

#include <string>

namespace emdae {

/// `s` as a CSV field: quoted when it holds a separator, a quote or a line
/// break, with its quotes doubled; otherwise as it is.
inline std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace emdae
