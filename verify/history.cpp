#include "verify/history.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iterator>
#include <stdexcept>

namespace emdae {

std::vector<std::string> history_columns(int dim, bool external_work, bool contact) {
  std::vector<std::string> c = {"t", "dt", "kinetic", "potential", "total_energy"};
  if (external_work) c.push_back("external_work");
  if (dim == 2) {
    c.insert(c.end(), {"Lx", "Ly", "J"});
  } else {
    c.insert(c.end(), {"Lx", "Ly", "Lz", "J", "Jx", "Jy", "Jz"});
  }
  c.insert(c.end(), {"phi_max", "newton_iterations", "cutbacks", "energy_error",
                     "linear_momentum_error", "angular_momentum_error"});
  if (contact)
    c.insert(c.end(),
             {"active_contacts", "contact_events", "gap_violation_max", "penetration_max"});
  return c;
}

HistoryWriter::HistoryWriter(const std::string& path, int dim, bool external_work, bool contact)
    : path_(path), dim_(dim), external_work_(external_work), contact_(contact) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_)
    throw std::runtime_error("cannot write history '" + path + "': " + std::strerror(errno));
  const auto columns = history_columns(dim, external_work, contact);
  for (std::size_t i = 0; i < columns.size(); ++i)
    std::fprintf(file_, "%s%s", i ? "," : "", columns[i].c_str());
  std::fputc('\n', file_);
  std::fflush(file_);
}

HistoryWriter::HistoryWriter(const std::string& path, int dim, bool external_work, bool contact,
                             long offset, long rows)
    : path_(path), dim_(dim), external_work_(external_work), contact_(contact), rows_(rows) {
  file_ = std::fopen(path.c_str(), "r+");
  if (!file_ || ::ftruncate(::fileno(file_), offset) != 0 ||
      std::fseek(file_, offset, SEEK_SET) != 0)
    throw std::runtime_error("cannot go on with history '" + path + "': " + std::strerror(errno));
}

long HistoryWriter::offset() const {
  return file_ ? std::ftell(file_) : -1;
}

HistoryWriter::~HistoryWriter() {
  if (file_) std::fclose(file_);
}

void history_row(const Sample& s, int dim, bool external_work, bool contact,
                 std::vector<double>& row) {
  const Quantities& q = s.quantities;
  row.clear();
  row.insert(row.end(), {s.t, s.dt, q.kinetic, q.potential, q.total()});
  if (external_work) row.push_back(s.external_work + s.constraint_work);
  for (int d = 0; d < q.linear_momentum.size(); ++d) row.push_back(q.linear_momentum[d]);
  if (dim == 2) {
    row.push_back(q.angular_momentum[0]);
  } else {
    row.push_back(q.angular_momentum.norm());
    for (int d = 0; d < 3; ++d) row.push_back(q.angular_momentum[d]);
  }
  row.insert(row.end(),
             {q.phi_max, static_cast<double>(s.newton_iterations), static_cast<double>(s.cutbacks),
              s.energy_error, s.linear_momentum_error, s.angular_momentum_error});
  if (contact)
    row.insert(row.end(), {static_cast<double>(s.active_contacts),
                           static_cast<double>(s.contact_events), s.gap_violation, s.penetration});
}

void HistoryWriter::write(const Sample& s) {
  if (!file_) throw std::logic_error("HistoryWriter::write after close");
  history_row(s, dim_, external_work_, contact_, row_);
  // %.17g: every double read back exactly; the counts print as integers.
  // (fmt's {:.17g} writes the same characters as printf's %.17g, at a
  // fraction of its cost.)
  fmt::memory_buffer line;
  for (std::size_t i = 0; i < row_.size(); ++i)
    fmt::format_to(std::back_inserter(line), i ? ",{:.17g}" : "{:.17g}", row_[i]);
  line.push_back('\n');
  // Flushed per row: a killed run keeps its history up to the last step.
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0)
    throw std::runtime_error("cannot write history '" + path_ + "': " + std::strerror(errno));
  ++rows_;
}

void HistoryWriter::close() {
  if (!file_) return;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0)
    throw std::runtime_error("cannot close history '" + path_ + "': " + std::strerror(errno));
}

}  // namespace emdae
