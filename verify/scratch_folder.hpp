// A private scratch folder under the system's temporary directory, removed
// with everything in it when the object goes: gnuplot's inputs and outputs
// (verify/plot.cpp), the runs of an MPI rank other than 0 before they travel
// to rank 0 (cli/compare_command.cpp).
#pragma once

#include <stdlib.h>  // mkdtemp

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace emdae {

class ScratchFolder {
 public:
  /// A new folder <tmp>/emdae-<tag>-XXXXXX; throws std::runtime_error saying
  /// what it was `for_what` when it cannot be made.
  ScratchFolder(const std::string& tag, const std::string& for_what) {
    std::string pattern =
        (std::filesystem::temp_directory_path() / ("emdae-" + tag + "-XXXXXX")).string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a scratch folder" + for_what + ": " +
                               std::strerror(errno));
    path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace emdae
