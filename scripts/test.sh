#!/usr/bin/env bash
# Set up .venv (see scripts/env.sh) and run the whole test suite:
# ruff and lint-imports, then pytest over tests/ and every notebook under notebooks/ (via nbmake).
# Extra arguments go to pytest. Exits non-zero if ruff, lint-imports or pytest fails.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# need_debian_package COMMAND PACKAGE WHAT: install Debian's PACKAGE (as root, with apt-get)
# when COMMAND is missing; otherwise say how and stop.
need_debian_package() {
    local command="$1" package="$2" what="$3"
    command -v "$command" >/dev/null 2>&1 && return 0
    if [[ "$(id -u)" -eq 0 ]] && command -v apt-get >/dev/null 2>&1; then
        echo "lfd-tutor: installing Debian's $package for $what" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$package" >/dev/null
    else
        echo "lfd-tutor: $what needs Debian's $package;" \
             "run 'sudo apt-get install $package' and try again." >&2
        exit 1
    fi
}

# The browser tests drive Debian's chromium (playwright uses it; it downloads no browser).
need_debian_package chromium chromium "the browser tests"

# The hub test (tests/hub) runs JupyterHub's proxy, configurable-http-proxy, from npm:
# installed once into .hub/ (gitignored), where deploy/jupyterhub_config.py finds it.
if [[ ! -x .hub/node_modules/.bin/configurable-http-proxy ]]; then
    need_debian_package npm npm "the hub test's proxy"
    echo "lfd-tutor: installing configurable-http-proxy (npm) into .hub/ for the hub test" >&2
    npm install --no-save --no-fund --no-audit --prefix .hub configurable-http-proxy >/dev/null
fi

source scripts/env.sh

export TUTOR_HEADLESS=1
# teaching runs saved by the notebooks go to a throwaway folder, never a trainee's
TUTOR_RUNS_DIR="$(mktemp -d)"
export TUTOR_RUNS_DIR
trap 'rm -rf "$TUTOR_RUNS_DIR"' EXIT
export MPLBACKEND=Agg

ruff_status=0
ruff check . || ruff_status=$?
# the layers contract of pyproject.toml ([tool.importlinter])
lint_status=0
lint-imports --no-logo || lint_status=$?

pytest_status=0
python -m pytest tests --nbmake notebooks --nbmake-timeout=600 -p no:cacheprovider "$@" \
    || pytest_status=$?

if [[ $pytest_status -ne 0 ]]; then
    exit "$pytest_status"
fi
if [[ $ruff_status -ne 0 ]]; then
    exit "$ruff_status"
fi
exit "$lint_status"
