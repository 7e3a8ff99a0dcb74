#!/usr/bin/env bash
# The CI regression gate in one script: plans and runs the gate's sweep (gate_sweep.yaml: 8
# short stretches of the river survey with the paper's camera), merges it, and compares the
# merged metrics with a committed baseline, job by job and section by section (paired tests;
# docs/sweeps.md). Exit 0 when no metric regressed, 5 on a regression (or a missing metric),
# 6 when sweep jobs failed, 1-4 on other failures (driftlab's exit codes). `scripts/test` runs
# it after ctest, then test-gate.sh; the GitHub Actions workflow beside it
# (github-actions.yml) does the same in CI. The frames are rendered once into the frame cache
# and replayed by every later gate run whose renderer and scenes are unchanged.
#
# Environment (all optional):
#   DRIFTLAB  the driftlab binary            (default: build/bin/driftlab of this checkout)
#   SWEEP     the sweep file                 (default: gate_sweep.yaml beside this script)
#   BASELINE  the baseline to compare with   (default: baseline.json beside this script)
#   OUT       the sweep folder to write      (default: a new temporary folder)
#   JOBS      jobs at once                   (default: the number of cores)
#   DRIFTLAB_FRAME_CACHE  the frame cache    (default: ~/.cache/driftlab/frames; about 3 GB
#             for this sweep)
#   UPDATE    non-empty: accept the new values into BASELINE (driftlab regress --update)
#   GATE_SET  space-separated KEY.PATH=VALUE overrides for every job (`sweep plan --set`), to
#             try a change without editing code, e.g.
#             GATE_SET="pipeline.sparse.lk_refinement=false" examples/ci/run-gate.sh
#   GATE_ONLY comma-separated key prefixes: compare only those metrics (`regress --only`), e.g.
#             GATE_ONLY=algorithms.sparse. with GATE_SET="pipeline.vo=[sparse]" runs one VO
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
DRIFTLAB=${DRIFTLAB:-$here/../../build/bin/driftlab}
SWEEP=${SWEEP:-$here/gate_sweep.yaml}
BASELINE=${BASELINE:-$here/baseline.json}
OUT=${OUT:-$(mktemp -d "${TMPDIR:-/tmp}/driftlab-gate.XXXXXX")/sweep}
JOBS=${JOBS:-$(nproc)}
export DRIFTLAB_FRAME_CACHE=${DRIFTLAB_FRAME_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/driftlab/frames}

sets=()
for kv in ${GATE_SET:-}; do sets+=(--set "$kv"); done

start=$(date +%s)
"$DRIFTLAB" sweep plan "$SWEEP" --out "$OUT" "${sets[@]}"
"$DRIFTLAB" sweep run "$OUT" -j "$JOBS"
"$DRIFTLAB" sweep merge "$OUT" --no-plots
set +e
"$DRIFTLAB" regress --baseline "$BASELINE" --results "$OUT" --junit "$OUT/regress-junit.xml" \
  ${UPDATE:+--update} ${GATE_ONLY:+--only "$GATE_ONLY"}
status=$?
set -e
echo "run-gate: sweep, merge and gate in $(( $(date +%s) - start )) s; summary in $OUT/summary," \
  "JUnit in $OUT/regress-junit.xml"
exit $status
