"""The hub kit's pre-spawn hook, driven as root in a scratch class folder, and its settings.

deploy/jupyterhub_config.py is executed here as JupyterHub would (``get_config`` given),
with its folders in a temp folder and its own educators' group, and its pre-spawn hook
is called with a small stand-in for a spawner. The hook then makes real system accounts
(``useradd``): every account and group made here is named ``lfdt-...`` and removed at
the end. What other accounts may read is checked by a forked child that drops root for
the account's uid, gid and groups (root itself reads everything).

Also here: the class analysis, read from an account that cannot enter a trainee folder
(mode 000, owned by nobody), says so; and the Zero to JupyterHub values in
deploy/z2jh-values.yaml isolate trainees.
"""

from __future__ import annotations

import grp
import importlib.util
import json
import os
import pwd
import secrets
import shutil
import stat
import subprocess
import tempfile
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.hub.hubkit import KIT_CONFIG, REPO
from tutor.errors import InvalidParameterError

PREFIX = "lfdt-"


# ---------------------------------------------------------------- helpers


def as_account(uid: int, gid: int, groups, fn):
    """``fn()`` in a forked child running as ``uid``/``gid`` with ``groups`` (umask 027,
    as the kit gives servers); returns what it returned, or the exception's name."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns into pytest
        os.close(read)
        try:
            os.setgroups(list(groups))
            os.setgid(gid)
            os.setuid(uid)
            os.umask(0o027)
            out = {"ok": fn()}
        except BaseException as exc:  # noqa: BLE001 (reported to the parent)
            out = {"error": type(exc).__name__, "text": str(exc)}
        with os.fdopen(write, "w") as pipe:
            json.dump(out, pipe)
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as pipe:
        text = pipe.read()
    os.waitpid(pid, 0)
    return json.loads(text)


def as_user(name: str, fn):
    account = pwd.getpwnam(name)
    groups = os.getgrouplist(name, account.pw_gid)
    return as_account(account.pw_uid, account.pw_gid, groups, fn)


def mode_of(path: Path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


class Room:
    """The kit loaded with its folders under ``root``; makes and removes lfdt- accounts."""

    def __init__(self, root: Path, monkeypatch):
        self.root = root
        self.tag = secrets.token_hex(3)
        self.group = f"{PREFIX}edu-{self.tag}"
        self.class_dir = root / "srv" / "class"
        self.state_dir = root / "srv" / "state"
        notebooks = root / "notebooks"
        notebooks.mkdir()
        (notebooks / "00_start.ipynb").write_text("{}")
        for key, value in {
            "LFD_CLASS_DIR": str(self.class_dir),
            "LFD_HUB_STATE_DIR": str(self.state_dir),
            "LFD_NOTEBOOKS": str(notebooks),
            "LFD_EDUCATORS_GROUP": self.group,
        }.items():
            monkeypatch.setenv(key, value)
        for key in ("LFD_HUB_IP", "LFD_HUB_PORT", "LFD_CPU_LIMIT", "LFD_IDLE_TIMEOUT"):
            monkeypatch.delenv(key, raising=False)
        self.names: list[str] = []
        self.kit = None

    def name(self, who: str) -> str:
        name = f"{PREFIX}{who}-{self.tag}"
        self.names.append(name)
        return name

    def load(self):
        self.kit = load_kit()
        assert self.kit.switches_users(), "as root the kit must switch users"
        return self.kit

    def spawn(self, name: str, admin: bool = False):
        spawner = SimpleNamespace(
            user=SimpleNamespace(name=name, admin=admin), environment={}, notebook_dir=""
        )
        self.kit.pre_spawn_hook(spawner)
        return spawner

    def cleanup(self) -> None:
        for name in self.names:
            try:
                pwd.getpwnam(name)
            except KeyError:
                continue
            subprocess.run(["userdel", "--remove", name], capture_output=True, check=False)
        for name in (self.group, *self.names):
            try:
                grp.getgrnam(name)
            except KeyError:
                continue
            subprocess.run(["groupdel", name], capture_output=True, check=False)


def load_kit():
    """Execute deploy/jupyterhub_config.py as JupyterHub's config loader would."""
    from traitlets.config import Config

    spec = importlib.util.spec_from_file_location("lfd_hub_kit_under_test", KIT_CONFIG)
    module = importlib.util.module_from_spec(spec)
    config = Config()
    module.get_config = lambda: config
    spec.loader.exec_module(module)
    return module


