"""How each payload of this folder becomes a submission, and what grade it must get.

``expected.csv`` is the table: one row per attacking student, with the notebook and graded name
attacked (blank: the first source notebook and its target, :func:`gradingtools.target_of`),
the payload, and the expected status and points of that name's test cell. A payload file's
prefix says how it is applied to the model answers: ``wrap_`` (the body of a wrapper around the
model answer, ``_model``), ``append_`` (appended to the name's solution cell) or ``replace_``
(the name's whole solution cell); ``edit:`` names a change to the notebook's structure (an
:data:`EDITS` function), ``layout:`` a folder built by the test's fixture. In a template,
``$name`` is the graded name and ``$path``, ``$module``, ``$function`` are the attacked
reference's file, module (renamed) and function.

``points``: ``full`` or ``0``. An attack whose wrapper lets the honest model raise on bad input
before it returns its junk passes exactly the cases where a ``ValueError`` is the right answer
(:func:`raising_fraction`), and those count only once an ordinary case passes: 0. ``others``:
``full`` (every
other cell full marks), ``full-except-callers`` (the cells whose model answer calls the
attacked name are not pinned) or ``same`` (every graded and manual cell 0 with the status: a
notebook that cannot be graded).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from string import Template

from gradingtools import (append_cell, cases_of, cell_index, expect_all, expect_full_marks,
                          model_version, release_version, target_of)

from autograder.exercises import REGISTRY

HERE = Path(__file__).parent


def payload(filename: str, **subs) -> str:
    """The text of payload ``filename``, its ``$`` placeholders filled from ``subs``."""
    text = (HERE / filename).read_text(encoding="utf-8")
    return Template(text).substitute(**subs) if subs else text


@dataclass
class Attack:
    """One row of ``expected.csv``."""

    student: str
    notebook: str        #: the source notebook attacked ("" = the first one)
    name: str            #: the graded name attacked ("" = the notebook's target)
    payload: str
    status: str          #: the status of the name's test cell
    points: str          #: "full" or "0"
    others: str          #: "full", "full-except-callers" or "same"

    def name_in(self, src) -> str:
        return self.name or target_of(src)

    def build(self, src) -> dict | None:
        """The submitted notebook (None for a ``layout:`` built by the fixture)."""
        name = self.name_in(src)
        if self.payload.startswith("layout:"):
            return None
        if self.payload.startswith("edit:"):
            return EDITS[self.payload[len("edit:"):]](src)
        nb = model_version(src)
        if self.payload.startswith("wrap_"):
            body = payload(self.payload)
            append_cell(nb, name, f"_model = {name}\ndef {name}(*args, **kwargs):\n"
                        + "".join("    " + ln + "\n" for ln in body.strip("\n").splitlines()))
        elif self.payload.startswith("append_"):
            append_cell(nb, name, payload(self.payload, **_reference_subs(name)))
        elif self.payload.startswith("replace_"):
            nb["cells"][cell_index(nb, name)]["source"] = payload(self.payload).lstrip("\n")
        else:
            raise ValueError(f"{self.student}: unknown payload {self.payload!r}")
        return nb

    def expected(self, src) -> dict[str, tuple]:
        """``{grade_id: (score, status)}`` of every pinned cell."""
        name = self.name_in(src)
        if self.others == "same":
            return expect_all(src, self.status)
        exp = expect_full_marks(src)
        if self.others == "full-except-callers":
            for caller in _callers(src, name):
                exp.pop(f"test_{caller}", None)
        if self.points == "full":
            return exp
        if self.points != "0":
            raise ValueError(f"{self.student}: points must be 'full' or '0', got {self.points!r}")
        exp[f"test_{name}"] = (0.0, self.status)
        return exp


def read_table() -> dict[str, Attack]:
    with open(HERE / "expected.csv", newline="", encoding="utf-8") as f:
        return {row["student"]: Attack(**row) for row in csv.DictReader(f)}


def _reference_subs(name: str) -> dict:
    ref = REGISTRY[name].reference
    return {"name": name, "path": repr(str(Path(ref.__code__.co_filename).resolve())),
            "module": repr(ref.__module__ + "_stolen"), "function": repr(ref.__name__)}


def raising_fraction(student: str, name: str, nb: dict) -> tuple[int, int]:
    """(cases where a ValueError is the right answer, all cases) for ``student``'s ``nb``."""
    cases = cases_of(student, name, nb)
    return sum(c.raises is not None and issubclass(ValueError, c.raises) for c in cases), len(cases)


