# Reconstruction benchmarks: one 3DGS training iteration on the CPU (benchmarks/README.md).
add_executable(bench_reconstruction ${CMAKE_CURRENT_LIST_DIR}/reconstruction_iteration.cc)
target_link_libraries(bench_reconstruction PRIVATE weathergs_reconstruction benchmark::benchmark)
target_include_directories(bench_reconstruction PRIVATE ${PROJECT_SOURCE_DIR})
