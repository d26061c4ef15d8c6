#!/usr/bin/env bash
# Every test tests/long_tests.cmake names exists and carries the label `long`: ctest applies no label from a list
# that names a test it does not know (a test renamed or removed), and says nothing, so the sanitized suite would run
# long tests unnoticed. Usage: long_labels.sh BUILD_DIR LIST_FILE
build=$1
list=$2
labelled=$(ctest --test-dir "$build" -N -L long | sed -n 's/^ *Test *#[0-9]*: //p')
mapfile -t names < <(sed -n 's/^  \([A-Za-z0-9_]*\.[A-Za-z0-9_]*\)$/\1/p' "$list")
listed=${#names[@]}
missing=0
for name in "${names[@]}"; do
  if ! grep -qxF "$name" <<< "$labelled"; then
    echo "FAIL $name is listed in $list but no test of that name is labelled long"
    missing=$((missing + 1))
  fi
done
echo "$listed listed, $missing not labelled"
[ "$listed" -gt 0 ] && [ "$missing" -eq 0 ]
