# Helpers that keep the layering honest and the test names uniform (COLMAP's CMakeHelper style).

# Which weathergs libraries each part may link. Anything else is a configure error.
set(WEATHERGS_ALLOWED_DEPS_core "")
set(WEATHERGS_ALLOWED_DEPS_evaluator "weathergs_core")
set(WEATHERGS_ALLOWED_DEPS_generator "weathergs_core")
set(WEATHERGS_ALLOWED_DEPS_reconstruction "weathergs_core")
# pipeline orchestrates whole-benchmark jobs (Blender, the generator, COLMAP): one layer above the parts.
set(WEATHERGS_ALLOWED_DEPS_pipeline "weathergs_core;weathergs_generator")

# weathergs_add_library(PART part SOURCES ... [DEPS weathergs_x ...] [EXTERNAL ...])
function(weathergs_add_library)
  cmake_parse_arguments(ARG "" "PART" "SOURCES;DEPS;EXTERNAL" ${ARGN})
  foreach(dep IN LISTS ARG_DEPS)
    if(NOT dep IN_LIST WEATHERGS_ALLOWED_DEPS_${ARG_PART})
      message(FATAL_ERROR "layering: ${ARG_PART} may not depend on ${dep} "
                          "(allowed: '${WEATHERGS_ALLOWED_DEPS_${ARG_PART}}'); see docs/architecture.md")
    endif()
  endforeach()
  set(target weathergs_${ARG_PART})
  add_library(${target} STATIC ${ARG_SOURCES})
  # Includes are spelled from the repository root: #include "core/image.h".
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} ${ARG_EXTERNAL})
  target_compile_definitions(${target} PUBLIC WEATHERGS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()

# weathergs_add_test(NAME part/name SOURCES ... DEPS ... [LABELS ...] [TIMEOUT s])
# ctest names read part/name; all tests share tests/gtest_main.cc, which fixes the seeds.
function(weathergs_add_test)
  cmake_parse_arguments(ARG "" "NAME;TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  string(REPLACE "/" "_" exe "test_${ARG_NAME}")
  add_executable(${exe} ${ARG_SOURCES} ${PROJECT_SOURCE_DIR}/tests/gtest_main.cc)
  target_link_libraries(${exe} PRIVATE ${ARG_DEPS} GTest::gtest)
  target_include_directories(${exe} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_definitions(${exe} PRIVATE
    WEATHERGS_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    WEATHERGS_BINARY="$<TARGET_FILE:weathergs>")
  add_test(NAME ${ARG_NAME} COMMAND ${exe})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  set_tests_properties(${ARG_NAME} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
  if(TARGET weathergs)
    add_dependencies(${exe} weathergs)
  endif()
endfunction()
