#!/usr/bin/env bash
# Does more 3D supervision teach the decoder finer shapes? (benchmarks/results/fine_tune_points.md, issue 12).
# code_oracle.md found the decoder, not the encoder, caps the model: even with codes fitted to ten posed views it
# renders its own training objects at only 0.67 mIoU. Its 3D supervision (the occupancy and point affordance of
# each training object's mesh) was chosen at weight 0.1 with 1,024 points an object in an 8-minute pilot and never
# varied since; a point costs one field evaluation against 48 for a ray. A further stage with three times the
# weight and twice the points (0.3, 2,048) against the same stage without the change, side by side
# (benchmarks/further_stage.sh), 17 minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
export MINUTES="${MINUTES:-17}"
export WORK="${WORK:-benchmarks/.work/fine_tune_points}"
exec benchmarks/further_stage.sh points "${POINTS_STEPS:-6500}" --points-weight 0.3 --points-per-object 2048
