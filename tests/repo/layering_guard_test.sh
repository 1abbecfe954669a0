#!/usr/bin/env bash
# The layering guard sees the truth: a part whose file includes a part it does not declare fails
# at configure time (cmake/WeatherGS.cmake), and the same part declaring it configures.
set -u
src="$1"
work=$(mktemp -d /tmp/weathergs-layering.XXXXXX)
trap 'rm -rf "$work"' EXIT
make_project() {  # $1: the needs of evaluator
  rm -rf "$work/p"; mkdir -p "$work/p/cmake" "$work/p/evaluator" "$work/p/generator"
  cp "$src/cmake/WeatherGS.cmake" "$work/p/cmake/"
  echo '#include "generator/thing.h"' > "$work/p/evaluator/uses.cc"
  echo 'int thing();' > "$work/p/generator/thing.h"
  cat > "$work/p/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.16)
project(guard CXX)
include(cmake/WeatherGS.cmake)
set(WEATHERGS_PART_NEEDS_evaluator "$1")
add_subdirectory(evaluator)
CMAKE
  echo 'weathergs_add_library(PART evaluator SOURCES uses.cc)' > "$work/p/evaluator/CMakeLists.txt"
}
fail=0
make_project ""
if cmake -S "$work/p" -B "$work/p/build" > "$work/undeclared.log" 2>&1; then
  echo "an undeclared include configured"; fail=1
elif ! tr -s " \n" " " < "$work/undeclared.log" | grep -q "includes generator/, which evaluator does not declare"; then
  echo "the configure error does not name the include:"; cat "$work/undeclared.log"; fail=1
fi
make_project "generator"
if ! cmake -S "$work/p" -B "$work/p/build" > "$work/declared.log" 2>&1; then
  echo "a declared include did not configure:"; cat "$work/declared.log"; fail=1
fi
[ $fail = 0 ] && echo "undeclared include refused at configure time; declared one accepted"
exit $fail
