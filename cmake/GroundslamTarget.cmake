# One helper so that every target builds with the same strict warnings.
function(groundslam_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -Wsign-conversion -pedantic -Werror)
endfunction()

# groundslam_add_library(NAME SOURCES a.cpp ... DEPS lib ...)
function(groundslam_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR}/cpp)
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  groundslam_set_warnings(${name})
endfunction()
