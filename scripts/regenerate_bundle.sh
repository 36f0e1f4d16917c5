#!/usr/bin/env bash
# Regenerate everything bundled that rests on the maze and the simulated teachers.
#
# Run after scripts/apply_calibration.py has put a calibration's point into
# tutor/teachers/traits.py and tutor/assets/maze.json. Each step is the command that
# writes that file; about 25 minutes on 2 cores, most of it the adaptive study.
#
#   bash scripts/regenerate_bundle.sh            # everything
#   bash scripts/regenerate_bundle.sh --no-adaptive
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# shellcheck source=scripts/env.sh
source scripts/env.sh
export TUTOR_HEADLESS=1 MPLBACKEND=Agg

step() { printf '\n== %s\n' "$*"; }

step "maze demo sets (and a typical simulated novice's set)"
python scripts/make_maze_demo_sets.py --novice
step "the optimal teacher (TD and best eta per task)"
python -m tutor.study.optimal --out tutor/assets/optimal.json
for e in 1 2; do
    step "Experiment $e: the seed-0 cohort and 20 seeds of robustness"
    lfd-tutor reproduce --experiment "$e" --seed 0 --out tutor/assets/cohorts --no-figures --no-progress
    lfd-tutor robustness --experiment "$e" --seeds 20 --out tutor/assets/cohorts --no-progress
done
if [[ "${1:-}" != "--no-adaptive" ]]; then
    step "the adaptive study (10 seeds)"
    lfd-tutor adaptive --seeds 10 --out tutor/assets/adaptive --no-progress
    # bundled as tutor/assets/README.md says: the runs gzipped, the per-demo curves left out
    gzip -9 -n -f tutor/assets/adaptive/adaptive_runs.csv
    rm -f tutor/assets/adaptive/adaptive_curves.csv
fi
step "done: run the tests (bash scripts/test.sh) and update the prose from the new reports"
