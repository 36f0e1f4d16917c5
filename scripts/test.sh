#!/usr/bin/env bash
# Set up .venv (see scripts/env.sh) and run the whole test suite:
# ruff, then pytest over tests/ and every notebook under notebooks/ (via nbmake).
# Extra arguments go to pytest. Exits non-zero if ruff or pytest fails.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# system packages needed by browser tests are installed here

source scripts/env.sh

export TUTOR_HEADLESS=1
export MPLBACKEND=Agg

ruff_status=0
ruff check . || ruff_status=$?

pytest_status=0
python -m pytest tests --nbmake notebooks --nbmake-timeout=600 -p no:cacheprovider "$@" \
    || pytest_status=$?

if [[ $pytest_status -ne 0 ]]; then
    exit "$pytest_status"
fi
exit "$ruff_status"
