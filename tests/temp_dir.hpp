// Helpers of the suites that run the emdae command: a fresh folder per test,
// removed afterwards (named after the test and the process, so that
// concurrent runs stay apart), a shell command with its output, the command
// itself (where the suite defines EMDAE_EXE), the example scenes (where it
// defines EMDAE_EXAMPLES_DIR) and readers of what a run wrote.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace emdae::test_systems {

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("emdae_") + std::to_string(::getpid()) + "_" +
                       info->test_suite_name() + "_" + info->name();
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// Writes `content` to `file` in the folder; returns its path.
  std::string write(const std::string& file, const std::string& content) const {
    std::ofstream(path_ / file, std::ios::binary) << content;
    return (path_ / file).string();
  }
  const std::filesystem::path& path() const { return path_; }
  std::string operator/(const std::string& p) const { return (path_ / p).string(); }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int code = -1;
  std::string output;  // stdout and stderr together
};

/// Runs `cmd` through the shell, capturing stdout and stderr together.
inline CommandResult shell(const std::string& cmd) {
  CommandResult r;
  FILE* pipe = ::popen((cmd + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
  const int status = ::pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// `s` as one shell word.
inline std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

#ifdef EMDAE_EXAMPLES_DIR
/// The path of examples/<name>.toml.
inline std::string example(const std::string& name) {
  return std::string(EMDAE_EXAMPLES_DIR) + "/" + name + ".toml";
}
#endif

#ifdef EMDAE_EXE
/// Runs the emdae executable with `args` through the shell from folder `cwd`.
inline CommandResult emdae(const std::string& args, const std::filesystem::path& cwd =
                                                        std::filesystem::temp_directory_path()) {
  return shell("cd " + quote(cwd.string()) + " && " + quote(EMDAE_EXE) + " " + args);
}
#endif

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::vector<std::string> read_lines(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The value of attribute `name` in the XML tag that starts `tag`; empty where
// the tag has no such attribute.
inline std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const std::size_t p = tag.find(key);
  if (p == std::string::npos || p > tag.find('>')) return "";
  const std::size_t b = p + key.size();
  return tag.substr(b, tag.find('"', b) - b);
}

}  // namespace emdae::test_systems
