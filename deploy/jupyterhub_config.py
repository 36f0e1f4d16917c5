"""JupyterHub for a workshop room on one machine: the lfd-tutor hub kit.

Run (as root, from the environment where ``lfd-tutor[hub]`` is installed)::

    LFD_WORKSHOP_PASSWORD='a-room-password' LFD_ADMIN_PASSWORD='32+ characters...' \\
        jupyterhub -f deploy/jupyterhub_config.py

What it sets up (deploy/README.md has the how-to):

- JupyterHub from PyPI and configurable-http-proxy from npm, found in
  ``deploy/node_modules``, ``.hub/node_modules`` (what ``scripts/test.sh`` installs) or
  on PATH; startup stops with a message saying how to install it if it is missing.
- A shared workshop password (JupyterHub's ``shared-password`` authenticator): every
  trainee logs in with a name of their choice and ``LFD_WORKSHOP_PASSWORD``; the
  educators listed in ``LFD_ADMINS`` log in with ``LFD_ADMIN_PASSWORD``. Anyone with the
  room password can log in as any non-admin trainee: this suits a room, not the internet.
- Local processes, one single-user server per trainee. Memory limits
  (``LFD_MEM_LIMIT``, default 1G) are *enforced* only by systemdspawner (used, as The
  Littlest JupyterHub does, when it is installed and the hub runs as root).
  LocalProcessSpawner does **not** enforce ``mem_limit``: it only tells the server
  (``MEM_LIMIT`` in its environment); one trainee's kernel can then use the whole
  machine. Without root the hub cannot switch users, so it falls back to
  SimpleLocalProcessSpawner: every server runs as the hub's own user with a home under
  the hub's state folder, and trainees are *not* isolated from each other.
- The idle culler (jupyterhub-idle-culler) as a hub service: servers idle for
  ``LFD_IDLE_TIMEOUT`` seconds (default 3600) are stopped; their runs are saved already.
- The class folder ``LFD_CLASS_DIR`` (default /srv/lfd-class): each trainee's
  ``TUTOR_RUNS_DIR`` is ``<class folder>/<user name>``, made before their server
  starts, so the educator collects every run with ``lfd-tutor class <class folder>``.
  As root the class folder is root:``LFD_EDUCATORS_GROUP`` (default lfd-educators) 2751
  and each trainee folder trainee:educators 2750 (setgid), modes set explicitly whatever
  the umask: the educators' own accounts read every run, a trainee only their own. The
  hook never follows a link, and refuses a name whose folder or account the hub did not
  make for that trainee (see :func:`claim_folder`, :func:`ensure_account`, :func:`give`).
  ``TUTOR_CLASS_PLAN`` points at ``<class folder>/plan.csv`` (or ``plan.json``) when
  the educator wrote one (Experiment 2's conditions). Admins (educators) get
  ``TUTOR_CLASS_DIR`` = the class folder, which notebook 05's dashboard reads.
- Each trainee gets their own copy of the notebooks (``LFD_NOTEBOOKS``, default the
  repository's ``notebooks/``) in ``~/lfd-notebooks``, which JupyterLab opens.
- The hub listens on 127.0.0.1:8000 unless ``LFD_HUB_IP`` (e.g. ``0.0.0.0`` to let the
  room's laptops in) and ``LFD_HUB_PORT`` say otherwise. Servers and kernels listen on
  loopback only.
- The tutor's compiled kernels (numba) are compiled once for the room as the hub starts,
  into ``LFD_KERNEL_CACHE`` (default: the state folder's name + ``-kernels`` beside it,
  0755, readable by every trainee, written only by the hub; ``off`` to skip), and each
  trainee's cache starts as a copy of it, so no trainee's first demo waits about 5 s
  for numba (numba will not read a cache it cannot write; see ``tutor.compiled``).
- Behind the hub the 3-D view uses its server-free widget mode (JupyterHub sets
  ``JUPYTERHUB_SERVICE_PREFIX``, which ``tutor.views.scene_page.choose_mode`` reads):
  no Meshcat port is opened per trainee, so no trainee can reach another's scene.

A test config can ``load_subconfig`` this file and override what it needs (see
tests/hub/hubkit.py).
"""

