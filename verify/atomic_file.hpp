// Every file a run writes whole (summary, report, study tables, contact
// table, VTU pieces) is written to a temporary file in the same folder and
// renamed into place, so that a reader never sees half a file and a failed
// write leaves the previous one.
#pragma once

#include <string>

namespace emdae {

/// Writes `content` to `path` atomically; throws std::runtime_error naming
/// `what` ("summary", "report", ...), the file and the system's reason.
void write_atomically(const std::string& path, const std::string& content, const char* what);

}  // namespace emdae
