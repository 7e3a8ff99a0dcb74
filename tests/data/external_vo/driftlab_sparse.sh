#!/bin/sh
# A real VO behind an external command: driftlab's own sparse VO, run by `driftlab vo` on the
# export (KITTI unless FORMAT says otherwise), with the export's own settings.
# Usage: driftlab_sparse.sh DRIFTLAB DIR ROOT OUT [FORMAT]
set -e
"$1" vo "$2" --format "${5:-kitti}" --algo sparse --settings "$3/scenario.resolved.yaml" --out "$4.d"
cp "$4.d/estimates/sparse.tum" "$4"