from __future__ import annotations

import grp
import importlib.util
import ipaddress
import json
import os
import pwd
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

from tutor.errors import InvalidParameterError, SaveError
from tutor.fileio import check_file_name, write_json

c = get_config()  # noqa: F821 (JupyterHub's config loader provides it)

# the hub, the proxy and every server they start make files for the owner and its group
# only, whatever umask the hub was started with (the hook's folders have explicit modes)
os.umask(0o027)

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
IS_ROOT = os.geteuid() == 0

CLASS_DIR = Path(os.environ.get("LFD_CLASS_DIR", "/srv/lfd-class"))
STATE_DIR = Path(os.environ.get("LFD_HUB_STATE_DIR", "/srv/lfd-hub"))
NOTEBOOKS = Path(os.environ.get("LFD_NOTEBOOKS", str(REPO / "notebooks")))
#: user and group names the hub accepts (and, as root, makes system accounts of)
NAME_PATTERN = r"^[a-z][a-z0-9_-]{0,31}$"
#: the folder modes, set explicitly (never the umask's): the class folder is
#: root:educators, setgid (what is made in it takes the educators' group); trainees may
#: pass through it to their own folder but not list it. Each trainee folder is
#: trainee:educators, setgid: the trainee writes, the educators read, nobody else enters.
STATE_MODE, CLASS_MODE, TRAINEE_MODE, PARENT_MODE = 0o700, 0o2751, 0o2750, 0o755
#: the comment (GECOS field) of the system accounts the hub makes: an existing account
#: without it (``root``, ``backup``, a person's own login) is never given to a trainee
ACCOUNT_MARK = "lfd-tutor hub trainee"
#: the hub's record of the trainee folders it made: user name -> [device, inode]
FOLDER_RECORD = STATE_DIR / "trainee-folders.json"
#: the folder, in each trainee's home, that holds their copy of the notebooks
NOTEBOOK_FOLDER = "lfd-notebooks"
#: the class plan file names the tutor reads (first one found)
PLAN_FILES = ("plan.csv", "plan.json")


def find_proxy() -> str:
    """The configurable-http-proxy script: deploy/ or .hub/ node_modules, else PATH."""
    for folder in (HERE, REPO / ".hub"):
        script = folder / "node_modules" / ".bin" / "configurable-http-proxy"
        if script.exists():
            return str(script)
    found = shutil.which("configurable-http-proxy")
    if found:
        return found
    sys.exit(
        "lfd-tutor hub kit: configurable-http-proxy is missing. Install it with\n"
        f"    npm install --prefix {HERE} configurable-http-proxy\n"
        "(or 'apt-get install node-configurable-http-proxy' on Debian), then start again."
    )


def env_number(name: str, default, kind=int, low=None, high=None):
    """The environment variable ``name`` as a number of type ``kind`` from ``low`` to
    ``high`` (else ``default`` when it is unset or blank); anything else stops the hub
    with a message naming the variable and what it may be."""
    value = os.environ.get(name, "").strip()
    if not value:
        return default
    what = "a whole number" if kind is int else "a number"
    allowed = f"{what} from {low} to {high}"
    try:
        number = kind(value)
    except ValueError:
        sys.exit(f"lfd-tutor hub kit: {name} is {value!r}; set it to {allowed}")
    if not low <= number <= high:  # NaN fails too
        sys.exit(f"lfd-tutor hub kit: {name} is {value!r}, out of range; set it to {allowed}")
    return number


def env_ip(name: str, default: str) -> str:
    """The environment variable ``name`` as an IP address (``default`` when unset).

    Set but empty is refused: JupyterHub would take an empty address as every interface.
    """
    value = os.environ.get(name)
    if value is None:
        return default
    try:
        return str(ipaddress.ip_address(value.strip()))
    except ValueError:
        sys.exit(
            f"lfd-tutor hub kit: {name} is {value!r}; set it to an IP address: 127.0.0.1 "
            "(this machine only) or 0.0.0.0 (every interface, to let the room's laptops in)"
        )


