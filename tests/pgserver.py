"""A throw-away PostgreSQL server on loopback for the tests and the load benchmark.

``PostgresServer.start()`` runs Debian's ``initdb`` and ``pg_ctl`` on a fresh data
directory, in memory where there is room (as the ``postgres`` user when we are root, since
the server refuses to run as root), listening on 127.0.0.1 and a free port with ``trust``
authentication, and without fsync (a test cluster has nothing to keep).
``GYROLAB_TEST_POSTGRES_URL`` points the tests at an existing server instead; its user must
be allowed to create databases.
"""

from __future__ import annotations

import glob
import os
import shutil
import socket
import subprocess
import tempfile
import time
from pathlib import Path

from sqlalchemy.engine import make_url

ADMIN_URL_ENV = "GYROLAB_TEST_POSTGRES_URL"
USER = "gyrolab"


class PostgresUnavailable(RuntimeError):
    """No PostgreSQL binaries (or no way to run them) on this machine."""


def find_bindir() -> Path | None:
    """The directory holding initdb/pg_ctl: on PATH, or Debian's /usr/lib/postgresql/N/bin."""
    on_path = shutil.which("initdb")
    if on_path:
        return Path(on_path).resolve().parent
    candidates = sorted(
        glob.glob("/usr/lib/postgresql/*/bin/initdb"),
        key=lambda path: int(Path(path).parts[-3]) if Path(path).parts[-3].isdigit() else 0,
    )
    return Path(candidates[-1]).parent if candidates else None


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


MEMORY_DIR = Path("/dev/shm")
MEMORY_NEEDED = 2 * 1024**3  # the cluster with its WAL, with room to spare


def _scratch_dir(durable: bool) -> str | None:
    """Where a cluster lives: in memory (``/dev/shm``, where it has room) unless it must be
    durable (benchmarks).  Every test creates a database from the template and drops it,
    ≈ 1,000 files each time: ≈ 100 ms on this machine's disk, ≈ 9 ms in memory."""
    if durable or not MEMORY_DIR.is_dir() or not os.access(MEMORY_DIR, os.W_OK | os.X_OK):
        return None
    room = os.statvfs(MEMORY_DIR)
    return str(MEMORY_DIR) if room.f_bavail * room.f_frsize >= MEMORY_NEEDED else None


class PostgresServer:
    """One PostgreSQL cluster in a temporary directory; ``url(db)`` gives SQLAlchemy URLs."""

    def __init__(self, admin_url: str | None = None) -> None:
        self.admin_url = admin_url
        self.root: Path | None = None
        self.port = 0
        self._bindir: Path | None = None

    # -- lifecycle -------------------------------------------------------------------------
    def start(self, *, durable: bool = False) -> PostgresServer:
        """Start the cluster; ``durable`` keeps fsync on (benchmarks), tests turn it off."""
        if self.admin_url:
            return self
        bindir = find_bindir()
        if bindir is None:
            raise PostgresUnavailable("PostgreSQL is not installed (Debian package: postgresql)")
        self._bindir = bindir
        self.root = Path(tempfile.mkdtemp(prefix="gyrolab-pg-", dir=_scratch_dir(durable)))
        self.root.chmod(0o755)
        data = self.root / "data"
        data.mkdir()
        if os.geteuid() == 0:
            if shutil.which("runuser") is None:
                raise PostgresUnavailable("running as root without runuser(1)")
            try:
                shutil.chown(self.root, user="postgres")
                shutil.chown(data, user="postgres")
            except LookupError as error:
                raise PostgresUnavailable("running as root and no 'postgres' user") from error
        self._run(
            "initdb",
            "-D",
            str(data),
            "-U",
            USER,
            "--auth=trust",
            "--encoding=UTF8",
            "--locale=C.UTF-8",
            "--no-sync",
        )
        # a port found free can be taken by another test worker before this cluster binds
        # it: the cluster is then started again on another port, up to three times
        for attempt in range(3):
            self.port = _free_port()
            try:
                self._pg_ctl_start(data, durable)
                break
            except PostgresUnavailable:
                log = (self.root / "server.log").read_text(errors="replace")
                if attempt == 2 or "already in use" not in log:
                    raise
        self.admin_url = f"postgresql+psycopg://{USER}@127.0.0.1:{self.port}/postgres"
        return self

    def _pg_ctl_start(self, data: Path, durable: bool) -> None:
        options = (
            f"-c listen_addresses=127.0.0.1 -p {self.port} -c unix_socket_directories={self.root}"
            " -c max_connections=300 -c shared_buffers=128MB"
        )
        if not durable:
            options += " -c fsync=off -c synchronous_commit=off -c full_page_writes=off"
        assert self.root is not None
        self._run(
            "pg_ctl",
            "-D",
            str(data),
            "-l",
            str(self.root / "server.log"),
            "-o",
            options,
            "-w",
            "-t",
            "60",
            "start",
        )

    def stop(self) -> None:
        if self.root is None:
            return
        try:
            self._run("pg_ctl", "-D", str(self.root / "data"), "-m", "immediate", "-w", "stop")
        finally:
            shutil.rmtree(self.root, ignore_errors=True)
            self.root = None

    def _run(self, program: str, *args: str) -> None:
        assert self._bindir is not None
        command = [str(self._bindir / program), *args]
        if os.geteuid() == 0:
            command = ["runuser", "-u", "postgres", "--", *command]
        result = subprocess.run(command, capture_output=True, text=True, cwd="/")
        if result.returncode != 0:
            raise PostgresUnavailable(f"{program} failed: {result.stderr.strip()[-2000:]}")

    # -- databases -------------------------------------------------------------------------
    def url(self, database: str) -> str:
        assert self.admin_url, "start() first"
        return make_url(self.admin_url).set(database=database).render_as_string(hide_password=False)

    def execute(self, *statements: str) -> None:
        """Run statements on the maintenance database outside a transaction."""
        import psycopg

        url = make_url(self.admin_url)
        with psycopg.connect(
            host=url.host,
            port=url.port,
            user=url.username,
            password=url.password,
            dbname=url.database or "postgres",
            autocommit=True,
        ) as connection:
            for statement in statements:
                connection.execute(statement)

    def create_database(self, name: str, template: str | None = None) -> str:
        # FILE_COPY: a small database is copied faster than through the WAL (PostgreSQL 15+'s
        # default); tests create one per test.
        suffix = f' TEMPLATE "{template}" STRATEGY FILE_COPY' if template else ""
        self.execute(
            f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)', f'CREATE DATABASE "{name}"{suffix}'
        )
        return self.url(name)

    def drop_database(self, name: str) -> None:
        self.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')

    def wait_ready(self, timeout: float = 30) -> None:
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.execute("SELECT 1")
                return
            except Exception:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
