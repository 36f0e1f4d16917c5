"""A real JupyterHub with deploy/'s config, for the hub test and the load benchmark.

:class:`Hub` starts ``jupyterhub`` on 127.0.0.1 (free ports) with a test config that
``load_subconfig``-s ``deploy/jupyterhub_config.py`` and overrides only what a test
must: the dummy authenticator, SimpleLocalProcessSpawner with homes in a temp folder,
temp state and class folders, ``--allow-root`` when run as root, and a service token
(granted through ``load_roles``) that drives the REST API. Everything else (the class
folder callables, the pre-spawn hook copying the notebooks, the idle culler, the proxy
found by the kit) is the kit's own.

:class:`KernelTrainee` drives one user's kernel through the Jupyter server REST API and
its websocket (tornado's client), timing each execute request to its reply.

The process helpers read /proc (Linux): the hub's process tree, each process's
listening sockets, and PSS from ``/proc/PID/smaps_rollup``.
"""

from __future__ import annotations

import asyncio
import json
import os
import secrets
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
import uuid
from pathlib import Path

from tests.browser.conftest import free_port

REPO = Path(__file__).resolve().parents[2]
KIT_CONFIG = REPO / "deploy" / "jupyterhub_config.py"
PROXY_HELP = (
    "configurable-http-proxy is missing: scripts/test.sh installs it with "
    "'npm install --no-save --prefix .hub configurable-http-proxy'"
)

TEST_CONFIG = """\
# written by tests/hub/hubkit.py: the kit's config, with a test's overrides
c = get_config()  # noqa: F821
load_subconfig({kit!r})  # noqa: F821
c.JupyterHub.authenticator_class = "dummy"
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = {homes!r} + "/{{username}}"
c.JupyterHub.hub_port = {hub_port}
c.ConfigurableHTTPProxy.api_url = "http://127.0.0.1:{proxy_api_port}"
c.Spawner.args = {args!r}
c.Spawner.start_timeout = 300
c.Spawner.http_timeout = 300
c.JupyterHub.concurrent_spawn_limit = 100
c.JupyterHub.services.append({{"name": "lfd-test", "api_token": {token!r}}})
c.JupyterHub.load_roles.append(
    {{
        "name": "lfd-test",
        "scopes": ["admin:users", "admin:servers", "access:servers", "list:users"],
        "services": ["lfd-test"],
    }}
)
"""


# ---------------------------------------------------------------- processes (/proc)


def _children() -> dict[int, list[int]]:
    kids: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        ppid = int(stat[stat.rindex(")") + 2 :].split()[1])
        kids.setdefault(ppid, []).append(int(entry))
    return kids


def process_tree(pid: int) -> list[int]:
    """``pid`` and all its descendants that are alive now."""
    kids, out, todo = _children(), [], [pid]
    while todo:
        p = todo.pop()
        if Path(f"/proc/{p}").exists():
            out.append(p)
        todo.extend(kids.get(p, []))
    return out


def pss_kb(pids) -> int:
    """The summed PSS (kB) of ``pids`` from /proc/PID/smaps_rollup (gone ones count 0)."""
    total = 0
    for pid in pids:
        try:
            text = Path(f"/proc/{pid}/smaps_rollup").read_text()
        except OSError:
            continue
        for line in text.splitlines():
            if line.startswith("Pss:"):
                total += int(line.split()[1])
    return total


