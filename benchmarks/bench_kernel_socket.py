"""Benchmark a comm message's round trip through Jupyter Server's kernel websocket.

A client (tornado's websocket, TCP_NODELAY on its side, as browsers have) sends a comm
message to a kernel through a Jupyter server on 127.0.0.1, and the kernel answers it at
once. Printed: the median and p90 round trip with the tutor's connection
(``tutor.kernel_socket``, enabled by the environment's settings) and with Jupyter
Server's own (Nagle's algorithm on: the answer waits for the client's delayed ACK).

Run:  .venv/bin/python benchmarks/bench_kernel_socket.py [--n 60]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
import urllib.request
import uuid
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import RESULTS, save  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
from tests.browser.conftest import free_port, stop, wait_http  # noqa: E402

#: the kernel's side: a comm target that answers each message at once
ECHO = """
def _echo(comm, _):
    comm.on_msg(lambda m: comm.send({"pong": m["content"]["data"]["i"]}))
get_ipython().kernel.comm_manager.register_target("lfd-echo", _echo)
"""
#: Jupyter Server's own connection (the tutor's extension leaves a configured one alone)
PLAIN = (
    "--ServerApp.kernel_websocket_connection_class="
    "jupyter_server.services.kernels.connection.channels.ZMQChannelsWebsocketConnection"
)


@contextlib.contextmanager
def jupyter_server(root: Path, *args: str):
    """A Jupyter server on 127.0.0.1 in ``root``; yields (base URL, token, log path)."""
    port, token = free_port(), "lfd-bench"
    log_path = root / "server.log"
    log = open(log_path, "w")  # noqa: SIM115 (closed below)
    env = {k: v for k, v in os.environ.items() if k != "JUPYTER_CONFIG_DIR"}
    cmd = [sys.executable, "-m", "jupyter_server", "--no-browser", "--ServerApp.ip=127.0.0.1"]
    cmd += [f"--port={port}", f"--ServerApp.token={token}", f"--ServerApp.root_dir={root}"]
    cmd += ["--allow-root", *args]
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=root, env=env)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_http(f"{base}/api/status?token={token}", proc)
        yield base, token, log_path
    finally:
        stop(proc)
        log.close()


def _message(kind: str, content: dict) -> str:
    header = {"msg_id": uuid.uuid4().hex, "msg_type": kind, "username": "", "session": "bench"}
    header.update(date="", version="5.3")
    return json.dumps(
        {"header": header, "parent_header": {}, "metadata": {}, "content": content,
         "channel": "shell"}
    )


async def _round_trips(base: str, token: str, n: int) -> list[float]:
    from tornado.websocket import websocket_connect

    request = urllib.request.Request(
        f"{base}/api/kernels?token={token}", data=b"{}", method="POST",
        headers={"Content-Type": "application/json"},
    )
    kernel = json.loads(urllib.request.urlopen(request, timeout=60).read())["id"]
    url = base.replace("http", "ws") + f"/api/kernels/{kernel}/channels?token={token}"
    ws = await websocket_connect(url)
    ws.protocol.stream.set_nodelay(True)  # the client's side, as a browser's
    try:
        await ws.write_message(_message("execute_request", {"code": ECHO, "silent": False}))
        while json.loads(await ws.read_message())["msg_type"] != "execute_reply":
            pass
        comm = uuid.uuid4().hex
        await ws.write_message(
            _message("comm_open", {"comm_id": comm, "target_name": "lfd-echo", "data": {}})
        )
        await asyncio.sleep(0.5)
        trips = []
        for i in range(n):
            t0 = time.perf_counter()
            await ws.write_message(_message("comm_msg", {"comm_id": comm, "data": {"i": i}}))
            while True:
                got = json.loads(await asyncio.wait_for(ws.read_message(), 30))
                if got["msg_type"] == "comm_msg" and got["content"]["data"].get("pong") == i:
                    break
            trips.append((time.perf_counter() - t0) * 1e3)
            await asyncio.sleep(0.02)
        return trips
    finally:
        ws.close()


def comm_round_trips(base: str, token: str, n: int = 60) -> list[float]:
    """ms of ``n`` comm messages' round trips to a new kernel of the server at ``base``."""
    return asyncio.run(_round_trips(base, token, n))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=60)
    parser.add_argument("--out", type=Path, default=RESULTS / "bench_kernel_socket.json")
    args = parser.parse_args()
    result = {}
    for name, extra in (("tutor's connection", ()), ("Jupyter Server's own", (PLAIN,))):
        with tempfile.TemporaryDirectory() as tmp, jupyter_server(Path(tmp), *extra) as running:
            trips = comm_round_trips(running[0], running[1], args.n)
        result[name] = {"median_ms": float(np.median(trips)),
                        "p90_ms": float(np.percentile(trips, 90)), "n": len(trips)}
        print(f"{name:22s} comm round trip: median {result[name]['median_ms']:.1f} ms, "
              f"p90 {result[name]['p90_ms']:.1f} ms ({len(trips)} messages)")
    save(result, args.out)


if __name__ == "__main__":
    main()