def env_name(name: str, default: str) -> str:
    """The environment variable ``name`` as a user or group name (``default`` if unset)."""
    value = os.environ.get(name, default).strip()
    if not re.fullmatch(NAME_PATTERN, value):
        sys.exit(
            f"lfd-tutor hub kit: {name} is {value!r}; set it to a group name of lower-case "
            "letters, digits, - and _ (starting with a letter, at most 32 characters)"
        )
    return value


def env_folder(name: str, default: Path) -> Path:
    """The environment variable ``name`` as an absolute folder path (``default`` when unset
    or blank): a relative one is taken from the folder the hub starts in, and a path no
    file system can hold (a NUL character, a name over 255 bytes) stops the hub."""
    value = os.environ.get(name, "").strip() or str(default)
    problem = check_file_name(value)
    if problem:
        sys.exit(f"lfd-tutor hub kit: {name} is not a usable folder ({problem}); set it "
                 "to a folder path such as /srv/lfd-hub-kernels")
    return Path(os.path.abspath(value))


#: the group whose members (the educators' own accounts) read every trainee's folder
EDUCATORS = env_name("LFD_EDUCATORS_GROUP", "lfd-educators")


def open_folder(path: Path) -> int:
    """A file descriptor of the folder ``path`` itself, never of what a link points at."""
    return os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)


def set_folder(path: Path, mode: int, uid: int = -1, gid: int = -1) -> None:
    """Give the folder ``path`` (not a link: refused) its owner and exact ``mode``."""
    try:
        fd = open_folder(path)
    except OSError as exc:
        raise SaveError(
            f"{path} is not a folder the hub can use ({exc.strerror}): it must be a real "
            "folder, not a link or a file; give the real path or move it aside"
        ) from exc
    try:
        os.fchown(fd, uid, gid)
        os.fchmod(fd, mode)
    except OSError as exc:
        raise SaveError(
            f"the hub cannot set the owner and mode of {path} ({exc.strerror}): run it as "
            "root, or as the folder's owner"
        ) from exc
    finally:
        os.close(fd)


def make_folder(path: Path, mode: int, uid: int = -1, gid: int = -1) -> None:
    """Make the folder ``path`` (and missing parents, 0755) with exactly ``mode``.

    ``os.mkdir`` is given 0700 and the mode is set after, so the umask never decides who
    may enter.
    """
    for parent in reversed(path.parents):
        if not parent.exists():
            make_folder(parent, PARENT_MODE)
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    set_folder(path, mode, uid, gid)


# ---------------------------------------------------------------- hub and proxy

try:
    make_folder(STATE_DIR, STATE_MODE)
except OSError as exc:
    sys.exit(
        f"lfd-tutor hub kit: cannot make the hub's state folder {STATE_DIR} ({exc}); "
        "run as root or set LFD_HUB_STATE_DIR to a folder you can write to"
    )
c.JupyterHub.ip = env_ip("LFD_HUB_IP", "127.0.0.1")
c.JupyterHub.port = env_number("LFD_HUB_PORT", 8000, low=1, high=65535)
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.db_url = f"sqlite:///{STATE_DIR / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(STATE_DIR / "jupyterhub_cookie_secret")
c.ConfigurableHTTPProxy.command = [find_proxy()]
c.ConfigurableHTTPProxy.pid_file = str(STATE_DIR / "jupyterhub-proxy.pid")

# ---------------------------------------------------------------- who logs in

c.JupyterHub.authenticator_class = "shared-password"
c.SharedPasswordAuthenticator.user_password = os.environ.get("LFD_WORKSHOP_PASSWORD") or None
c.SharedPasswordAuthenticator.admin_password = os.environ.get("LFD_ADMIN_PASSWORD") or None
c.Authenticator.admin_users = {
    name.strip() for name in os.environ.get("LFD_ADMINS", "educator").split(",") if name.strip()
}
# anyone with the room password may log in under a name of their choice
c.Authenticator.allow_all = True
# names become folder names (and, as root, system accounts): letters, digits, - and _
c.Authenticator.username_pattern = NAME_PATTERN

