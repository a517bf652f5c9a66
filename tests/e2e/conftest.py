"""Fixtures for the browser test of the sliders: a JupyterLab server and headless Chromium.

Both run on loopback only and are always stopped at the end, passed or failed. JupyterLab serves
a throwaway copy of ``notebooks/`` (so autosave and the kernels' files never touch the committed
notebooks), with its own config, settings, workspace, runtime and kernel folders, so it does not
clash with the nbval run of the same notebooks. Chromium is Debian's (``/usr/bin/chromium``),
driven by Playwright through ``executable_path``; Playwright's own browser download is never used.
"""
from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
OUTPUT = Path(__file__).resolve().parent / "output"
CHROMIUM = os.environ.get("LANELIB_CHROMIUM", "/usr/bin/chromium")

# Nothing under output/ is a test (it may hold copies of notebooks while a run is in progress).
collect_ignore_glob = ["output/*"]

# Headless Chromium offline: no background requests, no QUIC, a fresh profile (the user-data-dir is
# given to launch_persistent_context). A dead proxy catches any request to a non-loopback host
# (Chromium never proxies loopback), and the resolver knows no other host either.
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--proxy-server=http://127.0.0.1:9",
    "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1, EXCLUDE localhost",
]

# JupyterLab settings for the test user: no news or update checks, every cell in the DOM (no
# virtual scrolling), no autosave churn. Written to a fresh JUPYTERLAB_SETTINGS_DIR.
LAB_SETTINGS = {
    "@jupyterlab/apputils-extension/notification.jupyterlab-settings": {
        "fetchNews": "false", "checkForUpdates": False},
    "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {"windowingMode": "none"},
    "@jupyterlab/docmanager-extension/plugin.jupyterlab-settings": {"autosave": False},
}


