# Sourced by scripts/test.sh and scripts/ci-sanitize.sh (issue 41): ctest's measured test times
# (Testing/Temporary/CTestCostData.txt) kept outside the clone, beside the compiler cache. With
# them `ctest -j` starts the longest tests first, so the last minutes of a step are not one
# 200 s ASan test running alone; a fresh clone has no times of its own and ran them in file order.
SEMAP_CTEST_COSTS="${SEMAP_CTEST_COSTS:-${XDG_CACHE_HOME:-$HOME/.cache}/semap-ctest-costs}"

# ctest_costs_restore TREE NAME  puts the kept times NAME into build tree TREE (if there are any).
ctest_costs_restore() {
  local kept="$SEMAP_CTEST_COSTS/$2.txt"
  mkdir -p "$1/Testing/Temporary"
  [ -f "$kept" ] && cp "$kept" "$1/Testing/Temporary/CTestCostData.txt" || true
}
# ctest_costs_save TREE NAME  keeps the times ctest updated in TREE as NAME.
ctest_costs_save() {
  local costs="$1/Testing/Temporary/CTestCostData.txt"
  [ -f "$costs" ] || return 0
  mkdir -p "$SEMAP_CTEST_COSTS"
  cp "$costs" "$SEMAP_CTEST_COSTS/$2.txt.$$" && mv "$SEMAP_CTEST_COSTS/$2.txt.$$" "$SEMAP_CTEST_COSTS/$2.txt"
}