# ---------------------------------------------------------------- one server per trainee

if IS_ROOT and importlib.util.find_spec("systemdspawner") is not None:
    # enforces mem_limit and cpu_limit through systemd (MemoryMax, CPUQuota), as TLJH
    c.JupyterHub.spawner_class = "systemdspawner.SystemdSpawner"
    c.SystemdSpawner.isolate_tmp = True
    c.SystemdSpawner.isolate_devices = True
    c.SystemdSpawner.disable_user_sudo = True
elif IS_ROOT:
    # LocalProcessSpawner does NOT enforce mem_limit (it only passes MEM_LIMIT along)
    c.JupyterHub.spawner_class = "localprocess"
else:
    # no root, no switching users: every server runs as the hub's user (not isolated)
    c.JupyterHub.spawner_class = "simple"
    c.SimpleLocalProcessSpawner.home_dir_template = str(STATE_DIR / "homes" / "{username}")

c.Spawner.mem_limit = os.environ.get("LFD_MEM_LIMIT", "1G")
c.Spawner.cpu_limit = env_number("LFD_CPU_LIMIT", 1.0, float, low=0.01, high=1024)
# the single-user server of this very environment (where lfd-tutor is installed)
c.Spawner.cmd = [str(Path(sys.executable).with_name("jupyterhub-singleuser"))]
c.Spawner.default_url = "/lab"
c.Spawner.ip = "127.0.0.1"
c.Spawner.http_timeout = 120
c.Spawner.start_timeout = 180

# ---------------------------------------------------------------- compiled kernels

#: the kernels compiled once for the whole room (numba's cache, readable by every
#: trainee, written only by the hub); LFD_KERNEL_CACHE=off leaves each trainee to
#: compile their own on their first demo (about 5 s each)
KERNEL_SEED = None if os.environ.get("LFD_KERNEL_CACHE", "").strip() == "off" else env_folder(
    "LFD_KERNEL_CACHE", STATE_DIR.with_name(f"{STATE_DIR.name}-kernels")
)


def warm_kernel_seed(folder: Path) -> subprocess.Popen:
    """Compile the tutor's kernels into ``folder`` in the background (``lfd-tutor warm``:
    about 8 s, a second or two once it is current) and return the process.

    The folder is 0755 and what numba writes in it 0644 (umask 022 for that process
    only), so trainees may read it but not change it. Each trainee's server gets its
    own ``NUMBA_CACHE_DIR`` and ``TUTOR_KERNEL_CACHE_SEED`` naming this folder: the tutor
    copies the kernels in on import (``tutor.compiled.seed_cache``). A trainee whose
    first demo comes before the hub has finished compiles what is still missing.
    """
    try:
        make_folder(folder, 0o755)
    except (OSError, SaveError) as exc:
        sys.exit(
            f"lfd-tutor hub kit: cannot make the compiled-kernel folder {folder} ({exc}); "
            "set LFD_KERNEL_CACHE to a folder the hub can write (or to off)"
        )
    log = open(STATE_DIR / "kernel-cache.log", "ab")  # noqa: SIM115 (the child keeps it)
    # isolated (-I: no current folder, user site or PYTHON* variables on its path) and run
    # from the hub's own 0700 state folder: as root, nothing a trainee can write is imported
    return subprocess.Popen(
        [sys.executable, "-I", "-m", "tutor", "warm"],
        env={**os.environ, "NUMBA_CACHE_DIR": str(folder)},
        cwd=STATE_DIR,
        stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, umask=0o022,
    )


def trainee_kernel_cache(spawner) -> str:
    """The trainee's own compiled-kernel cache (in their home), seeded from the room's."""
    return str(user_home(spawner) / ".cache" / "lfd-tutor-kernels")



