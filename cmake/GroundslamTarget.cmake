# One helper so that every target builds with the same strict warnings and instruction set.
# On x86-64, the POPCNT instruction (every x86-64 CPU since 2008) counts descriptor bits in one
# instruction; without it GCC calls a software popcount and Hamming matching runs several times slower.
# -Werror with GCC only: the fuzz build (clang, `make fuzz`) warns differently and is not where warnings are policed.
function(groundslam_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -Wsign-conversion -pedantic
                                           $<$<CXX_COMPILER_ID:GNU>:-Werror>)
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
    target_compile_options(${target} PRIVATE -mpopcnt)
  endif()
endfunction()

# groundslam_add_library(NAME SOURCES a.cpp ... DEPS lib ...): a static library of the installed package,
# `groundslam_<part>` in this build and `groundslam::<part>` for users (alias here, exported name when installed).
# Headers come from cpp/ in the build tree and from include/ under the install prefix.
set(GROUNDSLAM_LIBRARIES "" CACHE INTERNAL "the package's libraries")
function(groundslam_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  string(REPLACE "groundslam_" "" part ${name})
  add_library(groundslam::${part} ALIAS ${name})
  set_target_properties(${name} PROPERTIES EXPORT_NAME ${part} POSITION_INDEPENDENT_CODE ON)
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/cpp> $<INSTALL_INTERFACE:include>)
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  groundslam_set_warnings(${name})
  set(GROUNDSLAM_LIBRARIES ${GROUNDSLAM_LIBRARIES} ${name} CACHE INTERNAL "the package's libraries")
endfunction()

# Sanitizer build (`make test-sanitize`): -DGROUNDSLAM_SANITIZE=address,undefined instruments every target.
# GCC's `undefined` leaves out float-cast-overflow, so it is added; no recovery, so that any report fails
# the test that triggered it.
set(GROUNDSLAM_SANITIZE "" CACHE STRING "Comma-separated -fsanitize= list for every target (e.g. address,undefined); empty: off")
if(GROUNDSLAM_SANITIZE)
  set(groundslam_sanitize_flags -fsanitize=${GROUNDSLAM_SANITIZE} -fsanitize=float-cast-overflow -fno-sanitize-recover=all
      -fno-omit-frame-pointer)
  add_compile_options(${groundslam_sanitize_flags} -g -O2)
  add_link_options(${groundslam_sanitize_flags})
  message(STATUS "groundslam: sanitizers ${GROUNDSLAM_SANITIZE},float-cast-overflow")
endif()

# Fuzz build (`make fuzz`, clang with libFuzzer): every library instrumented for coverage and checked with
# AddressSanitizer and UndefinedBehaviorSanitizer; the fuzz executables (tests/fuzz/) link -fsanitize=fuzzer.
option(GROUNDSLAM_FUZZ "Build the libFuzzer targets of tests/fuzz (needs clang)" OFF)
if(GROUNDSLAM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "GROUNDSLAM_FUZZ needs clang (configure with -DCMAKE_CXX_COMPILER=clang++)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g)
  add_link_options(-fsanitize=address,undefined)
endif()
