#!/usr/bin/env bash
# Open JupyterLab on notebooks/, listening on 127.0.0.1 only.
# Sets up .venv first (see scripts/env.sh). Extra arguments go to `jupyter lab`,
# e.g. `bash scripts/lab.sh --no-browser --port 8899`.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/env.sh"

extra=()
# Jupyter refuses to start as root without --allow-root (e.g. inside a container).
if [[ "$(id -u)" -eq 0 ]]; then
    extra+=(--allow-root)
fi

# numba's kernels compiled in the background while the lab opens (about 7 s the first
# time on a machine, cached afterwards), so a trainee's first demo does not wait for them
"$TUTOR_VENV/bin/python" -m tutor warm >/dev/null 2>&1 &

exec "$TUTOR_VENV/bin/jupyter" lab \
    --ServerApp.ip=127.0.0.1 \
    --ServerApp.root_dir="$TUTOR_ROOT/notebooks" \
    ${extra[@]+"${extra[@]}"} \
    "$@"
