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


#: the kernel's side: a burst of comm messages, far more than ZeroMQ's default queue
BURST = """
from comm import create_comm
_c = create_comm(target_name="lfd-burst")
for _i in range({n}):
    _c.send({{"i": _i, "pad": "x" * 2000}})
"""


def _burst_received(connection_class, n: int = 20_000) -> tuple[int, int]:
    """A real kernel sends ``n`` comm messages while the server's side of the connection
    (``connection_class``'s channels) reads nothing for 4 s, as a busy event loop would;
    returns (the iopub socket's receive high-water mark, comm messages then received)."""
    import asyncio
    import time

    from jupyter_client import BlockingKernelClient
    from jupyter_client.session import Session
    from jupyter_server.services.kernels.kernelmanager import ServerKernelManager

    loop = asyncio.new_event_loop()  # the server's loop (its streams are made on it)
    asyncio.set_event_loop(loop)
    km = ServerKernelManager(kernel_name="python3")  # the server's kind of kernel manager
    loop.run_until_complete(km.start_kernel())
    client = BlockingKernelClient()
    client.load_connection_info(km.get_connection_info())
    client.start_channels()
    try:
        client.wait_for_ready(timeout=120)
        connection = connection_class(parent=km)
        connection.create_stream()
        iopub = connection.channels["iopub"].socket
        time.sleep(1.0)  # the subscription is in place before the burst
        client.execute(BURST.format(n=n))
        time.sleep(4.0)
        received = 0
        while iopub.poll(500):
            _, parts = Session().feed_identities(iopub.recv_multipart())
            received += json.loads(parts[1])["msg_type"] == "comm_msg"
        hwm = iopub.rcvhwm
        for stream in connection.channels.values():
            stream.close()
        return hwm, received
    finally:
        client.stop_channels()
        loop.run_until_complete(km.shutdown_kernel(now=True))
        asyncio.set_event_loop(None)
        loop.close()


def test_a_burst_of_kernel_messages_is_never_dropped():
    """ZeroMQ drops a publisher's messages once the subscriber's queue (1000 by default)
    and the socket's buffers are full: with Jupyter Server's own connection most of a
    20 000-message burst is lost while the server does not read; with the tutor's, none."""
    from jupyter_server.services.kernels.connection.channels import (
        ZMQChannelsWebsocketConnection,
    )

    from tutor.kernel_socket import NoDelayKernelConnection

    hwm, received = _burst_received(NoDelayKernelConnection)
    assert hwm == 0 and received == 20_000, (hwm, received)
    hwm, received = _burst_received(ZMQChannelsWebsocketConnection)
    assert hwm == 1000 and received < 20_000, (hwm, received)  # what the fix is for