@pytest.fixture(autouse=True)
def no_kernel_warming(monkeypatch):
    """The kit compiles the room's kernels as it loads; only the test of it asks for that."""
    monkeypatch.setenv("LFD_KERNEL_CACHE", "off")


@pytest.fixture
def umask_000():
    """The hub started under umask 000 (and the test's own umask back afterwards)."""
    old = os.umask(0)
    yield
    os.umask(old)


@pytest.fixture
def scratch():
    """A scratch folder other accounts may pass through (pytest's tmp_path is in a 0700
    folder of root's)."""
    root = Path(tempfile.mkdtemp(prefix=PREFIX, dir="/tmp"))
    os.chmod(root, 0o755)
    yield root
    shutil.rmtree(root, ignore_errors=True)


@pytest.fixture
def room(scratch, monkeypatch, umask_000):
    made = Room(scratch, monkeypatch)
    try:
        yield made
    finally:
        made.cleanup()


# ---------------------------------------------------------------- the hook


def test_umask_000_gives_exact_folder_modes(room):
    kit = room.load()
    os.umask(0)  # the kit sets its own umask; the folders' modes must not depend on it
    trainee = room.name("a")
    room.spawn(trainee)
    group = grp.getgrnam(room.group).gr_gid
    folder = room.class_dir / trainee
    assert mode_of(room.state_dir) == 0o700
    assert mode_of(room.class_dir) == 0o2751
    assert mode_of(folder) == 0o2750
    assert (os.stat(room.class_dir).st_uid, os.stat(room.class_dir).st_gid) == (0, group)
    assert (os.stat(folder).st_uid, os.stat(folder).st_gid) == (
        pwd.getpwnam(trainee).pw_uid,
        group,
    )
    assert pwd.getpwnam(trainee).pw_gecos == kit.ACCOUNT_MARK
    for where, dirs, files in os.walk(room.root / "srv"):
        for entry in (where, *(Path(where) / n for n in dirs + files)):
            assert not mode_of(Path(entry)) & 0o002, f"{entry} is world-writable"


def test_a_planted_link_never_changes_the_file_it_points_at(room):
    room.load()
    trainee = room.name("b")
    room.spawn(trainee)
    folder = room.class_dir / trainee
    outside = room.root / "outside"
    outside.mkdir()
    target = outside / "root-file"
    target.write_text("root's")
    os.chmod(target, 0o644)
    (outside / "inner").mkdir()
    inner = outside / "inner" / "deep-file"
    inner.write_text("root's too")
    # what the trainee plants between two server starts (made here as root)
    (folder / "innocent.json").symlink_to(target)
    (folder / "runs").symlink_to(outside / "inner", target_is_directory=True)
    os.link(target, folder / "hard.json")  # fs.protected_hardlinks stops a trainee, not root
    (folder / "from-the-educator.json").write_text("{}")  # a real file root put there
    room.spawn(trainee)
    for path in (target, inner, outside / "inner"):
        info = os.stat(path)
        assert (info.st_uid, info.st_gid) == (0, 0), f"{path} changed owner"
    assert mode_of(target) == 0o644
    assert (folder / "innocent.json").is_symlink(), "the link is left where it was"
    assert os.lstat(folder / "innocent.json").st_uid == 0, "the link itself is not chowned"
    owner = pwd.getpwnam(trainee).pw_uid
    assert os.stat(folder / "from-the-educator.json").st_uid == owner


def test_a_name_colliding_with_another_folder_is_refused_untouched(room):
    room.load()
    room.spawn(room.name("first"))  # the class folder exists
    name = room.name("backup")
    planted = room.class_dir / name
    planted.mkdir()
    os.chmod(planted, 0o700)
    (planted / "secret.json").write_text("{}")
    os.chmod(planted / "secret.json", 0o600)
    before = {p: (os.lstat(p).st_uid, os.lstat(p).st_gid, mode_of(p))
              for p in (planted, planted / "secret.json")}
    with pytest.raises(InvalidParameterError, match="is taken"):
        room.spawn(name)
    after = {p: (os.lstat(p).st_uid, os.lstat(p).st_gid, mode_of(p)) for p in before}
    assert after == before


