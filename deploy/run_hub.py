"""JupyterHub, with time for the formgrader service to start (``python deploy/run_hub.py -f ...``).

JupyterHub gives a managed service about ten seconds to answer, then exits (``app.py``,
``start_service``: ten one-second tries). The formgrader service is a whole JupyterLab with
nbgrader's extensions; on a loaded two-core machine it needs longer. This hub waits up to
:data:`SERVICE_START_TIMEOUT` seconds more for a managed service whose process is still running,
and gives up, as JupyterHub does, when the process has exited.
"""

from __future__ import annotations

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


if __name__ == "__main__":
    CourseHub.launch_instance()
