// libFuzzer entry point for one parser; the code under test is groundslam::fuzz::fuzzConfigYaml (FuzzTargets.cpp).
#include <cstddef>
#include <cstdint>

#include "FuzzTargets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  groundslam::fuzz::fuzzConfigYaml(data, size);
  return 0;
}