def test_an_account_the_hub_did_not_make_is_refused(room):
    room.load()
    existing = room.name("human")
    subprocess.run(["useradd", "--comment", "a person", existing], check=True)
    with pytest.raises(InvalidParameterError, match="did not make"):
        room.spawn(existing)
    assert not (room.class_dir / existing).exists()
    with pytest.raises(InvalidParameterError, match="did not make"):
        room.spawn("root")
    with pytest.raises(InvalidParameterError, match="educators' group"):
        room.spawn(room.group)


def test_the_educators_group_reads_every_run_and_trainees_read_only_their_own(room):
    room.load()
    alice, bob = room.name("alice"), room.name("bob")
    room.spawn(alice)
    room.spawn(bob)
    educator = room.name("teacher")  # the educator's own, non-root account
    subprocess.run(["useradd", "--groups", room.group, educator], check=True)
    folder = room.class_dir / alice

    def save_a_run():  # what alice's tutor does: a subfolder, then an atomic write
        from tutor.fileio import write_json

        write_json(folder / "alice" / "NF.json", {"demos": 3})
        return oct(stat.S_IMODE(os.stat(folder / "alice" / "NF.json").st_mode))

    assert as_user(alice, save_a_run) == {"ok": "0o640"}

    def read_alices_run():
        names = sorted(os.listdir(folder))
        return names, json.loads((folder / "alice" / "NF.json").read_text())

    assert as_user(educator, read_alices_run) == {"ok": [["alice"], {"demos": 3}]}
    assert as_user(bob, read_alices_run)["error"] == "PermissionError"
    assert as_user(bob, lambda: os.listdir(room.class_dir))["error"] == "PermissionError"
    plan = room.class_dir / "plan.csv"
    plan.write_text("trainee,condition\n")
    os.chmod(plan, 0o644)
    assert as_user(bob, lambda: plan.read_text()) == {"ok": "trainee,condition\n"}


def test_an_educator_admin_joins_the_educators_group(room):
    room.load()
    educator = room.name("admin")
    spawner = room.spawn(educator, admin=True)
    assert educator in grp.getgrnam(room.group).gr_mem
    assert spawner.environment["TUTOR_CLASS_DIR"] == str(room.class_dir)


# ---------------------------------------------------------------- compiled kernels


def test_trainees_start_from_the_rooms_compiled_kernels_and_cannot_change_them(
    room, monkeypatch
):
    seed = room.root / "srv" / "kernels"
    monkeypatch.setenv("LFD_KERNEL_CACHE", str(seed))
    # a package named tutor where the hub is started: root must never import it
    planted = room.root / "planted"
    marker = room.root / "planted-ran"
    (planted / "tutor").mkdir(parents=True)
    (planted / "tutor" / "__init__.py").write_text("")
    (planted / "tutor" / "__main__.py").write_text(
        f"open({str(marker)!r}, 'w').close()\nraise SystemExit(3)\n"
    )
    monkeypatch.chdir(planted)
    kit = room.load()
    assert kit.WARMING.wait(timeout=600) == 0, (room.state_dir / "kernel-cache.log").read_text()
    assert not marker.exists()
    kernels = sorted(p for p in seed.rglob("*") if p.is_file())
    assert kernels and all(p.suffix in (".nbi", ".nbc") for p in kernels)
    # every trainee may read the room's kernels, only the hub (root) may change them
    assert mode_of(seed) == 0o755 and os.stat(seed).st_uid == 0
    for p in (seed, *seed.rglob("*")):
        assert mode_of(p) == (0o755 if p.is_dir() else 0o644), p

    trainee = room.name("k")
    spawner = room.spawn(trainee)
    env = {k: v(spawner) if callable(v) else v for k, v in kit.c.Spawner.environment.items()}
    home = Path(pwd.getpwnam(trainee).pw_dir)
    own = home / ".cache" / "lfd-tutor-kernels"
    assert env["NUMBA_CACHE_DIR"] == str(own) and env["TUTOR_KERNEL_CACHE_SEED"] == str(seed)

    def seed_as_trainee():  # what tutor.compiled does on import in the trainee's kernel
        from tutor.compiled import seed_cache

        return seed_cache(env["TUTOR_KERNEL_CACHE_SEED"], env["NUMBA_CACHE_DIR"])

    assert as_user(trainee, seed_as_trainee) == {"ok": len(kernels)}
    uid = pwd.getpwnam(trainee).pw_uid
    assert all(os.stat(p).st_uid == uid for p in own.rglob("*"))
    assert sorted(p.relative_to(own) for p in own.rglob("*") if p.is_file()) == sorted(
        p.relative_to(seed) for p in kernels
    )

    def tamper():  # a trainee cannot plant code in what the room's kernels are copied from
        (kernels[0].parent / "planted.nbc").write_bytes(b"x")

    assert as_user(trainee, tamper)["error"] == "PermissionError"
    assert as_user(trainee, lambda: kernels[0].write_bytes(b"x"))["error"] == "PermissionError"


