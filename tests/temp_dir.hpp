// A fresh folder per test, removed afterwards: named after the test and the
// process, so that concurrent runs (two build trees, ctest -j) stay apart.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

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

}  // namespace emdae::test_systems