def _callers(src, name: str) -> set[str]:
    """Graded names whose model solution mentions ``name`` (their score may depend on it)."""
    model = model_version(src)
    texts = {c["metadata"].get("nbgrader", {}).get("grade_id"): c["source"]
             for c in model["cells"] if c["metadata"].get("nbgrader", {}).get("solution")}
    return {g for g, t in texts.items() if g != name and re.search(rf"\b{re.escape(name)}\b", t)}


def cell_of(nb: dict, name: str) -> str:
    source = nb["cells"][cell_index(nb, name)]["source"]
    return source if isinstance(source, str) else "".join(source)


# --------------------------------------------------------------------------------------------
# changes to a notebook's structure (edit:...)


def _untagged_override(src):
    """The graded name redefined in an untagged later cell through ``globals()``/``exec``."""
    name = target_of(src)
    nb = model_version(src)
    i = cell_index(nb, name)
    nb["cells"].insert(i + 1, {
        "cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
        "source": f"globals()[{name!r}] = lambda *a, **k: 'cheat'\n"
                  f"exec('def {name}(*a, **k):\\n    return \"cheat\"')\n"})
    return nb


def _exec_only(src):
    """The solution cell gone; the name defined only through ``exec`` in a plain cell."""
    name = target_of(src)
    nb = model_version(src)
    i = cell_index(nb, name)
    body = cell_of(nb, name)
    nb["cells"][i] = {"cell_type": "code", "execution_count": None, "metadata": {},
                      "outputs": [], "source": f"exec({body!r})\n"}
    return nb


def _zero_width(src):
    """Zero-width characters in the grade_ids, and a forged test cell worth 100 points."""
    name = target_of(src)
    nb = model_version(src)
    nb["cells"][cell_index(nb, name)]["metadata"]["nbgrader"]["grade_id"] = name + "\u200b"
    t = cell_index(nb, f"test_{name}")
    nb["cells"][t]["metadata"]["nbgrader"]["grade_id"] = f"test_{name}\u200b"
    nb["cells"][t]["metadata"]["nbgrader"]["points"] = 100
    nb["cells"][t]["source"] = "assert True\n"
    return nb


def _source_numbers(src):
    """A solution cell whose source is a list of numbers."""
    nb = model_version(src)
    nb["cells"][cell_index(nb, target_of(src))]["source"] = [1, 2, 3]
    return nb


def _cells_dict(src):
    """``cells`` that is not a list."""
    nb = model_version(src)
    nb["cells"] = {str(k): c for k, c in enumerate(nb["cells"])}
    return nb


def _big_metadata(src):
    """8 MB of notebook metadata."""
    nb = model_version(src)
    nb["metadata"]["junk"] = ["x" * 1000] * 8000
    return nb


def _sum_of_ones(terms: int) -> str:
    return "_x = " + "+".join(["1"] * terms) + "\n"


def _deep_plain(src):
    """The target's nbgrader metadata gone (so planning reads every plain cell) and plain cells
    too deeply nested for Python's parser (one beyond the size cap, one under it)."""
    name = target_of(src)
    nb = model_version(src)
    nb["cells"][cell_index(nb, name)]["metadata"].pop("nbgrader")
    for terms in (100_000, 30_000):
        nb["cells"].append({"cell_type": "code", "execution_count": None, "metadata": {},
                            "outputs": [], "source": _sum_of_ones(terms)})
    return nb


def _in_target(extra_of: Callable) -> Callable:
    def build(src):
        nb = model_version(src)
        append_cell(nb, target_of(src), extra_of(target_of(src)))
        return nb
    return build


