# Shared by the command-line test scripts: `source checks.sh BIN TMP` sets $bin, makes a fresh $tmp and
# enters it; `check NAME CONDITION...` counts a pass or prints the failure; `finish_checks` reports and
# sets the exit status.
bin=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
cd "$tmp" || exit 1
failures=0
passes=0

check() {  # check NAME CONDITION...
  local name=$1
  shift
  if "$@"; then passes=$((passes + 1)); else echo "FAIL $name"; failures=$((failures + 1)); fi
}

finish_checks() {
  echo "$passes passed, $failures failed"
  [ "$failures" -eq 0 ]
}
