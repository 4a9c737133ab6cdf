"""The gradebook's database URL, checked before any grading starts.

nbgrader opens its gradebook through SQLAlchemy, which picks a database driver from the URL.
A plain ``postgresql://`` means SQLAlchemy's default driver (psycopg2 up to SQLAlchemy 2.0,
psycopg 3 from 2.1); the course installs psycopg 3 (the ``postgres`` extra), so
:func:`resolve_db_url` names it (``postgresql+psycopg://``) whenever it is installed. A URL
whose driver cannot be imported raises :class:`MissingDriver` naming the package to install,
so ``grade --db-url`` stops with an error at once instead of grading for an hour and then
leaving the gradebook untouched.
"""

from __future__ import annotations

import importlib.util

#: What to install for a driver SQLAlchemy could not import (its module name -> the advice).
INSTALL_ADVICE = {
    "psycopg": "pip install 'psycopg[binary]' (the course's `postgres` extra: "
               "pip install '4f9-course[postgres]')",
    "psycopg2": "pip install psycopg2-binary, or use postgresql+psycopg://... with the course's "
                "`postgres` extra",
}


class MissingDriver(RuntimeError):
    """The database driver a gradebook URL needs is not installed (the message names it)."""


def _importable(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


def resolve_db_url(db_url: str) -> str:
    """``db_url`` with the driver this installation has, after checking the driver imports.

    Parameters
    ----------
    db_url : str
        An SQLAlchemy URL such as ``sqlite:///course/gradebook.db`` or
        ``postgresql://grader@db.example/gradebook``.

    Returns
    -------
    str
        The same URL, with ``postgresql://`` made ``postgresql+psycopg://`` when psycopg 3 is
        installed; any other URL unchanged.

    Raises
    ------
    ValueError
        When ``db_url`` is not a database URL SQLAlchemy knows.
    MissingDriver
        When the URL's driver is not installed (the message says what to install).
    """
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import ArgumentError, NoSuchModuleError

    if type(db_url) is not str or not db_url.strip():
        raise ValueError(f"db_url must be a database URL, got {db_url!r}")
    try:
        url = make_url(db_url)
        if url.drivername == "postgresql" and _importable("psycopg"):
            url = url.set(drivername="postgresql+psycopg")
        dialect = url.get_dialect()
    except (ArgumentError, NoSuchModuleError) as exc:
        raise ValueError(f"db_url {db_url!r} is not a database URL SQLAlchemy knows "
                         f"({exc})") from None
    try:
        dialect.import_dbapi()
    except ImportError as exc:
        module = (exc.name or "").split(".")[0] or url.get_driver_name()
        advice = INSTALL_ADVICE.get(module, f"install the Python module {module!r}")
        raise MissingDriver(f"the gradebook URL needs the database driver {module!r} "
                            f"({url.drivername}), which is not installed: {advice}") from None
    if url.drivername == db_url.split(":", 1)[0]:
        return db_url
    return url.render_as_string(hide_password=False)
