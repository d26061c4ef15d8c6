# One helper so that every target builds with the same strict warnings and instruction set.
# On x86-64, the POPCNT instruction (every x86-64 CPU since 2008) counts descriptor bits in one
# instruction; without it GCC calls a software popcount and Hamming matching runs several times slower.
function(groundslam_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -Wsign-conversion -pedantic -Werror)
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
    target_compile_options(${target} PRIVATE -mpopcnt)
  endif()
endfunction()

# groundslam_add_library(NAME SOURCES a.cpp ... DEPS lib ...)
function(groundslam_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR}/cpp)
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  groundslam_set_warnings(${name})
endfunction()
