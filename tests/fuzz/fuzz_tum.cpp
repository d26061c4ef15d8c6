// libFuzzer entry point for one parser; the code under test is groundslam::fuzz::fuzzTum (FuzzTargets.cpp).
#include <cstddef>
#include <cstdint>

#include "FuzzTargets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  groundslam::fuzz::fuzzTum(data, size);
  return 0;
}
