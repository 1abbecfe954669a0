#!/usr/bin/env bash
# ctest must see a failure as a failure even beside a skip: the test main exits 1 then, 77 for a skip
# alone, 0 when everything passed (tests/gtest_main.cc).
set -u
probe="$1"
fail=0
expect() {
  local want="$1" mode="$2"
  WEATHERGS_SKIP_PROBE="$mode" "$probe" > /dev/null 2>&1
  local got=$?
  if [ "$got" != "$want" ]; then echo "probe mode '$mode': exit $got, expected $want"; fail=1; fi
}
expect 0 ""
expect 77 skip
expect 1 skip_and_fail
[ $fail = 0 ] && echo "exit codes: pass 0, skip 77, skip + failure 1"
exit $fail