def _dup_arg(src):
    """A graded function that does not compile (a duplicate argument)."""
    nb = model_version(src)
    name = target_of(src)
    nb["cells"][cell_index(nb, name)]["source"] = f"def {name}(a, a):\n    return 0\n"
    return nb


def _big_notebook(src):
    """2.5 MB of ``a=1`` lines in the graded cell (the parser takes ~600 B a byte)."""
    nb = model_version(src)
    append_cell(nb, target_of(src), "a=1\n" * 625_000)
    return nb


def _surrogates(src):
    """Lone surrogates early in a cell and after its 20,000th character."""
    nb = model_version(src)
    append_cell(nb, target_of(src), "# \udcff\n#" + "x" * 20_001 + " \udcff\n")
    if src.manual:
        gid = src.manual[0][0]
        nb["cells"][cell_index(nb, gid)]["source"] += "\n\udcff"
    return nb


def _quote_flood(src):
    """25,000 ``"`` in every solution cell, its output and every written answer (each escaped
    to six characters); on the notebook with the most cells: 2.5 MB unless cut."""
    nb = model_version(src)
    for name, _, _ in src.graded:                # first, so that the cut keeps only quotes
        cell = nb["cells"][cell_index(nb, name)]
        cell["source"] = ("# " + '"' * 25_000 + "\n" + cell["source"]
                          + "\nprint('\"' * 25_000)\n")
    for gid, _ in src.manual:
        nb["cells"][cell_index(nb, gid)]["source"] = '"' * 25_000
    return nb


EDITS: dict[str, Callable] = {
    "untagged_override": _untagged_override,
    "exec_only": _exec_only,
    "zero_width": _zero_width,
    "source_numbers": _source_numbers,
    "cells_dict": _cells_dict,
    "big_metadata": _big_metadata,
    "deep_plain": _deep_plain,
    "deep_graded": _in_target(lambda n: _sum_of_ones(30_000)),
    "deep_digest": _in_target(lambda n: _sum_of_ones(2_000)),
    "dup_arg": _dup_arg,
    "big_cell": _in_target(lambda n: "a=1\n" * 50_000),
    "big_notebook": _big_notebook,
    "surrogates": _surrogates,
    "quote_flood": _quote_flood,
}


# --------------------------------------------------------------------------------------------
# the notebooks of the other fixtures


def blank_attacker(src, targets: dict[str, list[str]]) -> dict:
    """The release notebook with the raw-memory attack (``raw_memory.txt``: a raw write, then
    every read, listing and write of ``targets``) at the top of its first function's cell (the
    stub below it stays: the attacker answers nothing)."""
    nb = release_version(src)
    first = next(c for c in nb["cells"] if c["cell_type"] == "code"
                 and c["metadata"].get("nbgrader", {}).get("solution") and "def " in c["source"])
    first["source"] = payload("raw_memory.txt", read=repr(targets["read"]),
                              list=repr(targets["list"]),
                              write=repr(targets["write"])) + first["source"]
    return nb


def lookup_notebook(src, table: dict) -> dict:
    """The q5 model with ``phong`` answering from ``table`` (keyed by ``key.txt``'s ``_key``)."""
    nb = model_version(src)
    nb["cells"][cell_index(nb, "phong")]["source"] = payload("key.txt") + table_phong(table,
                                                                                      "phong")
    return nb


def table_phong(table: dict, function: str) -> str:
    return (f"_TABLE = {table!r}\n"
            f"def {function}(*args, **kwargs):\n"
            "    hit = _TABLE.get(_key(args, kwargs))\n"
            "    if hit == 'RAISE':\n"
            "        raise ValueError('from the table')\n"
            "    return np.array(hit, dtype=float) if hit is not None else np.zeros(3)\n")


def elsewhere_notebook(src, helper: str, choice: str) -> dict:
    """The q5 model whose ``phong`` delegates to ``_rt_impl``, defined with ``helper`` in the
    cell of item ``choice``."""
    nb = model_version(src)
    model_phong = cell_of(nb, "phong")
    nb["cells"][cell_index(nb, "phong")]["source"] = payload("delegate.txt")
    append_cell(nb, choice, model_phong.replace("def phong(", "def _rt_impl(") + "\n" + helper)
    return nb