def trainee_folder(spawner) -> Path:
    """The trainee's ``TUTOR_RUNS_DIR``: ``<class folder>/<user name>``."""
    return CLASS_DIR / spawner.user.name


def class_plan() -> Path | None:
    """The class plan file in the class folder (``TUTOR_CLASS_PLAN``), or None."""
    for name in PLAN_FILES:
        if (CLASS_DIR / name).is_file():
            return CLASS_DIR / name
    return None


def user_home(spawner) -> Path:
    """The home folder the trainee's server runs in."""
    home = getattr(spawner, "home_dir", "")  # SimpleLocalProcessSpawner
    if home:
        return Path(home)
    return Path(pwd.getpwnam(spawner.user.name).pw_dir)


def switches_users() -> bool:
    """True when servers run as the trainees' own accounts (root, not the simple spawner)."""
    return IS_ROOT and c.JupyterHub.spawner_class != "simple"


def run_tool(command: list[str]) -> None:
    """Run ``useradd``, ``groupadd`` or ``usermod``; a failure is said in plain words."""
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SaveError(
            f"the hub could not run {' '.join(command)!r}: {done.stderr.strip()}; the "
            "server was not started"
        )


def ensure_group(name: str) -> int:
    """As root, the educators' group id (the group is made if missing)."""
    try:
        return grp.getgrnam(name).gr_gid
    except KeyError:
        run_tool(["groupadd", name])
        return grp.getgrnam(name).gr_gid


def ensure_account(name: str, educator: bool) -> pwd.struct_passwd:
    """As root, the system account a local-process server runs as (made, as TLJH does).

    An account the hub made carries :data:`ACCOUNT_MARK` as its comment. Any other
    account of that name (``root``, ``backup``, a person's own login) is refused, except
    for an educator (a hub admin, who logs in with the admin password): their own
    account is used. Educators are put in the educators' group.
    """
    if name == EDUCATORS:
        raise InvalidParameterError(
            f"the user name {name!r} is the educators' group's name: log in under another name"
        )
    try:
        account = pwd.getpwnam(name)
    except KeyError:
        run_tool(["useradd", "--create-home", "--shell", "/bin/bash", "--comment",
                  ACCOUNT_MARK, name])
        account = pwd.getpwnam(name)
    if account.pw_gecos != ACCOUNT_MARK and not educator:
        raise InvalidParameterError(
            f"the user name {name!r} is an account of this machine that the hub did not "
            "make for a trainee: log in under another name"
        )
    if educator and name not in grp.getgrnam(EDUCATORS).gr_mem:
        run_tool(["usermod", "--append", "--groups", EDUCATORS, name])
    return account


def give(path: Path, uid: int, gid: int) -> None:
    """Give ``path`` and what it holds to ``uid``:``gid``, never through a link.

    The walk holds each folder open (``os.fwalk``, which does not enter a link, even one
    swapped in while it walks) and changes each entry relative to it without following
    it. Links are left as they are (not removed, their owner unchanged); a file with more
    than one hard link (perhaps a link to a file elsewhere) is left too.
    """
    fd = open_folder(path)
    try:
        os.fchown(fd, uid, gid)
    finally:
        os.close(fd)
    for _, dirnames, filenames, dirfd in os.fwalk(path, follow_symlinks=False):
        for name in dirnames + filenames:
            info = os.stat(name, dir_fd=dirfd, follow_symlinks=False)
            if stat.S_ISLNK(info.st_mode):
                continue
            if not stat.S_ISDIR(info.st_mode) and info.st_nlink > 1:
                continue
            os.chown(name, uid, gid, dir_fd=dirfd, follow_symlinks=False)


