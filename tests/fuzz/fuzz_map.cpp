// libFuzzer entry point for one parser; the code under test is groundslam::fuzz::fuzzMap (FuzzTargets.cpp).
#include <cstddef>
#include <cstdint>

#include "FuzzTargets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  groundslam::fuzz::fuzzMap(data, size);
  return 0;
}