def cpu_seconds(pids) -> float:
    """User + system CPU time (s) used so far by ``pids`` (not their dead children)."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0
    for pid in pids:
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        total += int(fields[11]) + int(fields[12])
    return total / tick


def environ_of(pid: int) -> dict[str, str]:
    try:
        raw = Path(f"/proc/{pid}/environ").read_bytes()
    except OSError:
        return {}
    pairs = (item.split(b"=", 1) for item in raw.split(b"\0") if b"=" in item)
    return {k.decode(errors="replace"): v.decode(errors="replace") for k, v in pairs}


def _socket_inodes(pid: int) -> set[int]:
    out = set()
    try:
        fds = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return out
    for fd in fds:
        try:
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if target.startswith("socket:["):
            out.add(int(target[8:-1]))
    return out


def _decode_address(hex_addr: str) -> str:
    ip_hex, port_hex = hex_addr.split(":")
    raw = bytes.fromhex(ip_hex)
    # /proc/net prints each 32-bit word in host (little-endian) order
    words = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
    if len(words) == 4:
        ip = ".".join(str(b) for b in words)
    else:
        import ipaddress

        ip = str(ipaddress.IPv6Address(words))
    return f"{ip}:{int(port_hex, 16)}"


def listening_sockets(pids) -> list[dict]:
    """Every TCP socket in LISTEN and every bound UDP socket held by ``pids``."""
    owners = {inode: pid for pid in pids for inode in _socket_inodes(pid)}
    found = []
    for proto in ("tcp", "tcp6", "udp", "udp6"):
        try:
            lines = Path(f"/proc/net/{proto}").read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            parts = line.split()
            local, state, inode = parts[1], parts[3], int(parts[9])
            listening = state == "0A" if proto.startswith("tcp") else state == "07"
            if inode in owners and listening:
                address = _decode_address(local)
                found.append({"pid": owners[inode], "proto": proto, "address": address})
    return found


def is_loopback(address: str) -> bool:
    host = address.rsplit(":", 1)[0]
    return host.startswith("127.") or host in ("::1", "::ffff:127.0.0.1") or (
        host.startswith("::ffff:127.")
    )


def percentile(values, q: float) -> float:
    """The ``q``-th percentile (linear interpolation, as numpy's default)."""
    import numpy as np

    return float(np.percentile(np.asarray(values, dtype=float), q))


# ---------------------------------------------------------------- the hub


class HubError(RuntimeError):
    """The hub, a server or a kernel did not do what the test asked."""


class Hub:
    """A running JupyterHub started with the kit's config (use as a context manager).

    Parameters
    ----------
    root : Path
        An empty temp folder: state, homes, the class folder and logs go here.
    idle_timeout : int
        The idle culler's timeout (s), passed to the kit as ``LFD_IDLE_TIMEOUT``.
    """

    def __init__(self, root: Path, idle_timeout: int = 3600):
        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        self.class_dir = self.root / "class"
        self.homes = self.root / "homes"
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.token = secrets.token_hex(16)
        self.idle_timeout = idle_timeout
        self.proc: subprocess.Popen | None = None
        self.seen: set[int] = set()  # every pid of the hub's tree seen, for the cleanup
        self.log_path = self.root / "jupyterhub.log"
        self.log = None

    # ---------------------------------------------------------------- start, stop

    def write_config(self) -> Path:
        args = ["--allow-root"] if os.geteuid() == 0 else []
        config = self.root / "jupyterhub_test_config.py"
        config.write_text(
            TEST_CONFIG.format(
                kit=str(KIT_CONFIG),
                homes=str(self.homes),
                hub_port=free_port(),
                proxy_api_port=free_port(),
                args=args,
                token=self.token,
            )
        )
        return config

    def environment(self) -> dict[str, str]:
        # a person's session, not CI's headless one: notebooks wait for the mouse
        env = {k: v for k, v in os.environ.items() if k not in ("TUTOR_HEADLESS",)}
        env.update(
            LFD_CLASS_DIR=str(self.class_dir),
            LFD_HUB_STATE_DIR=str(self.root / "state"),
            LFD_HUB_PORT=str(self.port),
            LFD_IDLE_TIMEOUT=str(self.idle_timeout),
            LFD_NOTEBOOKS=str(REPO / "notebooks"),
            PYTHONPATH=os.pathsep.join(
                p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p
            ),
        )
        # the kit puts each trainee's folder under the class folder itself
        env.pop("TUTOR_RUNS_DIR", None)
        return env

    def start(self, timeout: float = 120.0) -> Hub:
        if not any(
            (folder / "node_modules" / ".bin" / "configurable-http-proxy").exists()
            for folder in (REPO / "deploy", REPO / ".hub")
        ):
            raise HubError(PROXY_HELP)
        config = self.write_config()
        self.log = open(self.log_path, "w")  # noqa: SIM115
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "jupyterhub", "-f", str(config)],
            cwd=self.root,
            env=self.environment(),
            stdout=self.log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.remember()
            if self.proc.poll() is not None:
                raise HubError(f"jupyterhub exited with {self.proc.returncode}:\n{self.log_tail()}")
            try:
                self.api("GET", "/hub/api/")
                return self
            except (OSError, HubError):
                time.sleep(0.5)
        raise HubError(f"the hub did not answer within {timeout} s:\n{self.log_tail()}")

    def log_tail(self, n: int = 40) -> str:
        try:
            return "\n".join(self.log_path.read_text().splitlines()[-n:])
        except OSError:
            return ""

    def remember(self) -> list[int]:
        """The hub's process tree now (remembered for the cleanup)."""
        if self.proc is None:
            return []
        pids = process_tree(self.proc.pid)
        self.seen.update(pids)
        return pids

    def stop(self) -> None:
        """Stop the hub (which stops the servers), then end whatever of its tree is left."""
        if self.proc is None:
            if self.log is not None:
                self.log.close()
            return
        self.remember()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for sig in (signal.SIGTERM, signal.SIGKILL):
            alive = [p for p in self.seen if Path(f"/proc/{p}").exists() and _is_ours(p)]
            for pid in alive:
                try:
                    os.kill(pid, sig)
                except OSError:
                    pass
            if alive:
                time.sleep(2)
        self.log.close()

    def __enter__(self) -> Hub:
        try:
            return self.start()
        except BaseException:
            self.stop()
            raise

    def __exit__(self, *exc) -> None:
        self.stop()

    # ---------------------------------------------------------------- REST

    def api(self, method: str, path: str, body=None, timeout: float = 60.0):
        """Call the hub (or, with a /user/ path, a server) with the service token."""
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(
            f"{self.url}{path}",
            data=data,
            method=method,
            headers={"Authorization": f"token {self.token}", "Content-Type": "application/json"},
        )
        try:
            with urllib.request.urlopen(request, timeout=timeout) as reply:
                text = reply.read()
        except urllib.error.HTTPError as exc:
            raise HubError(f"{method} {path}: HTTP {exc.code} {exc.read()[:300]!r}") from exc
        return json.loads(text) if text.strip() else None

    def create_users(self, names) -> None:
        self.api("POST", "/hub/api/users", {"usernames": list(names)})

    def start_servers(self, names, timeout: float = 300.0) -> float:
        """Ask for every user's server at once, wait until all are ready; returns seconds."""
        t0 = time.monotonic()
        for name in names:
            self.api("POST", f"/hub/api/users/{name}/server")
        waiting = set(names)
        while waiting and time.monotonic() - t0 < timeout:
            self.remember()
            for name in sorted(waiting):
                server = self.api("GET", f"/hub/api/users/{name}")["servers"].get("", {})
                if server.get("ready"):
                    waiting.discard(name)
            time.sleep(1.0)
        if waiting:
            raise HubError(f"servers not ready after {timeout} s: {sorted(waiting)}\n"
                           f"{self.log_tail()}")
        self.remember()
        return time.monotonic() - t0

    def server_pids(self) -> dict[str, int]:
        """Each user's single-user server process (found by its JUPYTERHUB_USER)."""
        out = {}
        for pid in self.remember():
            env = environ_of(pid)
            user = env.get("JUPYTERHUB_USER")
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if user and b"jupyterhub-singleuser" in cmd and user not in out:
                out[user] = pid
        return out

    def memory_report(self) -> dict:
        """PSS (MB) of each user's server with its kernels, and of the hub and proxy."""
        servers = self.server_pids()
        per_user = {u: pss_kb(process_tree(p)) / 1024 for u, p in sorted(servers.items())}
        in_servers = {q for p in servers.values() for q in process_tree(p)}
        rest = [p for p in self.remember() if p not in in_servers]
        return {"per_user_mb": per_user, "hub_proxy_culler_mb": pss_kb(rest) / 1024}

    def exposed_sockets(self) -> tuple[list[dict], list[dict]]:
        """(all listening sockets of the hub's tree, those not on loopback)."""
        found = listening_sockets(self.remember())
        return found, [s for s in found if not is_loopback(s["address"])]


