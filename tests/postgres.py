"""A throw-away PostgreSQL server for the tests (Debian's ``postgresql`` binaries).

:func:`start_server` runs ``initdb`` in a fresh temporary folder, then ``pg_ctl start`` on a
free port of 127.0.0.1 with its unix socket in that folder; :meth:`PostgresServer.stop` stops
it and removes the folder. As root both run as the system user ``postgres`` (``initdb``
refuses root; Debian's package creates that user, and :func:`_server_user` creates it when it
is missing). ``tests/conftest.py`` exposes it as the session fixture ``postgres_url``; tests
that need an empty gradebook call :func:`fresh_database`.

    server = start_server()
    url = fresh_database(server.url(), "gradebook_a")   # postgresql+psycopg://...
    ...
    server.halt(); server.resume()                      # a crash and a restart, data kept
    server.stop()
"""

from __future__ import annotations

import glob
import os
import pwd
import re
import shutil
import socket
import subprocess
import tempfile
from pathlib import Path

SUPERUSER = "postgres"
#: Server settings for a disposable test database: durability off, loopback only.
SETTINGS = ("-c listen_addresses=127.0.0.1 -c fsync=off -c synchronous_commit=off "
            "-c full_page_writes=off -c max_connections=50")
INSTALL_HINT = "make postgres-deps installs Debian's postgresql as root"


class PostgresUnavailable(RuntimeError):
    """No PostgreSQL server binaries here (the message says how to install them)."""


def find_bindir() -> Path | None:
    """The newest ``/usr/lib/postgresql/<version>/bin`` holding ``initdb`` and ``pg_ctl``."""
    found = [Path(p).parent for p in glob.glob("/usr/lib/postgresql/*/bin/initdb")
             if os.access(Path(p).parent / "pg_ctl", os.X_OK)]
    return max(found, key=lambda p: int(re.sub(r"\D", "", p.parent.name) or 0), default=None)


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _server_user() -> str | None:
    """The account the server runs as: ``postgres`` as root (created if missing), else None
    (this process's own user)."""
    if os.geteuid() != 0:
        return None
    try:
        pwd.getpwnam(SUPERUSER)
    except KeyError:
        subprocess.run(["useradd", "--system", "--no-create-home", "--shell",
                        "/usr/sbin/nologin", SUPERUSER], check=True, capture_output=True)
    return SUPERUSER


class PostgresServer:
    """A running throw-away server (see the module docstring)."""

    def __init__(self, bindir: Path, base: Path, port: int, user: str | None):
        self.bindir, self.base, self.port, self.user = bindir, base, port, user
        self.data = base / "data"

    def _run(self, tool: str, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
        argv = [str(self.bindir / tool), *args]
        if self.user is not None:
            argv = ["runuser", "-u", self.user, "--", *argv]
        return subprocess.run(argv, capture_output=True, text=True, timeout=timeout,
                              cwd=self.base)

    def start(self) -> None:
        done = self._run("initdb", "-D", str(self.data), "-A", "trust", "-U", SUPERUSER,
                         "-E", "UTF8", "--locale=C", "--no-sync")
        if done.returncode != 0:
            raise RuntimeError(f"initdb failed: {done.stderr[-2000:]}")
        done = self._run("pg_ctl", "-D", str(self.data), "-l", str(self.base / "server.log"),
                         "-w", "-t", "60", "-o", f"-p {self.port} -k {self.base} {SETTINGS}",
                         "start")
        if done.returncode != 0:
            log = (self.base / "server.log").read_text(errors="replace")[-2000:] \
                if (self.base / "server.log").exists() else ""
            raise RuntimeError(f"pg_ctl start failed: {done.stderr[-1000:]}\n{log}")

    def url(self, database: str = "postgres") -> str:
        """An SQLAlchemy URL of ``database`` on this server (psycopg 3, as the superuser)."""
        return f"postgresql+psycopg://{SUPERUSER}@127.0.0.1:{self.port}/{database}"

    def halt(self) -> None:
        """Stop the server at once (as a crash would: ``-m immediate``), keeping its data for
        :meth:`resume`."""
        done = self._run("pg_ctl", "-D", str(self.data), "-m", "immediate", "-w", "stop",
                         timeout=60)
        if done.returncode != 0:
            raise RuntimeError(f"pg_ctl stop failed: {done.stderr[-1000:]}")

    def resume(self) -> None:
        """Start a server :meth:`halt` stopped, on the same port and data."""
        done = self._run("pg_ctl", "-D", str(self.data), "-l", str(self.base / "server.log"),
                         "-w", "-t", "60", "-o", f"-p {self.port} -k {self.base} {SETTINGS}",
                         "start")
        if done.returncode != 0:
            raise RuntimeError(f"pg_ctl start failed: {done.stderr[-1000:]}")

    def stop(self) -> None:
        """Stop the server at once and remove its folder."""
        try:
            if self.data.exists():
                self._run("pg_ctl", "-D", str(self.data), "-m", "immediate", "-w", "stop",
                          timeout=60)
        finally:
            shutil.rmtree(self.base, ignore_errors=True)


def start_server() -> PostgresServer:
    """Start a server (:class:`PostgresUnavailable` when the binaries are not installed)."""
    bindir = find_bindir()
    if bindir is None:
        raise PostgresUnavailable(f"no PostgreSQL server binaries in /usr/lib/postgresql "
                                  f"({INSTALL_HINT})")
    user = _server_user()
    base = Path(tempfile.mkdtemp(prefix="autograder-postgres-"))
    if user is not None:
        record = pwd.getpwnam(user)
        os.chown(base, record.pw_uid, record.pw_gid)
    server = PostgresServer(bindir, base, _free_port(), user)
    try:
        server.start()
    except BaseException:
        server.stop()
        raise
    return server


def fresh_database(server_url: str, name: str) -> str:
    """Create the empty database ``name`` on the server of ``server_url`` (dropping any older
    one of that name); its SQLAlchemy URL."""
    import psycopg

    if not re.fullmatch(r"[a-z_][a-z0-9_]{0,62}", name):
        raise ValueError(f"name must be a lower-case SQL identifier, got {name!r}")
    plain = server_url.replace("postgresql+psycopg://", "postgresql://", 1)
    with psycopg.connect(plain, autocommit=True) as con:
        con.execute(f"DROP DATABASE IF EXISTS {name} WITH (FORCE)")
        con.execute(f"CREATE DATABASE {name}")
    return server_url.rsplit("/", 1)[0] + "/" + name
