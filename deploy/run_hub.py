"""JupyterHub, with time for the formgrader service to start (``python deploy/run_hub.py -f ...``).

JupyterHub gives a managed service about ten seconds to answer, then exits (``app.py``,
``start_service``: ten one-second tries). The formgrader service is a whole JupyterLab with
nbgrader's extensions; on a loaded two-core machine it needs longer. This hub waits up to
:data:`SERVICE_START_TIMEOUT` seconds more for a managed service whose process is still running,
and gives up, as JupyterHub does, when the process has exited.

Ctrl-C stops it with one line, :data:`STOPPED`, and no traceback, whenever it comes: once the
hub runs, JupyterHub's own SIGINT handler stops the services, servers and proxy; before that
(while it waits for the formgrader service) JupyterHub has no handler yet, the interrupt would
end the process with a traceback and leave the proxy and the service running, so :func:`main`
runs JupyterHub's own cleanup itself.
"""

from __future__ import annotations

import signal
import subprocess
import sys

from jupyterhub.app import JupyterHub
from jupyterhub.objects import Server
from jupyterhub.utils import AnyTimeoutError

#: seconds a managed service may take to answer, after JupyterHub's own ten
SERVICE_START_TIMEOUT = 120


class CourseHub(JupyterHub):
    """JupyterHub that waits longer for a slow managed service."""

    async def start_service(self, service_name, service, ssl_context=None):
        if await super().start_service(service_name, service, ssl_context):
            return True
        if not (service.managed and service.url) or await service.spawner.poll() is not None:
            return False
        self.log.info("Still waiting for service %s (up to %d s)", service_name,
                      SERVICE_START_TIMEOUT)
        try:
            await Server.from_orm(service.orm.server).wait_up(
                http=True, timeout=SERVICE_START_TIMEOUT, ssl_context=ssl_context)
        except AnyTimeoutError:
            return False
        self.log.info("Service %s is up", service_name)
        return True


#: The last line of a hub stopped by Ctrl-C (or SIGTERM).
STOPPED = "hub: stopped; `make hub` starts it again (users, course, submissions and marks stay)"


def main(argv: list[str] | None = None) -> int:
    """Run the hub until it is stopped; end with :data:`STOPPED`, never a traceback."""
    try:
        CourseHub.launch_instance(argv)
    except KeyboardInterrupt:
        _clean_up_after_interrupt(CourseHub.instance())
    _wait_for_the_proxy(CourseHub.instance())
    # a deliberate stop is a normal end: exit status 0, so `make hub` adds no "Error" line
    print(STOPPED, file=sys.stderr, flush=True)
    return 0


def _clean_up_after_interrupt(hub: CourseHub) -> None:
    """Stop what a hub interrupted while starting had started (proxy, services, servers)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C would leave half of it
    try:
        # JupyterHub's cleanup, in a fresh event loop: the interrupted one is unclean
        hub.atexit()
    except Exception as exc:  # noqa: BLE001 - say what failed in a line, then the stop line
        print(f"hub: cleaning up after Ctrl-C failed ({type(exc).__name__}: {exc}); the proxy "
              "may still run (its pid is in the hub's proxy.pid)", file=sys.stderr, flush=True)


def _wait_for_the_proxy(hub: CourseHub, timeout: float = 10) -> None:
    """JupyterHub terminates its proxy without waiting for it: wait (bounded), so the proxy's
    last words come before :data:`STOPPED` and nothing of the hub outlives it."""
    process = getattr(getattr(hub, "proxy", None), "proxy_process", None)
    if process is not None:
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            pass


if __name__ == "__main__":
    sys.exit(main())