def read_record() -> dict:
    """The hub's record of the trainee folders it made (:data:`FOLDER_RECORD`)."""
    try:
        return json.loads(FOLDER_RECORD.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    except (OSError, ValueError) as exc:
        raise SaveError(
            f"the hub's record of trainee folders {FOLDER_RECORD} cannot be read ({exc}): "
            "restore it from a backup, or remove it and move the trainee folders aside"
        ) from exc


def claim_folder(name: str, uid: int, gid: int) -> Path:
    """The trainee's folder ``<class folder>/<name>``: made now, or one the hub made for
    this trainee before; any other folder of that name is refused, untouched.

    "Made by the hub for this trainee" means: the hub's record (in its state folder,
    which only the hub's user can write) holds the folder's device and inode under this
    name and, when servers run as the trainees' accounts, the folder belongs to the
    trainee's account. Trainees cannot make folders in the class folder.
    """
    folder = CLASS_DIR / name
    record = read_record()
    try:
        os.mkdir(folder, 0o700)
    except FileExistsError:
        info = os.lstat(folder)
        mine = record.get(name) == [info.st_dev, info.st_ino] and stat.S_ISDIR(info.st_mode)
        if not mine or (uid != -1 and info.st_uid != uid):
            raise InvalidParameterError(
                f"the user name {name!r} is taken: {folder} is a folder the hub did not make "
                "for this trainee. Log in under another name (the educator may move that "
                "folder aside)"
            ) from None
    set_folder(folder, TRAINEE_MODE, uid, gid)
    info = os.lstat(folder)
    if record.get(name) != [info.st_dev, info.st_ino]:
        write_json(FOLDER_RECORD, {**record, name: [info.st_dev, info.st_ino]})
    return folder


def pre_spawn_hook(spawner) -> None:
    """Before a server starts: its account, class folder, notebooks and class plan."""
    name, educator = spawner.user.name, bool(spawner.user.admin)
    uid = gid = group = -1
    if switches_users():
        group = ensure_group(EDUCATORS)
        account = ensure_account(name, educator)
        uid, gid = account.pw_uid, account.pw_gid
    make_folder(CLASS_DIR, CLASS_MODE, 0 if IS_ROOT else -1, group)
    folder = claim_folder(name, uid, group)
    if uid != -1:
        give(folder, uid, group)
    home = user_home(spawner)
    home.mkdir(parents=True, exist_ok=True)
    notebooks = home / NOTEBOOK_FOLDER
    if not notebooks.exists():  # a trainee's own edits are never overwritten
        shutil.copytree(NOTEBOOKS, notebooks, ignore=shutil.ignore_patterns("sessions", "runs"))
        if uid != -1:
            give(notebooks, uid, gid)
    spawner.notebook_dir = str(notebooks)
    plan = class_plan()
    if plan is not None:  # read when the server starts: a plan written later counts
        spawner.environment = {**spawner.environment, "TUTOR_CLASS_PLAN": str(plan)}
    if educator:  # the educator's dashboard (notebook 05) reads the whole class
        spawner.environment = {**spawner.environment, "TUTOR_CLASS_DIR": str(CLASS_DIR)}


c.Spawner.pre_spawn_hook = pre_spawn_hook
# callables: '{username}' is NOT expanded inside Spawner.environment values
c.Spawner.environment = {
    "TUTOR_RUNS_DIR": lambda spawner: str(trainee_folder(spawner)),
    **({} if KERNEL_SEED is None else {
        "NUMBA_CACHE_DIR": trainee_kernel_cache,
        "TUTOR_KERNEL_CACHE_SEED": str(KERNEL_SEED),
    }),
}

# ---------------------------------------------------------------- the idle culler

c.JupyterHub.services = [
    {
        "name": "idle-culler",
        # isolated (-I) and from the hub's 0700 state folder, as the kernel warm-up: the
        # hub's user (root) never imports a module from the folder it was started in
        "command": [
            sys.executable,
            "-I",
            "-m",
            "jupyterhub_idle_culler",
            f"--timeout={env_number('LFD_IDLE_TIMEOUT', 3600, low=1, high=10**7)}",
        ],
        "cwd": str(STATE_DIR),
    }
]
c.JupyterHub.load_roles = [
    {
        "name": "idle-culler",
        "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
        "services": ["idle-culler"],
    }
]

# last, once every setting above is taken: the room's kernels, compiled in the background
WARMING = None if KERNEL_SEED is None else warm_kernel_seed(KERNEL_SEED)
