#!/usr/bin/env bash
# The commit stamp (cmake/CommitStamp.cmake, what results.json's weathergs_commit holds) is read at
# every build, not when the build folder was configured. A tiny project stamped the same way, built in
# a temporary git repository: a rebuild after a commit names the new commit, an uncommitted change
# adds -dirty, and a rebuild on the same commit relinks nothing. Then the weathergs binary: built
# after the source tree's HEAD was committed, it must name that commit.
# Arguments: source tree, cmake, CMake generator, C++ compiler, weathergs binary. 77: no git.
set -u
src="$1"; cmake="$2"; generator="$3"; cxx="$4"; wgs="$5"
command -v git > /dev/null || { echo "git not installed"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
check() {  # check WHAT GOT WANT
  if [ "$2" = "$3" ]; then echo "ok: $1 ($2)"; else echo "FAIL: $1: got '$2', expected '$3'"; fail=1; fi
}

repo="$work/repo"
mkdir -p "$repo"
git -C "$repo" init -q
git -C "$repo" config user.email stamp@test && git -C "$repo" config user.name stamp
cat > "$repo/CMakeLists.txt" << EOF
cmake_minimum_required(VERSION 3.22)
project(stamp LANGUAGES CXX)
include($src/cmake/CommitStamp.cmake)
weathergs_commit_stamp(NAME stamp_commit TEMPLATE $src/core/version.cc.in OUTPUT \${CMAKE_BINARY_DIR}/version.cc
                       SOURCE_DIR \${PROJECT_SOURCE_DIR})
add_executable(stamp main.cc \${CMAKE_BINARY_DIR}/version.cc)
target_include_directories(stamp PRIVATE $src)
add_dependencies(stamp stamp_commit)
EOF
cat > "$repo/main.cc" << 'EOF'
#include <cstdio>
#include "core/version.h"
int main() { std::puts(weathergs::source_commit()); }
EOF
echo one > "$repo/notes.txt"
printf 'build/\n' > "$repo/.gitignore"
git -C "$repo" add -A && git -C "$repo" commit -q -m one
build="$repo/build"
"$cmake" -S "$repo" -B "$build" -G "$generator" -DCMAKE_CXX_COMPILER="$cxx" > "$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; exit 1; }
stamp() { "$cmake" --build "$build" > "$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }; "$build/stamp"; }

check "first build" "$(stamp)" "$(git -C "$repo" rev-parse --short HEAD)"
marker="$work/marker"
touch "$marker"
stamp > /dev/null
check "a rebuild on the same commit relinks nothing" "$(find "$build/stamp" -newer "$marker")" ""
echo two > "$repo/notes.txt"
check "an uncommitted change" "$(stamp)" "$(git -C "$repo" rev-parse --short HEAD)-dirty"
git -C "$repo" commit -q -am two
check "a rebuild after a commit (the build folder configured before it)" "$(stamp)" \
  "$(git -C "$repo" rev-parse --short HEAD)"

# The binary itself, when the source tree is a git checkout. Built before HEAD was committed, it is
# merely out of date (another commit landed since the build), which this test cannot judge.
if head=$(git -C "$src" rev-parse --short HEAD 2> /dev/null); then
  version=$("$wgs" --version)
  built=$(echo "$version" | sed -n 's/^weathergs [^ ]* (\([0-9a-f]*\)\(-dirty\)\{0,1\})$/\1/p')
  if [ -z "$built" ]; then
    echo "FAIL: weathergs --version does not name a commit: $version"; fail=1
  elif [ "$(stat -c %Y "$wgs")" -ge "$(git -C "$src" log -1 --format=%ct HEAD)" ]; then
    check "weathergs --version, built after HEAD was committed" "$built" "$head"
  else
    echo "skipped: $wgs was built before HEAD ($head) was committed: $version"
  fi
else
  echo "skipped: $src is not a git checkout"
fi
exit $fail