def _missing_reason() -> str | None:
    """Say what to install when Chromium or Playwright is missing, else None."""
    if not (os.path.isfile(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        return (f"{CHROMIUM} not found: install Debian's chromium (`apt-get install chromium`, "
                "as root; `make test` does it when run as root)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "Playwright not installed: `pip install playwright` (pinned in requirements.txt)"
    return None


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@dataclass
class Lab:
    """A running JupyterLab: where it listens, its token, and the folder it serves."""

    url: str
    token: str
    root: Path
    log: Path

    def api(self, method: str, path: str, timeout: float = 5.0):
        """Call the server's REST API; return the decoded JSON (or None for an empty body)."""
        req = urllib.request.Request(f"{self.url}{path}", method=method,
                                     headers={"Authorization": f"token {self.token}"})
        with urllib.request.urlopen(req, timeout=timeout) as resp:
            body = resp.read()
        return json.loads(body) if body else None

    def shutdown_kernels(self) -> None:
        """Shut down every kernel of this server (each notebook's test frees its CPU at the end)."""
        try:
            for kernel in self.api("GET", "/api/kernels"):
                self.api("DELETE", f"/api/kernels/{kernel['id']}", timeout=15)
        except (OSError, urllib.error.URLError):
            pass


def _mirror_repo(dest: Path) -> Path:
    """Make ``dest/<repo name>`` look like the repo: notebooks/ copied, everything else symlinked.

    Relative paths from a notebook (``../test_images``, ``../../shared/data``) resolve as in the
    repo, while whatever the notebook or JupyterLab writes lands in the copy. ``out/``, where
    the notebooks save (``out/tuned.json``, ``out/project_tuned.mp4``), is a fresh empty folder:
    a run never writes into the repo's ``out/``, nor races the nbval run writing there.
    """
    root = dest / REPO.name
    root.mkdir(parents=True)
    source = Path(os.environ.get("LANELIB_E2E_NOTEBOOKS", REPO / "notebooks"))
    shutil.copytree(source, root / "notebooks",
                    ignore=shutil.ignore_patterns(".ipynb_checkpoints", "__pycache__"))
    (root / "out").mkdir()
    for entry in REPO.iterdir():
        if entry.name not in {"notebooks", "out", ".git", ".venv"}:
            (root / entry.name).symlink_to(entry)
    for sibling in REPO.parent.iterdir():
        if sibling.name != REPO.name and not (dest / sibling.name).exists():
            (dest / sibling.name).symlink_to(sibling)
    return root


def _own_session_dies_with_parent() -> None:
    """In the server's child: a session (process group) of its own, and SIGTERM when pytest dies.

    Even a pytest killed with SIGKILL (a CI time-out) then takes the server, and so its kernels,
    with it; the normal end of the test goes through ``_stop``.
    """
    os.setsid()
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG (Linux)
    except (OSError, AttributeError):
        pass


def _pids_mentioning(marker: str) -> list[int]:
    """Pids of processes whose command line mentions ``marker`` (our unique temp folder)."""
    pids = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit() or int(proc.name) == os.getpid():
            continue
        try:
            if marker in (proc / "cmdline").read_bytes().decode(errors="replace"):
                pids.append(int(proc.name))
        except OSError:
            continue
    return pids


def _stop(proc: subprocess.Popen, marker: str) -> None:
    """Stop the server's process group, then any kernel it started in a session of its own."""
    for sig, wait_s in ((signal.SIGTERM, 10), (signal.SIGKILL, 5)):
        if proc.poll() is not None:
            break
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        try:
            proc.wait(timeout=wait_s)
        except subprocess.TimeoutExpired:
            pass
    # Kernels run in their own sessions; their command lines name our runtime folder.
    for sig in (signal.SIGTERM, signal.SIGKILL):
        pids = _pids_mentioning(marker)
        for pid in pids:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        if pids:
            time.sleep(1)


@pytest.fixture(scope="module")
def need_browser() -> str:
    """Path of Debian's chromium, or skip saying what to install."""
    reason = _missing_reason()
    if reason:
        pytest.skip(reason)
    return CHROMIUM


@pytest.fixture(scope="module")
def lab(need_browser, tmp_path_factory) -> Lab:
    """A JupyterLab server on a free loopback port with a random token, serving a notebooks copy."""
    base = tmp_path_factory.mktemp("lab")
    root = _mirror_repo(base / "work")
    home = base / "home"
    settings = home / "lab-settings"
    for name, value in LAB_SETTINGS.items():
        plugin, file = name.rsplit("/", 1)
        (settings / plugin).mkdir(parents=True, exist_ok=True)
        (settings / plugin / file).write_text(json.dumps(value))
    config = home / "config"
    config.mkdir(parents=True)
    # news_url must be None (no feed fetch), which only a config file can say.
    (config / "jupyter_lab_config.json").write_text(json.dumps({
        "LabApp": {"news_url": None, "extension_manager": "readonly",
                   "check_for_updates_class": "jupyterlab.NeverCheckForUpdate"}}))
    runtime = home / "runtime"
    env = dict(os.environ,
               JUPYTER_CONFIG_DIR=str(config), JUPYTER_DATA_DIR=str(home / "data"),
               JUPYTER_RUNTIME_DIR=str(runtime), JUPYTERLAB_SETTINGS_DIR=str(settings),
               JUPYTERLAB_WORKSPACES_DIR=str(home / "workspaces"), IPYTHONDIR=str(home / "ipython"),
               JUPYTER_PLATFORM_DIRS="1", PYTHONUNBUFFERED="1", MPLBACKEND="agg")
    port, token = _free_port(), secrets.token_hex(24)
    url = f"http://127.0.0.1:{port}"
    OUTPUT.mkdir(parents=True, exist_ok=True)
    log_path = OUTPUT / "jupyterlab.log"
    cmd = [sys.executable, "-m", "jupyterlab", "--no-browser", "--ServerApp.ip=127.0.0.1",
           f"--ServerApp.port={port}", "--ServerApp.port_retries=0",
           f"--IdentityProvider.token={token}", f"--ServerApp.root_dir={root}",
           "--ServerApp.open_browser=False", "--LabApp.expose_app_in_browser=True",
           "--ServerApp.allow_remote_access=False", "--ServerApp.terminals_enabled=False",
           "--ServerApp.allow_root=True"]
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, preexec_fn=_own_session_dies_with_parent)
    try:
        server = Lab(url=url, token=token, root=root, log=log_path)
        deadline = time.monotonic() + 60
        while True:
            if proc.poll() is not None:
                pytest.fail(f"JupyterLab exited with {proc.returncode}; see {log_path}")
            try:
                server.api("GET", "/api/status", timeout=2)
                break
            except (OSError, urllib.error.URLError):
                if time.monotonic() > deadline:
                    pytest.fail(f"JupyterLab did not answer on {url} within 60 s; see {log_path}")
                time.sleep(0.2)
        yield server
    finally:
        _stop(proc, str(runtime))
        shutil.rmtree(base, ignore_errors=True)


@pytest.fixture(scope="module")
def browser_context(need_browser, tmp_path_factory):
    """A headless Chromium context (fresh profile) that is closed at the end whatever happens."""
    from playwright.sync_api import sync_playwright

    profile = tmp_path_factory.mktemp("chromium-profile")
    with sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            str(profile), executable_path=need_browser, headless=True, args=CHROMIUM_ARGS,
            viewport={"width": 1440, "height": 900}, device_scale_factor=1,
            timeout=60_000)
        try:
            yield context
        finally:
            context.close()
