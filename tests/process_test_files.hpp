// Temporary files of the process tests (tests/test_process*.cpp): one folder per test executable and
// run, removed at the end when every test passed (kept for inspection otherwise).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace livo::test {

inline std::filesystem::path tempRoot() {
  return std::filesystem::temp_directory_path() / ("livo_test_process_" + std::to_string(::getpid()));
}

struct TempCleanup : testing::Environment {
  void TearDown() override {
    if (testing::UnitTest::GetInstance()->Passed()) std::filesystem::remove_all(tempRoot());
  }
};
inline testing::Environment* const kTempCleanup = testing::AddGlobalTestEnvironment(new TempCleanup);

/// A fresh folder `name` under this run's temporary root.
inline std::string tempDir(const std::string& name) {
  const std::filesystem::path p = tempRoot() / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream is(text);
  for (std::string l; std::getline(is, l);) out.push_back(l);
  return out;
}

/// Non-empty lines of a file.
inline std::size_t countLines(const std::string& path) {
  std::size_t n = 0;
  for (const auto& l : lines(readFile(path))) n += !l.empty();
  return n;
}

}  // namespace livo::test