def _is_ours(pid: int) -> bool:
    """A guard for the cleanup: the pid still runs a program of the hub's tree."""
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False
    return any(
        word in cmd
        for word in (b"jupyterhub", b"configurable-http-proxy", b"ipykernel", b"idle_culler")
    )


# ---------------------------------------------------------------- kernels over websockets


#: a trainee's first cell: the Experiment 1 form started with the hub user's name, one
#: NF demonstration and Finish, then VF; demonstrations come from the scripted maze paths
SETUP_CODE = """\
import numpy as np
from tutor.tasks.maze import load_layout
from tutor.views.start import maze_experiment
_layout = load_layout()
_rng = np.random.default_rng({seed})
def _next_demo():
    start = _layout.sample_starts(1, _rng)[0]
    return _layout.reference_path(start, _rng, jitter=0.004)
experiment = maze_experiment(start=True)
experiment.current.pad.draw(_next_demo())
experiment.current.buttons["Finish"].click()
vf = experiment.current
assert vf.condition == "VF", vf.condition
print(experiment.trainee, experiment.folder)
"""
#: one demonstration, drawn as a stroke would be; prints the demo count and any message
DEMO_CODE = "vf.pad.draw(_next_demo()); print(vf.session.n_demos, repr(vf.message))"
FINISH_CODE = "vf.buttons['Finish'].click(); print(vf.finished)"