def test_the_kit_can_leave_kernels_to_each_trainee(room):
    kit = room.load()  # LFD_KERNEL_CACHE=off (the fixture)
    assert kit.WARMING is None and kit.KERNEL_SEED is None
    assert set(kit.c.Spawner.environment) == {"TUTOR_RUNS_DIR"}


def test_a_relative_kernel_folder_is_made_absolute_for_the_trainees(room, monkeypatch):
    monkeypatch.chdir(room.root)
    monkeypatch.setenv("LFD_KERNEL_CACHE", "kernels")
    kit = room.load()
    kit.WARMING.wait(timeout=600)
    # a trainee's server runs elsewhere: the seed it is given must not depend on that
    assert kit.KERNEL_SEED == room.root / "kernels" and kit.KERNEL_SEED.is_absolute()
    assert kit.c.Spawner.environment["TUTOR_KERNEL_CACHE_SEED"] == str(room.root / "kernels")


# ---------------------------------------------------------------- the settings


@pytest.mark.parametrize(
    ("variable", "value", "says"),
    [
        ("LFD_HUB_PORT", "-1", "from 1 to 65535"),
        ("LFD_HUB_PORT", "70000", "from 1 to 65535"),
        ("LFD_HUB_PORT", "abc", "from 1 to 65535"),
        ("LFD_HUB_IP", "", "IP address"),
        ("LFD_HUB_IP", "not-an-ip", "IP address"),
        ("LFD_CPU_LIMIT", "nan", "from 0.01 to 1024"),
        ("LFD_IDLE_TIMEOUT", "0", "from 1 to"),
        ("LFD_EDUCATORS_GROUP", "Educators!", "group name"),
        ("LFD_KERNEL_CACHE", "/srv/" + "k" * 300, "more than the 255 a file name can have"),
    ],
)
def test_bad_settings_stop_the_hub_with_a_message(tmp_path, monkeypatch, variable, value, says):
    monkeypatch.setenv("LFD_HUB_STATE_DIR", str(tmp_path / "state"))
    monkeypatch.setenv("LFD_CLASS_DIR", str(tmp_path / "class"))
    monkeypatch.setenv(variable, value)
    old = os.umask(0o022)
    try:
        with pytest.raises(SystemExit) as stopped:
            load_kit()
    finally:
        os.umask(old)
    message = str(stopped.value)
    assert variable in message and says in message, message


def test_good_settings_are_taken(tmp_path, monkeypatch):
    monkeypatch.setenv("LFD_HUB_STATE_DIR", str(tmp_path / "state"))
    monkeypatch.setenv("LFD_HUB_PORT", "8123")
    monkeypatch.setenv("LFD_HUB_IP", "0.0.0.0")
    old = os.umask(0o022)
    try:
        kit = load_kit()
    finally:
        os.umask(old)
    assert (kit.c.JupyterHub.port, kit.c.JupyterHub.ip) == (8123, "0.0.0.0")
    # the services root starts import nothing from the folder the hub was started in
    for service in kit.c.JupyterHub.services:
        if "command" in service:
            assert service["command"][1] == "-I" and service["cwd"] == str(tmp_path / "state")


# ---------------------------------------------------------------- the class analysis


