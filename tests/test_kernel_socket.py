"""The kernel's websocket without Nagle's delay (tutor/kernel_socket.py).

A real Jupyter server started with the environment's settings (scripts/env.sh copies
etc/jupyter into .venv) loads the extension and answers a comm message over the kernel
websocket; Voila's settings name the same connection class. How much faster it is, is
measured by benchmarks/bench_kernel_socket.py.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benchmarks"))
from bench_kernel_socket import PLAIN, comm_round_trips, jupyter_server  # noqa: E402


def test_the_repository_settings_name_the_connection():
    server = json.loads((REPO / "etc/jupyter/jupyter_server_config.d/lfd-tutor.json").read_text())
    assert server["ServerApp"]["jpserver_extensions"] == {"tutor.kernel_socket": True}
    voila = json.loads((REPO / "etc/jupyter/voila.json").read_text())
    name = voila["Voila"]["kernel_websocket_connection_class"]
    assert name == "tutor.kernel_socket.NoDelayKernelConnection"


def test_voila_takes_the_connection_from_the_environment(tmp_path):
    code = (
        "from voila.app import Voila\n"
        "app = Voila()\n"
        "app.initialize(['--no-browser'])\n"
        "print(app.kernel_websocket_connection_class.__module__,"
        " app.kernel_websocket_connection_class.__name__)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["tutor.kernel_socket", "NoDelayKernelConnection"]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with jupyter_server(tmp_path_factory.mktemp("server")) as running:
        yield running


def test_the_server_loads_the_extension_and_answers_over_the_websocket(server):
    base, token, log = server
    trips = comm_round_trips(base, token, n=5)
    assert len(trips) == 5 and all(t > 0 for t in trips)
    text = log.read_text()
    assert "lfd-tutor: kernel websockets without Nagle's delay" in text, text[-2000:]


def test_a_connection_the_user_configured_stands(tmp_path):
    with jupyter_server(tmp_path, PLAIN) as (base, token, log):
        assert len(comm_round_trips(base, token, n=2)) == 2
        text = log.read_text()
    assert "kernel websockets left as ZMQChannelsWebsocketConnection" in text, text[-2000:]
    assert "without Nagle's delay" not in text