class KernelTrainee:
    """One user's kernel, driven over the server's REST API and kernel websocket.

    Parameters
    ----------
    hub : Hub
    user : str
    seed : int
        Seeds the user's scripted demonstrations.
    """

    def __init__(self, hub: Hub, user: str, seed: int):
        self.hub, self.user, self.seed = hub, user, seed
        self.session = uuid.uuid4().hex
        self.ws = None
        self.latencies_ms: list[float] = []
        self.outputs: list[str] = []

    async def _rest(self, method: str, path: str, body=None):
        from tornado.httpclient import AsyncHTTPClient

        reply = await AsyncHTTPClient().fetch(
            f"{self.hub.url}/user/{self.user}{path}",
            method=method,
            body=None if body is None else json.dumps(body),
            headers={"Authorization": f"token {self.hub.token}"},
            request_timeout=300,
        )
        return json.loads(reply.body)

    async def connect(self) -> None:
        """Start a kernel session (a notebook path of the user's) and open its websocket."""
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        path = f"hub_trainee_{self.user}.ipynb"
        session = await self._rest(
            "POST",
            "/api/sessions",
            {"path": path, "type": "notebook", "name": path, "kernel": {"name": "python3"}},
        )
        kernel = session["kernel"]["id"]
        url = f"ws://127.0.0.1:{self.hub.port}/user/{self.user}/api/kernels/{kernel}/channels"
        self.ws = await websocket_connect(
            # the upgrade waits for the kernel to start: slow when a room starts at once
            HTTPRequest(
                url,
                headers={"Authorization": f"token {self.hub.token}"},
                connect_timeout=300,
                request_timeout=300,
            ),
            max_message_size=256 * 1024 * 1024,
        )

    async def execute(self, code: str, timeout: float = 300.0) -> tuple[float, str]:
        """Run ``code``; returns (ms from sending the request to its execute_reply, stdout).

        Raises
        ------
        HubError
            The cell raised, or no reply came within ``timeout`` seconds.
        """
        msg_id = uuid.uuid4().hex
        message = {
            "header": {
                "msg_id": msg_id,
                "msg_type": "execute_request",
                "session": self.session,
                "username": self.user,
                "version": "5.3",
                "date": "",
            },
            "parent_header": {},
            "metadata": {},
            "content": {
                "code": code,
                "silent": False,
                "store_history": True,
                "user_expressions": {},
                "allow_stdin": False,
                "stop_on_error": True,
            },
            "channel": "shell",
            "buffers": [],
        }
        t0 = time.perf_counter()
        await self.ws.write_message(json.dumps(message))
        out, error, reply, idle, replied_at = [], None, None, False, t0
        deadline = t0 + timeout
        # iopub (outputs, idle) and shell (the reply) are not ordered: wait for both
        while reply is None or not idle:
            left = deadline - time.perf_counter()
            if left <= 0:
                raise HubError(f"{self.user}: no reply within {timeout} s to {code[:60]!r}")
            raw = await asyncio.wait_for(self.ws.read_message(), left)
            if raw is None:
                raise HubError(f"{self.user}: the kernel websocket closed")
            if isinstance(raw, bytes):
                continue  # binary frames carry widget buffers, not replies
            msg = json.loads(raw)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind = msg["msg_type"]
            if kind == "stream":
                out.append(msg["content"]["text"])
            elif kind == "error":
                error = "\n".join(msg["content"]["traceback"])
            elif kind == "status" and msg["content"]["execution_state"] == "idle":
                idle = True
            elif kind == "execute_reply" and msg["channel"] == "shell":
                reply, replied_at = msg, time.perf_counter()
        elapsed_ms = (replied_at - t0) * 1000
        if error or reply["content"]["status"] != "ok":
            raise HubError(f"{self.user}: the cell failed:\n{error or reply['content']}")
        return elapsed_ms, "".join(out)

    async def setup(self) -> str:
        await self.connect()
        _, out = await self.execute(SETUP_CODE.format(seed=self.seed))
        return out

    async def demonstrate(self) -> int:
        """Add one demonstration; records its latency; returns the demo count."""
        ms, out = await self.execute(DEMO_CODE)
        count, message = out.strip().split(" ", 1)
        if "not used" in message or "went wrong" in message:
            raise HubError(f"{self.user}: the demonstration was refused: {message}")
        self.latencies_ms.append(ms)
        return int(count)

    async def finish(self) -> None:
        _, out = await self.execute(FINISH_CODE)
        if out.strip() != "True":
            raise HubError(f"{self.user}: VF did not finish: {out!r}")

    def close(self) -> None:
        if self.ws is not None:
            self.ws.close()
