# shellcheck shell=bash
# Sourced by scripts/lab.sh and scripts/test.sh (or by hand: `source scripts/env.sh`).
#
# Makes sure a Python 3.11 virtual environment exists at .venv in the repo root
# (or at $TUTOR_VENV if set) with lfd-tutor installed editable, with the
# notebooks and test extras. The pip install runs only when pyproject.toml has
# changed since the last successful install (its sha256 is kept in
# .venv/.tutor-stamp), so a second run takes a second or two.
#
# On success: TUTOR_ROOT and TUTOR_VENV are set (not exported), VIRTUAL_ENV is
# exported and $TUTOR_VENV/bin is first on PATH. On failure: a message on stderr and a non-zero return status (the
# calling shell is not exited).

TUTOR_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
TUTOR_VENV="${TUTOR_VENV:-$TUTOR_ROOT/.venv}"

_tutor_env_setup() {
    local py want have stamp="$TUTOR_VENV/.tutor-stamp"

    if ! py="$(command -v python3.11)"; then
        echo "lfd-tutor: python3.11 not found on PATH. Install Python 3.11" \
             "(e.g. 'apt-get install python3.11 python3.11-venv', pyenv or python.org)" \
             "and run this again." >&2
        return 1
    fi

    if [[ ! -x "$TUTOR_VENV/bin/python" ]]; then
        echo "lfd-tutor: creating $TUTOR_VENV with $py" >&2
        "$py" -m venv "$TUTOR_VENV" || {
            echo "lfd-tutor: '$py -m venv $TUTOR_VENV' failed (on Debian/Ubuntu:" \
                 "apt-get install python3.11-venv)." >&2
            return 1
        }
    fi
    if ! "$TUTOR_VENV/bin/python" -c \
            'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
        echo "lfd-tutor: $TUTOR_VENV does not run Python 3.11; remove it" \
             "(rm -rf '$TUTOR_VENV') and run this again." >&2
        return 1
    fi

    if command -v sha256sum >/dev/null; then
        want="$(sha256sum "$TUTOR_ROOT/pyproject.toml")" || return 1
    else  # macOS
        want="$(shasum -a 256 "$TUTOR_ROOT/pyproject.toml")" || return 1
    fi
    want="${want%% *}"
    have="$(cat "$stamp" 2>/dev/null || true)"
    if [[ "$want" != "$have" ]]; then
        echo "lfd-tutor: installing lfd-tutor[notebooks,test] into $TUTOR_VENV" \
             "(takes a few minutes the first time)" >&2
        rm -f "$stamp"
        "$TUTOR_VENV/bin/python" -m pip install -q -e "$TUTOR_ROOT[notebooks,test]" || {
            echo "lfd-tutor: pip install failed (see the errors above)." >&2
            return 1
        }
        echo "$want" >"$stamp"
    fi

    # JupyterLab settings for a workshop room: no news or update pop-ups (and no
    # fetching them from the internet), and no "Select Kernel" question: a notebook
    # without a kernel starts the preferred one, as pressing Select would; and widget
    # messages handled on the kernel's main thread, not in a subshell (JupyterLab 4.4's
    # default with ipykernel 7 ran the widgets' callbacks in a thread beside the main
    # one, and a run's next tutor sometimes never reached the page); see
    # scripts/jupyterlab_overrides.json.
    local settings="$TUTOR_VENV/share/jupyter/lab/settings"
    if ! cmp -s "$TUTOR_ROOT/scripts/jupyterlab_overrides.json" "$settings/overrides.json"; then
        mkdir -p "$settings" &&
            cp "$TUTOR_ROOT/scripts/jupyterlab_overrides.json" "$settings/overrides.json"
    fi
    # and no debugger: trainees do not need it, and it sends a debug request to every
    # kernel it sees (its "Could not restore the debugger state" when a busy kernel
    # stops); see scripts/jupyterlab_page_config.json.
    local labconfig="$TUTOR_VENV/etc/jupyter/labconfig"
    if ! cmp -s "$TUTOR_ROOT/scripts/jupyterlab_page_config.json" "$labconfig/page_config.json"; then
        mkdir -p "$labconfig" &&
            cp "$TUTOR_ROOT/scripts/jupyterlab_page_config.json" "$labconfig/page_config.json"
    fi

    # The kernel's websocket without Nagle's delay (tutor/kernel_socket.py: a
    # widget's message reached the page ~43 ms late), for JupyterLab, the hub's
    # single-user servers (etc/jupyter/jupyter_server_config.d) and Voila (voila.json).
    local config
    for config in etc/jupyter/jupyter_server_config.d/lfd-tutor.json etc/jupyter/voila.json; do
        if ! cmp -s "$TUTOR_ROOT/$config" "$TUTOR_VENV/$config"; then
            mkdir -p "$(dirname "$TUTOR_VENV/$config")" &&
                cp "$TUTOR_ROOT/$config" "$TUTOR_VENV/$config"
        fi
    done

    # Voila's page for the tutor's notebooks (share/jupyter/voila/templates/lfd-tutor: no
    # CDN, the kernel shut down on leaving). A wheel installs it as data files; an editable
    # install does not, so it is copied here.
    local template="share/jupyter/voila/templates/lfd-tutor"
    if ! diff -rq "$TUTOR_ROOT/$template" "$TUTOR_VENV/$template" >/dev/null 2>&1; then
        rm -rf "${TUTOR_VENV:?}/$template" && mkdir -p "$TUTOR_VENV/$template" &&
            cp "$TUTOR_ROOT/$template"/* "$TUTOR_VENV/$template/"
    fi
}

if _tutor_env_setup; then
    unset -f _tutor_env_setup
    export VIRTUAL_ENV="$TUTOR_VENV"
    case ":$PATH:" in
        *":$TUTOR_VENV/bin:"*) ;;
        *) export PATH="$TUTOR_VENV/bin:$PATH" ;;
    esac
else
    unset -f _tutor_env_setup
    false
fi
