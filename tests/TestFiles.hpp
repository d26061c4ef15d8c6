#pragma once
// A fresh scratch folder per test, under the build tree.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace groundslam::testing {

inline std::filesystem::path scratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::path(GROUNDSLAM_TEST_TMP) / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

/// Runs `fn` and returns the message of the InputError it throws ("" when it does not throw).
template <class Fn>
std::string inputErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace groundslam::testing