def test_the_class_analysis_says_which_trainee_folders_it_cannot_read(scratch):
    from tutor.study.classroom import read_class
    from tutor.study.dashboard import ClassDashboard

    class_dir = scratch / "class"
    (class_dir / "open" / "someone").mkdir(parents=True)
    shut = class_dir / "shut"
    (shut / "someone").mkdir(parents=True)
    (shut / "someone" / "NF.json").write_text("{}")
    for path in (class_dir, class_dir / "open", class_dir / "open" / "someone"):
        os.chmod(path, 0o755)
    daemon, nobody = pwd.getpwnam("daemon"), pwd.getpwnam("nobody")
    os.chown(shut, daemon.pw_uid, daemon.pw_gid)  # another account's folder, mode 000
    os.chmod(shut, 0)
    # as root first, so that every module is imported before the child drops root
    assert "cannot read" not in ClassDashboard(class_dir, experiment=1).status.value

    def read_as_educator():
        result = read_class(class_dir, experiment=1, workers=1)
        board = ClassDashboard(class_dir, experiment=1)
        files = [f.file for f in result.unreadable_folders]
        return files, result.cannot_read_note, board.status.value, board.problems.value

    out = as_account(nobody.pw_uid, nobody.pw_gid, [nobody.pw_gid], read_as_educator)
    files, note, status, problems = out["ok"]
    assert files == ["shut/"], out
    assert "You cannot read 1 trainee folder " in note
    assert "You cannot read 1 trainee folder " in status  # the dashboard says it
    assert "shut/" in problems and "you cannot read this trainee folder" in problems
    # as root every folder is read, and nothing is said
    assert read_class(class_dir, experiment=1, workers=1).cannot_read_note == ""


# ---------------------------------------------------------------- Kubernetes values

VALUES = REPO / "deploy" / "z2jh-values.yaml"


def z2jh_values() -> dict:
    import yaml

    return yaml.safe_load(VALUES.read_text())


def class_mounts(mounts) -> list[dict]:
    return [m for m in mounts if m["name"] == "lfd-class"]


def test_each_trainee_pod_mounts_only_its_own_folder_of_the_class_volume():
    values = z2jh_values()["singleuser"]
    mounts = class_mounts(values["storage"]["extraVolumeMounts"])
    assert mounts, "no mount of the class volume"
    for mount in mounts:
        assert "{username}" in mount.get("subPath", ""), f"a trainee mounts the root: {mount}"
    assert values["extraEnv"]["TUTOR_RUNS_DIR"] == mounts[0]["mountPath"]
    trainee = [p for p in values["profileList"] if p["slug"] == "trainee"]
    assert trainee and trainee[0].get("default") is True
    assert "kubespawner_override" not in trainee[0]
    # every pod has one uid: the subPath, not file modes, keeps trainees apart
    assert values["uid"] == 1000 and values["fsGid"] == 100


def test_the_educator_profile_reads_the_class_volume_and_only_admins_get_it():
    values = z2jh_values()
    educator = next(p for p in values["singleuser"]["profileList"] if p["slug"] == "educator")
    mounts = class_mounts(educator["kubespawner_override"]["volume_mounts"])
    assert mounts and all(m.get("readOnly") is True and "subPath" not in m for m in mounts)
    assert educator["kubespawner_override"]["environment"]["TUTOR_CLASS_DIR"] == (
        mounts[0]["mountPath"]
    )
    # the chart's config as z2jh leaves it before extraConfig: the home mount, then
    # singleuser.storage.extraVolumeMounts, and singleuser.profileList
    from traitlets.config import Config

    c = Config()
    home = {"name": "volume-{user_server}", "mountPath": "/home/jovyan"}
    c.KubeSpawner.volume_mounts = [home, *values["singleuser"]["storage"]["extraVolumeMounts"]]
    c.KubeSpawner.profile_list = values["singleuser"]["profileList"]
    exec(values["hub"]["extraConfig"]["lfd-isolation"], {"c": c})  # noqa: S102
    offer = c.KubeSpawner.profile_list
    trainee = SimpleNamespace(user=SimpleNamespace(name="t", admin=False))
    admin = SimpleNamespace(user=SimpleNamespace(name="e", admin=True))
    assert [p["slug"] for p in offer(trainee)] == ["trainee"]
    assert [p["slug"] for p in offer(admin)] == ["trainee", "educator"]
    got = offer(admin)[1]["kubespawner_override"]["volume_mounts"]
    assert got[0] == home
    assert class_mounts(got) == mounts, "the educator must not get a trainee's subPath mount"
