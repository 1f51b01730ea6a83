// A test fixture with a fresh, empty folder per test, removed afterwards, so tests that write
// files neither see each other's files nor leave any behind. CTest runs the tests of one binary
// in parallel processes: the folder's name holds the test's own name and the process id.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace sb::test_support {

class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');  // parameterised tests: "Suite/Name/0"
    dir_ = std::filesystem::temp_directory_path() /
           ("softbody_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A path inside the test's folder.
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Writes `bytes` to path(name), replacing what was there.
  void write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary | std::ios::trunc) << bytes;
  }
  // The whole file at p ("" if it cannot be read).
  static std::string contents(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  std::filesystem::path dir_;
};

}  // namespace sb::test_support
