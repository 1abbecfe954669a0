# Particle/fog generator: quality knobs against time (benchmarks/README.md, "Generator: particles and fog").
add_executable(bench_generator_weather ${CMAKE_CURRENT_LIST_DIR}/generator_weather_bench.cc)
target_link_libraries(bench_generator_weather PRIVATE weathergs_generator benchmark::benchmark)
target_include_directories(bench_generator_weather PRIVATE ${PROJECT_SOURCE_DIR})
