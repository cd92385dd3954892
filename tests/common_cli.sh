# Shared by the tests/cli_*.sh scripts: sourced, not run (its name keeps it
# out of the cli_*.sh glob that makes ctest tests).
#
# A script counts checks with ok / bad and ends with `cli_finish NAME`, which
# exits 0 (all passed), 1 (a check failed) or 77 (skipped: ctest reports it,
# and scripts/test.sh fails on it where the dependencies are installed).
# Skipping is decided by an exit status only, never by matching the text of
# a message: mrcheck exits MR_CLI_EXIT_NODEVICE (69) when it finds no GL device,
# context or display, and nothing else exits 69. A part of a script that is
# skipped makes the whole script a skip (77), not a pass.
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  echo "common_cli.sh is sourced by the cli_*.sh tests; it has nothing to run" >&2
  exit 2
fi

MR_EXIT_NODEVICE=69
pass=0 fail=0 skipped=""
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*" >&2; }

# skip_part WHAT: records that WHAT did not run (no device); the script
# still runs the rest and ends as a skip unless something failed.
skip_part() {
  skipped="${skipped:+$skipped; }$1"
  echo "SKIPPED: $1" >&2
}

# need_device RC LOG WHAT: for a command that had to succeed and exited RC.
# Returns 0 if it succeeded; on the no-device status records the skip of
# WHAT and returns 1; on any other failure counts a failure (with the log)
# and returns 1.
need_device() {
  local rc=$1 log=$2 what=$3
  [ "$rc" -eq 0 ] && return 0
  if [ "$rc" -eq $MR_EXIT_NODEVICE ]; then
    skip_part "$what (no GL device: $(head -c 300 "$log"))"
  else
    bad "$what failed (exit $rc): $(head -c 2000 "$log")"
  fi
  return 1
}

# demo_or_exit NAME MRCHECK OUT: runs `mrcheck demo --out OUT`, which the
# whole script builds on: without a GL device the script is a skip (77),
# on any other failure it fails at once.
demo_or_exit() {
  local name=$1 mrbin=$2 out=$3
  "$mrbin" demo --out "$out" >"$out.log" 2>&1
  local rc=$?
  [ $rc -eq 0 ] && return 0
  if [ $rc -eq $MR_EXIT_NODEVICE ]; then
    echo "$name: SKIPPED: no GL device: $(cat "$out.log")"
    exit 77
  fi
  cat "$out.log"
  echo "$name: mrcheck demo failed (exit $rc)"
  exit 1
}

# expect_fail NAME OUTFILE -- command...: bad input must give exactly one
# line on stderr, a non-zero exit that is neither a crash nor the no-device
# status, and leave no output (nor a temporary file next to it).
expect_fail() {
  local name=$1 out=$2
  # A call without its OUTFILE ran the command's arguments as a command
  # and passed on "command not found": the form is checked, and a command
  # that did not run (126, 127) is a failure.
  if [ "${3-}" != "--" ]; then bad "$name: expect_fail NAME OUTFILE -- command... (use \"\" for no file)"; return; fi
  shift 3
  "$@" >"$tmp/$name.out" 2>"$tmp/$name.err"
  local rc=$?
  if [ $rc -eq 126 ] || [ $rc -eq 127 ]; then bad "$name: the command did not run: $(cat "$tmp/$name.err")"; return; fi
  local lines
  lines=$(wc -l <"$tmp/$name.err")
  if [ $rc -eq 0 ]; then bad "$name: exit 0"; return; fi
  if [ $rc -ge 128 ]; then bad "$name: crashed (rc $rc)"; return; fi
  if [ $rc -eq $MR_EXIT_NODEVICE ]; then bad "$name: failed for want of a GL device, not on the bad input: $(cat "$tmp/$name.err")"; return; fi
  if [ "$lines" -ne 1 ]; then bad "$name: $lines lines on stderr: $(cat "$tmp/$name.err")"; return; fi
  if [ -n "$out" ] && { [ -e "$out" ] || ls "$out".tmp.* >/dev/null 2>&1; }; then bad "$name: output left behind"; return; fi
  ok
}

# cli_finish NAME: the summary line and the exit status.
cli_finish() {
  if [ $fail -gt 0 ]; then
    echo "$1: $pass passed, $fail failed${skipped:+ (also skipped: $skipped)}"
    exit 1
  fi
  if [ -n "$skipped" ]; then
    echo "$1: $pass passed, SKIPPED: $skipped"
    exit 77
  fi
  if [ $pass -eq 0 ]; then
    echo "$1: no check ran"
    exit 1
  fi
  echo "$1: $pass passed, 0 failed"
  exit 0
}
