"""nbgrader's filesystem exchange, with each submission readable by its author and the graders only.

nbgrader's own ``ExchangeSubmit`` leaves every submission world-readable (files 0644, folder
0777, in ``<exchange>/<course>/inbound/``; nbgrader issues #978 and #1225). The inbound folder
cannot be listed by students (nbgrader makes it 2733), so a classmate needs the folder's name,
``<student>+<assignment>+<timestamp>+<random>``, but the name is all that protects the work.

This class keeps nbgrader's submit and takes the "other" bits away: files 0640 and folders 0750
(the submission's own folder 0770, so the graders can tidy up the inbound). The group of a
submission is the inbound folder's group, inherited through its setgid bit: the deployment
(``deploy/hub.py``) gives the inbound to the graders' group, which no student is in. Installed
in the students' environment by ``deploy/hub.py`` and switched on in their
``nbgrader_config.py`` with ``c.ExchangeFactory.submit = "private_exchange.PrivateExchangeSubmit"``.
"""

from __future__ import annotations

import os

from nbgrader.exchange.default.submit import ExchangeSubmit

#: permission bits a submission never gets: nothing for "other"
OTHERS = 0o007
#: the submission's own folder: its author and the graders' group may read, write and enter it
SUBMISSION_DIR_MODE = 0o770


class PrivateExchangeSubmit(ExchangeSubmit):
    """``nbgrader submit`` whose submission no other student can read, even knowing its name."""

    def set_perms(self, dest, fileperms, dirperms):
        """nbgrader's modes without the bits for others (files 0640, folders 0750)."""
        super().set_perms(dest, fileperms & ~OTHERS, dirperms & ~OTHERS)

    def copy_files(self):
        """Submit as nbgrader does, then close the folder nbgrader leaves at 0777."""
        super().copy_files()
        os.chmod(os.path.join(self.inbound_path, self.assignment_filename), SUBMISSION_DIR_MODE)
