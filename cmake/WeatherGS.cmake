# Helpers that keep the layering honest and the test names uniform (COLMAP's CMakeHelper style).

# The parts in build order (a part comes after every part it needs), and the parts each one needs.
# A part's libraries may link exactly the parts it needs (and core); anything else is a configure
# error (docs/architecture.md).
set(WEATHERGS_ALL_PARTS evaluator generator reconstruction restoration nerf capture adaptation methods)
set(WEATHERGS_PART_NEEDS_evaluator "")
set(WEATHERGS_PART_NEEDS_generator "")
set(WEATHERGS_PART_NEEDS_reconstruction "")
set(WEATHERGS_PART_NEEDS_restoration "")
set(WEATHERGS_PART_NEEDS_nerf "")
# capture makes whole benchmark datasets (Blender, the generator, COLMAP): one layer above the generator.
set(WEATHERGS_PART_NEEDS_capture "generator")
# adaptation fine-tunes restoration's networks to a dataset on effects the generator renders (the
# LED on new lens drops), so that restoration itself never depends on the generator.
set(WEATHERGS_PART_NEEDS_adaptation "restoration;generator")
# methods runs whole methods on datasets (train, render, evaluate; COLMAP points when a dataset has
# none; the LED adapted to the dataset by adaptation/): the top library layer, below
# apps only.
set(WEATHERGS_PART_NEEDS_methods "reconstruction;restoration;nerf;evaluator;capture;adaptation")

set(WEATHERGS_ALLOWED_DEPS_core "")
foreach(part IN LISTS WEATHERGS_ALL_PARTS)
  set(WEATHERGS_ALLOWED_DEPS_${part} "weathergs_core")
  foreach(need IN LISTS WEATHERGS_PART_NEEDS_${part})
    list(APPEND WEATHERGS_ALLOWED_DEPS_${part} weathergs_${need})
  endforeach()
endforeach()

# weathergs_resolve_parts(OUT requested...): the requested parts plus everything they need, in build
# order. Unknown part names are configure errors.
function(weathergs_resolve_parts out)
  set(wanted ${ARGN})
  set(changed TRUE)
  while(changed)
    set(changed FALSE)
    foreach(part IN LISTS wanted)
      if(NOT part IN_LIST WEATHERGS_ALL_PARTS)
        message(FATAL_ERROR "WEATHERGS_PARTS: unknown part '${part}' (known: ${WEATHERGS_ALL_PARTS})")
      endif()
      foreach(need IN LISTS WEATHERGS_PART_NEEDS_${part})
        if(NOT need IN_LIST wanted)
          list(APPEND wanted ${need})
          set(changed TRUE)
        endif()
      endforeach()
    endforeach()
  endwhile()
  set(ordered "")
  foreach(part IN LISTS WEATHERGS_ALL_PARTS)
    if(part IN_LIST wanted)
      list(APPEND ordered ${part})
    endif()
  endforeach()
  set(${out} ${ordered} PARENT_SCOPE)
endfunction()

# weathergs_add_library(PART part SOURCES ... [DEPS weathergs_x ...] [EXTERNAL ...])
function(weathergs_add_library)
  cmake_parse_arguments(ARG "" "PART" "SOURCES;DEPS;EXTERNAL" ${ARGN})
  foreach(dep IN LISTS ARG_DEPS)
    if(NOT dep IN_LIST WEATHERGS_ALLOWED_DEPS_${ARG_PART})
      message(FATAL_ERROR "layering: ${ARG_PART} may not depend on ${dep} "
                          "(allowed: '${WEATHERGS_ALLOWED_DEPS_${ARG_PART}}'); see docs/architecture.md")
    endif()
  endforeach()
  # What the part's files include must be what it declares: core, itself, or a part it needs.
  file(GLOB part_files ${CMAKE_CURRENT_SOURCE_DIR}/*.h ${CMAKE_CURRENT_SOURCE_DIR}/*.cc
       ${CMAKE_CURRENT_SOURCE_DIR}/*/*.h ${CMAKE_CURRENT_SOURCE_DIR}/*/*.cc)
  foreach(f IN LISTS part_files)
    file(STRINGS ${f} includes REGEX "^#include \"[a-z_]+/")
    foreach(line IN LISTS includes)
      string(REGEX REPLACE "^#include \"([a-z_]+)/.*" "\\1" included "${line}")
      if(NOT included STREQUAL "core" AND NOT included STREQUAL ARG_PART AND
         NOT included IN_LIST WEATHERGS_PART_NEEDS_${ARG_PART})
        message(FATAL_ERROR "layering: ${f} includes ${included}/, which ${ARG_PART} does not declare "
                            "(cmake/WeatherGS.cmake: WEATHERGS_PART_NEEDS_${ARG_PART}); see docs/architecture.md")
      endif()
    endforeach()
  endforeach()
  set(target weathergs_${ARG_PART})
  add_library(${target} STATIC ${ARG_SOURCES})
  # Includes are spelled from the repository root: #include "core/image.h".
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} ${ARG_EXTERNAL})
  # No source-tree paths in libraries or the binary: data is found through apps/resources.h.
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
    WEATHERGS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    WEATHERGS_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    WEATHERGS_BINARY="$<TARGET_FILE:weathergs>")
  add_test(NAME ${ARG_NAME} COMMAND ${exe})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  if(WEATHERGS_SANITIZE)
    # ASan + UBSan run 3-5x slower (the trainer test took > 600 s): the limits scale with them.
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * 5")
    target_compile_definitions(${exe} PRIVATE WEATHERGS_SANITIZED=1)
  endif()
  # tests/gtest_main.cc exits 77 when no test failed and one skipped (GTEST_SKIP: a missing tool), so
  # ctest reports a skip as skipped and a failure beside a skip as failed.
  set_tests_properties(${ARG_NAME} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}" SKIP_RETURN_CODE 77)
  if(TARGET weathergs)
    add_dependencies(${exe} weathergs)
  endif()
endfunction()
