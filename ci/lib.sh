#!/usr/bin/env bash
# Sourced by the CI steps and the bench scripts: checks that cannot pass while what they check
# fails, and that fail when they ran nothing.

# Command substitutions run with errexit too (bash drops it there otherwise, so a failing
# command inside $(…) would not stop a script).
shopt -s inherit_errexit

# How many tests a `cargo test` log says passed, summed over its test binaries.
tests_passed() {
  grep -Eo 'test result: ok\. [0-9]+ passed' "$1" | awk '{ s += $4 } END { print s + 0 }'
}

# expect_tests N COMMAND…: runs a `cargo test` COMMAND (its output shown) and fails when it fails
# or when other than N tests passed (a renamed or filtered-out test would otherwise pass unrun).
expect_tests() {
  local want=$1; shift
  local log; log=$(mktemp)
  "$@" 2>&1 | tee "$log"
  local ran; ran=$(tests_passed "$log")
  rm -f "$log"
  if [ "$ran" -ne "$want" ]; then
    echo "expected $want tests to run, $ran ran: $*" >&2
    return 1
  fi
}

# run_ignored PACKAGE TEST_FILE [LIBTEST_ARGS…]: runs the #[ignore]d tests of one test file and
# fails unless every one of them ran and passed (their number is counted in the file).
run_ignored() {
  local package=$1 file=$2; shift 2
  local want; want=$(grep -cE '^\s*#\[ignore' "$file")
  [ "$want" -gt 0 ] || { echo "$file has no #[ignore]d test" >&2; return 1; }
  expect_tests "$want" cargo test -q -p "$package" --test "$(basename "$file" .rs)" -- --ignored "$@"
}

# A script's background processes: append their PIDs here; `clean_at_exit` stops them.
pids=()

# clean_at_exit DIR: when the script exits, however it exits, stop the processes in `pids` and
# remove DIR (a scratch folder).
clean_at_exit() {
  _scratch=$1
  trap _clean_up EXIT
}

_clean_up() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$_scratch"
}
