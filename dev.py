#!/usr/bin/env python3
"""GyroLab's two commands, usable on a fresh machine with nothing but Python 3.11+.

    python3 dev.py run    create .venv, install, migrate, add demo data, serve on 127.0.0.1:8000
    python3 dev.py test   the same set-up plus test extras, Debian's Chromium (and in CI,
                          PostgreSQL), then ruff (lint and format check), the layers
                          contract (import-linter) and every test on SQLite and
                          PostgreSQL, in parallel
    python3 dev.py quick  the quick loop: tests without browser, server, PDF or Monte Carlo,
                          on SQLite only (under a minute)

Extra arguments after ``run`` go to ``gyrolab serve`` (e.g. ``--port 8080 --no-demo``);
after ``test`` they go to pytest (e.g. ``-k auth``).  Uses only the standard library.
"""

from __future__ import annotations

import glob
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / "bin"
CHROMIUM = Path("/usr/bin/chromium")


def say(message: str) -> None:
    print(f"[gyrolab] {message}", flush=True)


def run(cmd: list[str], **kwargs) -> None:
    subprocess.run(cmd, check=True, **kwargs)


def apt_install(*packages: str) -> bool:
    """Install Debian packages when we are root (or have sudo) and apt-get exists."""
    apt = shutil.which("apt-get")
    if apt is None:
        return False
    prefix: list[str] = []
    if os.geteuid() != 0:
        sudo = shutil.which("sudo")
        if sudo is None:
            return False
        prefix = [sudo, "-n"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    say(f"installing Debian package(s): {' '.join(packages)}")
    try:
        run([*prefix, apt, "-qq", "update"], env=env)
        run([*prefix, apt, "install", "-y", "-qq", *packages], env=env)
    except subprocess.CalledProcessError:
        return False
    return True


def ensure_venv() -> None:
    if (BIN / "python").exists():
        return
    say("creating virtual environment .venv")
    try:
        run([sys.executable, "-m", "venv", str(VENV)])
    except subprocess.CalledProcessError:
        # Debian ships venv/ensurepip separately.
        shutil.rmtree(VENV, ignore_errors=True)
        version = f"{sys.version_info.major}.{sys.version_info.minor}"
        if not apt_install(f"python{version}-venv"):
            sys.exit("python3 -m venv failed; install python3-venv and try again")
        run([sys.executable, "-m", "venv", str(VENV)])


def ensure_installed(extras: str) -> None:
    """pip install the project (editable) with pinned versions, skipped when unchanged."""
    stamp = VENV / f".installed-{extras or 'base'}"
    digest = hashlib.sha256()
    for name in ("pyproject.toml", "constraints.txt"):
        digest.update((ROOT / name).read_bytes())
    if stamp.exists() and stamp.read_text() == digest.hexdigest():
        return
    target = f".[{extras}]" if extras else "."
    say(f"installing gyrolab{target[1:]} into .venv (versions pinned by constraints.txt)")
    pip = [str(BIN / "python"), "-m", "pip", "install", "--disable-pip-version-check", "-q"]
    run([*pip, "-c", "constraints.txt", "-e", target], cwd=ROOT)
    stamp.write_text(digest.hexdigest())


REPORT_PACKAGES = ("libpango-1.0-0", "libpangoft2-1.0-0", "libharfbuzz-subset0", "fonts-wqy-zenhei")


def chinese_font_installed() -> bool:
    fc_list = shutil.which("fc-list")
    if fc_list is None:
        return False
    found = subprocess.run([fc_list, ":lang=zh", "family"], capture_output=True, text=True)
    return bool(found.stdout.strip())


def ensure_report_libraries() -> None:
    """WeasyPrint (the PDF lab reports) needs Debian's Pango, and Chinese reports a CJK font."""
    import ctypes.util

    have_pango = all(ctypes.util.find_library(name) for name in ("pango-1.0", "pangoft2-1.0"))
    if have_pango and chinese_font_installed():
        return
    if not apt_install(*REPORT_PACKAGES):
        say("could not install Pango and a CJK font: PDF lab reports will not work")


def postgres_installed() -> bool:
    return bool(shutil.which("initdb") or glob.glob("/usr/lib/postgresql/*/bin/initdb"))


def ensure_test_programs() -> None:
    """Debian's Chromium (browser tests) always; PostgreSQL in CI, where its tests must run.
    The tests start their own PostgreSQL server on loopback (tests/pgserver.py)."""
    in_ci = os.environ.get("CI", "").lower() == "true"
    wanted = [] if CHROMIUM.exists() else ["chromium", "fonts-wqy-zenhei"]
    if in_ci and not postgres_installed():
        wanted.append("postgresql")
    if wanted and not apt_install(*wanted):
        say(f"could not install {' '.join(wanted)}: the tests that need them will skip")
    if not in_ci and not postgres_installed():
        say("PostgreSQL is not installed: its tests will skip (CI installs it)")


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in {"run", "test", "quick"}:
        print(__doc__)
        return 2
    command, rest = argv[0], argv[1:]
    os.chdir(ROOT)
    ensure_venv()
    ensure_report_libraries()
    if command == "run":
        ensure_installed("")
        return subprocess.call([str(BIN / "gyrolab"), "serve", *rest])
    ensure_installed("test")
    pytest = [str(BIN / "python"), "-m", "pytest", "--dist", "worksteal"]
    # bytecode written even where the shell asks not to (PYTHONDONTWRITEBYTECODE): else each
    # server and CLI run the tests start compiles the app again (0.2 s of CPU each) and each
    # test worker rewrites every test module's assertions (3 s)
    env = {name: value for name, value in os.environ.items() if name != "PYTHONDONTWRITEBYTECODE"}
    if command == "quick":  # CPU-bound: one worker per core (2 cores: 56 s; 3 workers: 60 s)
        quick = ["-n", "auto", "-m", "not e2e and not slow", "--backends", "sqlite"]
        return subprocess.call([*pytest, *quick, *rest], env=env)
    # one worker more than cores: a browser test's worker waits on Chromium and the server
    # (2 cores: the suite 295 s with 2 workers, 266 s with 3)
    pytest += ["-n", str((os.cpu_count() or 1) + 1), "--durations=15"]
    ensure_test_programs()
    for check in (["ruff", "check", "."], ["ruff", "format", "--check", "."], ["lint-imports"]):
        say(" ".join(check))
        if subprocess.call([str(BIN / check[0]), *check[1:]]) != 0:
            return 1
    return subprocess.call([*pytest, *rest], env=env)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
