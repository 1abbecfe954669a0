# Pipeline benchmarks are whole runs of external tools (Blender, COLMAP), not microbenchmarks:
#   ninja bench_capture_quick_suite      the six quick variants from an empty cache, timed
#   bench_capture_cycles_validation      the path-tracer validation of the compositor (one view)
# Numbers go to benchmarks/README.md, section "Scenes and dataset generation".
add_custom_target(bench_capture_quick_suite
  COMMAND ${CMAKE_COMMAND} -E env bash ${PROJECT_SOURCE_DIR}/benchmarks/capture_quick_suite.sh
          $<TARGET_FILE:weathergs> ${CMAKE_CURRENT_BINARY_DIR}/capture_quick_suite
  DEPENDS weathergs USES_TERMINAL)

add_executable(bench_capture_cycles_validation ${CMAKE_CURRENT_LIST_DIR}/capture_cycles_validation.cc)
target_link_libraries(bench_capture_cycles_validation PRIVATE weathergs_capture)
target_include_directories(bench_capture_cycles_validation PRIVATE ${PROJECT_SOURCE_DIR})
