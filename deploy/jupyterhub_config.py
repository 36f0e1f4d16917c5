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
  ``TUTOR_SESSION_DIR`` is ``<class folder>/<user name>``, made before their server
  starts, so the educator collects every run with ``lfd-tutor class <class folder>``.
  ``TUTOR_CLASS_PLAN`` points at ``<class folder>/plan.csv`` (or ``plan.json``) when
  the educator wrote one (Experiment 2's conditions). Admins (educators) get
  ``TUTOR_CLASS_DIR`` = the class folder, which notebook 05's dashboard reads.
- Each trainee gets their own copy of the notebooks (``LFD_NOTEBOOKS``, default the
  repository's ``notebooks/``) in ``~/lfd-notebooks``, which JupyterLab opens.
- The hub listens on 127.0.0.1:8000 unless ``LFD_HUB_IP`` (e.g. ``0.0.0.0`` to let the
  room's laptops in) and ``LFD_HUB_PORT`` say otherwise. Servers and kernels listen on
  loopback only.
- Behind the hub the 3-D view uses its server-free widget mode (JupyterHub sets
  ``JUPYTERHUB_SERVICE_PREFIX``, which ``tutor.views.scene_page.choose_mode`` reads):
  no Meshcat port is opened per trainee, so no trainee can reach another's scene.

A test config can ``load_subconfig`` this file and override what it needs (see
tests/hub/hubkit.py).
"""

from __future__ import annotations

import importlib.util
import os
import pwd
import shutil
import subprocess
import sys
from pathlib import Path

c = get_config()  # noqa: F821 (JupyterHub's config loader provides it)

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
IS_ROOT = os.geteuid() == 0

CLASS_DIR = Path(os.environ.get("LFD_CLASS_DIR", "/srv/lfd-class"))
STATE_DIR = Path(os.environ.get("LFD_HUB_STATE_DIR", "/srv/lfd-hub"))
NOTEBOOKS = Path(os.environ.get("LFD_NOTEBOOKS", str(REPO / "notebooks")))
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


def env_number(name: str, default, kind=int):
    """The environment variable ``name`` as a number of type ``kind`` (else ``default``)."""
    value = os.environ.get(name, "").strip()
    if not value:
        return default
    try:
        return kind(value)
    except ValueError:
        what = "a whole number" if kind is int else "a number"
        sys.exit(f"lfd-tutor hub kit: {name} is {value!r}; set it to {what}")


# ---------------------------------------------------------------- hub and proxy

try:
    STATE_DIR.mkdir(parents=True, exist_ok=True)
except OSError as exc:
    sys.exit(
        f"lfd-tutor hub kit: cannot make the hub's state folder {STATE_DIR} ({exc.strerror}); "
        "run as root or set LFD_HUB_STATE_DIR to a folder you can write to"
    )
c.JupyterHub.ip = os.environ.get("LFD_HUB_IP", "127.0.0.1")
c.JupyterHub.port = env_number("LFD_HUB_PORT", 8000)
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
c.Authenticator.username_pattern = r"^[a-z][a-z0-9_-]{0,31}$"

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
c.Spawner.cpu_limit = env_number("LFD_CPU_LIMIT", 1.0, float)
# the single-user server of this very environment (where lfd-tutor is installed)
c.Spawner.cmd = [str(Path(sys.executable).with_name("jupyterhub-singleuser"))]
c.Spawner.default_url = "/lab"
c.Spawner.ip = "127.0.0.1"
c.Spawner.http_timeout = 120
c.Spawner.start_timeout = 180


def trainee_folder(spawner) -> Path:
    """The trainee's ``TUTOR_SESSION_DIR``: ``<class folder>/<user name>``."""
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


def ensure_account(name: str) -> None:
    """As root, make the system account a local-process server runs as (as TLJH does)."""
    try:
        pwd.getpwnam(name)
    except KeyError:
        subprocess.run(["useradd", "--create-home", "--shell", "/bin/bash", name], check=True)


def switches_users() -> bool:
    """True when servers run as the trainees' own accounts (root, not the simple spawner)."""
    return IS_ROOT and c.JupyterHub.spawner_class != "simple"


def own(path: Path, spawner) -> None:
    """Give ``path`` (and what it holds) to the trainee's account when servers use one."""
    if switches_users():
        account = pwd.getpwnam(spawner.user.name)
        for sub in (path, *path.rglob("*")):
            os.chown(sub, account.pw_uid, account.pw_gid)


def pre_spawn_hook(spawner) -> None:
    """Before a server starts: its account, class folder, notebooks and class plan."""
    if switches_users():
        ensure_account(spawner.user.name)
    CLASS_DIR.mkdir(parents=True, exist_ok=True)
    folder = trainee_folder(spawner)
    folder.mkdir(exist_ok=True)
    folder.chmod(0o750)  # the trainee and the educator (root, or the folder's group) read it
    own(folder, spawner)
    home = user_home(spawner)
    home.mkdir(parents=True, exist_ok=True)
    notebooks = home / NOTEBOOK_FOLDER
    if not notebooks.exists():  # a trainee's own edits are never overwritten
        shutil.copytree(NOTEBOOKS, notebooks, ignore=shutil.ignore_patterns("sessions"))
        own(notebooks, spawner)
    spawner.notebook_dir = str(notebooks)
    plan = class_plan()
    if plan is not None:  # read when the server starts: a plan written later counts
        spawner.environment = {**spawner.environment, "TUTOR_CLASS_PLAN": str(plan)}
    if spawner.user.admin:  # the educator's dashboard (notebook 05) reads the whole class
        spawner.environment = {**spawner.environment, "TUTOR_CLASS_DIR": str(CLASS_DIR)}


c.Spawner.pre_spawn_hook = pre_spawn_hook
# callables: '{username}' is NOT expanded inside Spawner.environment values
c.Spawner.environment = {
    "TUTOR_SESSION_DIR": lambda spawner: str(trainee_folder(spawner)),
}

# ---------------------------------------------------------------- the idle culler

c.JupyterHub.services = [
    {
        "name": "idle-culler",
        "command": [
            sys.executable,
            "-m",
            "jupyterhub_idle_culler",
            f"--timeout={env_number('LFD_IDLE_TIMEOUT', 3600)}",
        ],
    }
]
c.JupyterHub.load_roles = [
    {
        "name": "idle-culler",
        "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
        "services": ["idle-culler"],
    }
]
