"""A class of generated submissions graded with ``--jobs 2``: CSV, feedback and gradebook agree,
and grading the same folder again gives the same scores.

Each generated student hands in one or two notebooks; in each, every *independent* graded name
(one no other solution calls) is, at random, the model answer, a wrong answer, the release stub
(``raise NotImplementedError()``) or a deleted cell, so every expected score is known exactly by
construction: full points, or 0 with status failed / unanswered (the stub) / missing.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import sqlite3

import numpy as np
import pytest

from autograder.exercises import REGISTRY
from gradingtools import (SECRET, cell_index, gradebook_grades, model_version, read_grades,
                          release_version, run_grade, write_nb)

pytestmark = [pytest.mark.xdist_group("batch"), pytest.mark.slow]

N_STUDENTS = 24
KINDS = ("model", "wrong", "stub", "deleted")


def _independent(src) -> list[str]:
    model = model_version(src)
    texts = {}
    for c in model["cells"]:
        meta = c["metadata"].get("nbgrader", {})
        if meta.get("solution") and c["cell_type"] == "code":
            texts[meta["grade_id"]] = c["source"]
    out = []
    for name, _, _ in src.graded:
        if name not in REGISTRY or name not in texts:
            continue
        if any(re.search(rf"\b{re.escape(name)}\b", t) for g, t in texts.items() if g != name):
            continue
        out.append(name)
    return out


def _build(src, choice: dict[str, str]) -> dict:
    nb = model_version(src)
    stubbed = release_version(src)
    for name, kind in choice.items():
        ex = REGISTRY[name]
        i = cell_index(nb, name)
        if kind == "wrong":
            nb["cells"][i]["source"] = {
                "choice": f"{name} = 'z'\n", "value": f"{name} = -1.0e9\n",
            }.get(ex.kind, f"def {name}(*args, **kwargs):\n    return 'wrong'\n")
        elif kind == "stub":
            nb["cells"][i]["source"] = stubbed["cells"][cell_index(stubbed, name)]["source"]
        elif kind == "deleted":
            del nb["cells"][i]
    return nb


def _expected(src, choice: dict[str, str]) -> dict[str, tuple[float | None, str]]:
    exp = {}
    for name, tid, pts in src.graded:
        kind = choice.get(name, "model")
        exp[tid] = {"model": (pts, "ok"), "wrong": (0.0, "failed"), "stub": (0.0, "unanswered"),
                    "deleted": (0.0, "missing")}[kind]
    exp.update({gid: (None, "manual") for gid, _ in src.manual})
    return exp


@pytest.fixture(scope="module")
def batch(tmp_path_factory, sources, template_gradebook):
    rng = np.random.default_rng(20061)
    root = tmp_path_factory.mktemp("batch")
    (root / "secret").write_bytes(SECRET + b"\n")
    out = root / "out"
    out.mkdir()
    shutil.copyfile(template_gradebook, out / "gradebook.db")
    expected = {}
    for k in range(N_STUDENTS):
        student = f"s{k:03d}"
        picks = [sources[k % len(sources)]]
        if k % 5 == 0 and len(sources) > 1:
            picks.append(sources[(k + 1) % len(sources)])
        for src in picks:
            choice = {name: str(rng.choice(KINDS)) for name in _independent(src)}
            write_nb(root / "submitted" / student / "tripos2006" / f"{src.name}.ipynb",
                     _build(src, choice))
            for tid, value in _expected(src, choice).items():
                expected[(student, src.name, tid)] = value
    db_url = f"sqlite:///{out / 'gradebook.db'}"
    run_grade(root / "submitted", out, "--db-url", db_url, secret_file=root / "secret")
    first = (out / "grades.csv").read_text()
    pages = {p.relative_to(out): p.read_bytes()
             for p in [out / "report.html", *sorted((out / "feedback").rglob("*.html"))]}
    return {"root": root, "out": out, "expected": expected, "db_url": db_url,
            "rows": read_grades(out), "first_csv": first, "pages": pages}


def test_scores_are_exactly_as_built(batch):
    wrong = {}
    for key, (score, status) in batch["expected"].items():
        row = batch["rows"][key]
        got = None if row["score"] == "" else float(row["score"])
        if row["status"] != status or (got is None) != (score is None) or (
                score is not None and abs(got - score) > 1e-9):
            wrong[key] = ((score, status), (got, row["status"], row["message"][:200]))
    assert not wrong


def test_feedback_pages_match_the_csv(batch, sources):
    manual = {(src.name, gid) for src in sources for gid, _ in src.manual}
    totals: dict[tuple[str, str], list[float]] = {}
    for (student, nb, gid), row in batch["rows"].items():
        if (nb, gid) not in manual:
            t = totals.setdefault((student, nb), [0.0, 0.0])
            t[0] += float(row["score"])
            t[1] += float(row["max_score"])
    for (student, nb), (got, top) in totals.items():
        page = batch["out"] / "feedback" / student / f"{nb}.html"
        text = html.unescape(page.read_text(encoding="utf-8"))
        assert f"{got:g} / {top:g}" in text, (student, nb)
        for (s, n, _gid), row in batch["rows"].items():
            if s == student and n == nb:
                assert row["message"] in text


def test_gradebook_matches_the_csv(batch):
    from nbgrader.api import Gradebook

    grades = gradebook_grades(batch["db_url"])
    for key, row in batch["rows"].items():
        auto_score, needs_manual_grade = grades[key]
        if row["status"] == "manual":
            assert auto_score is None and needs_manual_grade
        else:
            assert auto_score == pytest.approx(float(row["score"]), abs=1e-9)
    with Gradebook(batch["db_url"]) as gb:
        for student in {k[0] for k in batch["rows"]}:
            sub = gb.find_submission("tripos2006", student)
            csv_total = sum(float(r["score"] or 0) for (s, _, _), r in batch["rows"].items()
                            if s == student)
            assert sub.score == pytest.approx(csv_total, abs=1e-6)


def test_regrading_gives_the_same_scores(batch):
    """Same folder, same secret: the same hidden cases, byte for byte the same CSV, feedback
    and report, the gradebook unchanged."""
    con = sqlite3.connect(batch["db_url"][len("sqlite:///"):])
    before = con.execute("SELECT COUNT(*) FROM grade").fetchone()[0]
    con.close()
    run_grade(batch["root"] / "submitted", batch["out"], "--db-url", batch["db_url"],
              secret_file=batch["root"] / "secret")
    assert (batch["out"] / "grades.csv").read_text() == batch["first_csv"]
    for rel, data in batch["pages"].items():
        assert (batch["out"] / rel).read_bytes() == data, rel
    con = sqlite3.connect(batch["db_url"][len("sqlite:///"):])
    after = con.execute("SELECT COUNT(*) FROM grade").fetchone()[0]
    con.close()
    assert after == before, "re-grading updates the existing submissions, it adds none"


def test_autograded_notebooks_are_valid_nbformat(batch):
    import nbformat

    paths = list((batch["out"] / "autograded").rglob("*.ipynb"))
    assert paths
    for path in paths[:40]:
        nb = nbformat.read(str(path), as_version=4)
        nbformat.validate(nb)
        ids = [c.metadata.get("nbgrader", {}).get("grade_id") for c in nb.cells]
        ids = [i for i in ids if i]
        assert len(ids) == len(set(ids))
        json.dumps(nb)
