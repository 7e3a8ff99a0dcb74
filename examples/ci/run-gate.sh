#!/usr/bin/env bash
# The CI regression gate in one script: plans and runs a small sweep, merges it,
# and compares the merged metrics with a committed baseline. Exit 0 when every
# metric is within tolerance, 5 on a regression (or a missing metric), 6 when
# sweep jobs failed, 1-4 on other failures (driftlab's exit codes). `scripts/test` runs it after ctest; the GitHub Actions
# workflow beside it (github-actions.yml) does the same in CI.
#
# Environment (all optional):
#   DRIFTLAB  the driftlab binary            (default: build/bin/driftlab of this checkout)
#   SWEEP     the sweep file                 (default: mini_sweep.yaml beside this script)
#   BASELINE  the baseline to compare with   (default: baseline.json beside this script)
#   OUT       the sweep folder to write      (default: a new temporary folder)
#   JOBS      jobs at once                   (default: the number of cores)
#   UPDATE    non-empty: accept the new values into BASELINE (driftlab regress --update)
#   GATE_SET  space-separated KEY.PATH=VALUE overrides for every job (`sweep plan --set`), to
#             try a change without editing code, e.g.
#             GATE_SET="pipeline.sparse.lk_refinement=false" examples/ci/run-gate.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
DRIFTLAB=${DRIFTLAB:-$here/../../build/bin/driftlab}
SWEEP=${SWEEP:-$here/mini_sweep.yaml}
BASELINE=${BASELINE:-$here/baseline.json}
OUT=${OUT:-$(mktemp -d "${TMPDIR:-/tmp}/driftlab-gate.XXXXXX")/sweep}
JOBS=${JOBS:-$(nproc)}

sets=()
for kv in ${GATE_SET:-}; do sets+=(--set "$kv"); done

start=$(date +%s)
"$DRIFTLAB" sweep plan "$SWEEP" --out "$OUT" "${sets[@]}"
"$DRIFTLAB" sweep run "$OUT" -j "$JOBS"
"$DRIFTLAB" sweep merge "$OUT"
set +e
"$DRIFTLAB" regress --baseline "$BASELINE" --results "$OUT" --junit "$OUT/regress-junit.xml" \
  ${UPDATE:+--update}
status=$?
set -e
echo "run-gate: sweep, merge and gate in $(( $(date +%s) - start )) s; summary in $OUT/summary," \
  "JUnit in $OUT/regress-junit.xml"
exit $status
