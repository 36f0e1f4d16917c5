"""Load benchmark of the workshop hub: simulated trainees teaching the maze at once.

Starts JupyterHub on 127.0.0.1 with deploy/jupyterhub_config.py (the test overrides of
tests/hub/hubkit.py: dummy authenticator, SimpleLocalProcessSpawner, temp folders),
creates N users (default 30), starts their servers, and in each server's kernel starts
the Experiment 1 form, teaches NF one demonstration and finishes it. Then, for
``--duration`` seconds (default 180), every trainee adds a VF demonstration every
``--interval`` seconds (default 10; each trainee starts at a random offset within the
interval, and keeps to its own schedule however long a demonstration takes).

Latency of a demonstration: from sending the ``execute_request`` of the cell that draws
the stroke (over the hub's proxy and the kernel websocket) to receiving its
``execute_reply``; the tutor's feedback (the refitted model's 140 attempts) is computed
by then. Reported: p50, p95 and max over all demonstrations, and by demonstration
number. CPU: the machine's busy share of all cores (/proc/stat) and the hub tree's CPU
seconds over the window. Memory: PSS (/proc/PID/smaps_rollup) of every user's server
with its kernel, of the hub, proxy and culler, and the machine's MemAvailable drop.

Not run in CI (it takes about 6-10 minutes). Run:

    .venv/bin/python benchmarks/bench_hub_load.py [--trainees 30] [--interval 10]
        [--duration 180] [--out benchmarks/results/bench_hub_load.json]

Needs configurable-http-proxy in .hub/ (scripts/test.sh installs it).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from results_file import RESULTS, save  # noqa: E402

from tests.hub.hubkit import (  # noqa: E402
    Hub,
    KernelTrainee,
    cpu_seconds,
    percentile,
    pss_kb,
)

DEFAULT_OUT = RESULTS / "bench_hub_load.json"
#: kernels started at once while the room sets up (a 2-core machine chokes on 30)
SETUP_AT_ONCE = 4


def cpu_busy_jiffies() -> tuple[int, int]:
    """(busy, total) jiffies of all cores since boot, from /proc/stat."""
    fields = [int(x) for x in Path("/proc/stat").read_text().splitlines()[0].split()[1:]]
    idle = fields[3] + fields[4]  # idle + iowait
    return sum(fields) - idle, sum(fields)


def mem_available_mb() -> float:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) / 1024
    return float("nan")


async def set_up(trainees) -> float:
    t0 = time.monotonic()
    gate = asyncio.Semaphore(SETUP_AT_ONCE)

    async def one(trainee):
        async with gate:
            await trainee.setup()

    await asyncio.gather(*(one(t) for t in trainees))
    return time.monotonic() - t0


async def teach(trainee, offset: float, interval: float, duration: float, t0: float) -> None:
    k = 0
    while True:
        due = t0 + offset + k * interval
        if due - t0 >= duration:
            return
        await asyncio.sleep(max(0.0, due - time.monotonic()))
        await trainee.demonstrate()
        k += 1


async def sample(hub: Hub, stop: asyncio.Event, period: float, samples: list) -> None:
    while not stop.is_set():
        pids = hub.remember()
        samples.append({"t": time.monotonic(), "pss_mb": pss_kb(pids) / 1024})
        try:
            await asyncio.wait_for(stop.wait(), period)
        except TimeoutError:
            pass


async def window(hub, trainees, interval: float, duration: float, seed: int) -> dict:
    rng = random.Random(seed)
    samples: list = []
    stop = asyncio.Event()
    sampler = asyncio.create_task(sample(hub, stop, 5.0, samples))
    load_before = os.getloadavg()[0]
    busy0, total0 = cpu_busy_jiffies()
    cpu0 = cpu_seconds(hub.remember())
    t0 = time.monotonic()
    await asyncio.gather(
        *(teach(t, rng.uniform(0, interval), interval, duration, t0) for t in trainees)
    )
    elapsed = time.monotonic() - t0
    busy1, total1 = cpu_busy_jiffies()
    cpu1 = cpu_seconds(hub.remember())
    stop.set()
    await sampler
    return {
        "elapsed_s": elapsed,
        "cpu_busy_share_all_cores": (busy1 - busy0) / max(1, total1 - total0),
        "hub_tree_cpu_s": cpu1 - cpu0,
        "pss_samples_mb": [round(s["pss_mb"], 1) for s in samples],
        "load_average": [load_before, os.getloadavg()[0]],
    }


def summarise(trainees, load: dict, memory: dict, setup: dict, args, mem_drop: float) -> dict:
    every = [ms for t in trainees for ms in t.latencies_ms]
    by_demo: dict[int, list[float]] = {}
    for t in trainees:
        for i, ms in enumerate(t.latencies_ms, start=1):
            by_demo.setdefault(i, []).append(ms)
    per_user = list(memory["per_user_mb"].values())
    cores = os.cpu_count() or 1
    return {
        "what": "N simulated trainees on the kit's hub, each adding a VF maze demonstration "
        "every INTERVAL s through its kernel; latency = execute_request to execute_reply (ms)",
        "trainees": args.trainees,
        "interval_s": args.interval,
        "duration_s": args.duration,
        "cores": cores,
        "n_demos": len(every),
        "latency_ms": {
            "p50": percentile(every, 50),
            "p95": percentile(every, 95),
            "max": max(every),
            "p50_by_demo": {i: percentile(v, 50) for i, v in sorted(by_demo.items())},
            "p95_by_demo": {i: percentile(v, 95) for i, v in sorted(by_demo.items())},
        },
        "cpu": {
            "busy_share_all_cores": load["cpu_busy_share_all_cores"],
            "hub_tree_cpu_s": load["hub_tree_cpu_s"],
            "hub_tree_cores_used": load["hub_tree_cpu_s"] / load["elapsed_s"],
            "hub_tree_cpu_s_per_demo": load["hub_tree_cpu_s"] / max(1, len(every)),
            # a shared machine: what everything outside the hub used meanwhile
            "other_cores_used": load["cpu_busy_share_all_cores"] * cores
            - load["hub_tree_cpu_s"] / load["elapsed_s"],
            "load_average_before_after": load["load_average"],
        },
        "memory_mb": {
            "per_user_pss_median": percentile(per_user, 50),
            "per_user_pss_max": max(per_user),
            "per_user_pss": memory["per_user_mb"],
            "hub_proxy_culler_pss": memory["hub_proxy_culler_mb"],
            "total_pss": sum(per_user) + memory["hub_proxy_culler_mb"],
            "total_pss_during_window": load["pss_samples_mb"],
            "mem_available_drop": mem_drop,
        },
        "setup_s": setup,
        "window_elapsed_s": load["elapsed_s"],
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trainees", type=int, default=30)
    parser.add_argument("--interval", type=float, default=10.0)
    parser.add_argument("--duration", type=float, default=180.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)

    users = [f"trainee{i:02d}" for i in range(1, args.trainees + 1)]
    mem_before = mem_available_mb()
    with tempfile.TemporaryDirectory() as tmp, Hub(Path(tmp) / "hub") as hub:
        setup = {}
        hub.create_users(users)
        setup["servers_ready"] = hub.start_servers(users, timeout=900)
        print(f"{len(users)} servers ready in {setup['servers_ready']:.0f} s", flush=True)
        trainees = [KernelTrainee(hub, u, seed=i) for i, u in enumerate(users)]

        async def run() -> dict:
            try:
                setup["kernels_ready"] = await set_up(trainees)
                print(f"kernels ready in {setup['kernels_ready']:.0f} s", flush=True)
                return await window(hub, trainees, args.interval, args.duration, args.seed)
            finally:
                for t in trainees:
                    t.close()

        load = asyncio.run(run())
        memory = hub.memory_report()
        mem_drop = mem_before - mem_available_mb()
        _, exposed = hub.exposed_sockets()
        if exposed:
            raise SystemExit(f"listening beyond loopback: {exposed}")
    result = summarise(trainees, load, memory, setup, args, mem_drop)
    save(result, args.out)
    lat, cpu, mem = result["latency_ms"], result["cpu"], result["memory_mb"]
    print(
        f"{args.trainees} trainees, a demo every {args.interval:.0f} s for "
        f"{args.duration:.0f} s ({result['n_demos']} demos, {result['cores']} cores)\n"
        f"latency: p50 {lat['p50']:.0f} ms, p95 {lat['p95']:.0f} ms, max {lat['max']:.0f} ms\n"
        f"CPU: machine {100 * cpu['busy_share_all_cores']:.0f}% busy; hub tree "
        f"{cpu['hub_tree_cores_used']:.2f} cores ({cpu['hub_tree_cpu_s_per_demo']:.2f} s/demo), "
        f"other processes {cpu['other_cores_used']:.2f} cores\n"
        f"memory (PSS): {mem['per_user_pss_median']:.0f} MB per trainee (median, max "
        f"{mem['per_user_pss_max']:.0f}), hub+proxy+culler {mem['hub_proxy_culler_pss']:.0f} MB, "
        f"total {mem['total_pss']:.0f} MB; MemAvailable dropped "
        f"{mem['mem_available_drop']:.0f} MB"
    )
    return result


if __name__ == "__main__":
    main()
