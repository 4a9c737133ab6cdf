"""Attacks on the batch grader, beyond the bank of ``test_bank.py``, against the OS sandbox.

The payloads, how each becomes a submission, and the table of expected grades live in
``tests/grading/attacks/`` (its README lists what the attacks try). Every attack of
``attacks/expected.csv`` is graded in ONE batch (``python -m autograder grade --jobs 2``, as an
instructor runs it) with an exact expected score and status for every graded cell; the other
fixtures below (a lookup table of the hidden cases, the sandbox's job printed at load time,
the result cap as an oracle, fake frames, a slow notebook, two runs at once) check what one
row of a table cannot.
"""

from __future__ import annotations

import html
import os
import re
import time
from pathlib import Path

import numpy as np
import pytest
from attacks.builders import (blank_attacker, cell_of, elsewhere_notebook, lookup_notebook,
                              payload, raising_fraction, read_table, table_phong)
from gradingtools import (SECRET, append_cell, cases_of, counted_cases, course_sources,
                          expect_full_marks,
                          model_version, points_of, read_grades, run_grade, set_cell, target_of,
                          write_nb)

from autograder.exercises import REGISTRY, for_notebook

pytestmark = [pytest.mark.xdist_group("attacks")]

_ALL = course_sources()
SRC = _ALL[0] if _ALL else None
ATTACKS = read_table()
ODD_IDS = ["bad id;rm -rf", "-rf", "\u00fcn\u00efc\u00f6de", ".hidden"]
SOURCES = {s.name: s for s in _ALL}


def _src_of(student: str):
    return SOURCES.get(ATTACKS[student].notebook) or SRC if student in ATTACKS else SRC


def _blank_attacker(src, root: Path, sub: Path) -> dict:
    ref = Path(REGISTRY[target_of(src)].reference.__code__.co_filename).resolve()
    return blank_attacker(src, {
        "read": [str(src.path), str(ref), str(root / "secret"),
                 str(sub / "rt_zero_d" / "tripos2006" / f"{src.name}.ipynb"),
                 str(root / "out" / "gradebook.db")],
        "list": [str(sub), str(sub / "rt_zero_d"), str(root / "out")],
        "write": [str(root / "out" / "gradebook.db"), str(root / "out" / "grades.csv"),
                  str(root / "out" / "feedback" / "planted.html")]})


@pytest.fixture(scope="module")
def redteam(tmp_path_factory, template_gradebook):
    if SRC is None:
        pytest.skip("no source notebooks with registered exercises yet")
    import shutil

    root = tmp_path_factory.mktemp("attacks")
    sub = root / "submitted"
    for student, attack in ATTACKS.items():
        src = _src_of(student)
        nb = attack.build(src)
        if nb is not None:
            write_nb(sub / student / "tripos2006" / f"{src.name}.ipynb", nb)
    write_nb(sub / "rt_raw_memory" / "tripos2006" / f"{SRC.name}.ipynb",
             _blank_attacker(SRC, root, sub))
    (sub / "rt_symlink_folder").mkdir()
    os.symlink(sub / "rt_zero_d" / "tripos2006", sub / "rt_symlink_folder" / "tripos2006")
    (sub / "rt_symlink_passwd" / "tripos2006").mkdir(parents=True)
    os.symlink("/etc/passwd", sub / "rt_symlink_passwd" / "tripos2006" / f"{SRC.name}.ipynb")
    for odd in ODD_IDS:
        write_nb(sub / odd / "tripos2006" / f"{SRC.name}.ipynb", model_version(SRC))
    (root / "secret").write_bytes(SECRET + b"\n")
    (root / "out").mkdir()
    shutil.copyfile(template_gradebook, root / "out" / "gradebook.db")
    t0 = time.monotonic()
    # after the deadline (--reveal-hidden): the attempts' prints, the evidence that each ran,
    # are in the feedback (before it, a notebook with hidden cases shows none of its prints)
    proc = run_grade(sub, root / "out", "--db-url", f"sqlite:///{root / 'out' / 'gradebook.db'}",
                     "--reveal-hidden", secret_file=root / "secret")
    return {"root": root, "rows": read_grades(root / "out"), "proc": proc,
            "elapsed": time.monotonic() - t0}


def _rows(redteam, student: str, notebook: str) -> dict:
    return {gid: r for (s, nb, gid), r in redteam["rows"].items()
            if s == student and nb == notebook}


def _page(redteam, student: str, notebook: str, with_code: bool = False) -> str:
    path = redteam["root"] / "out" / "feedback" / student / f"{notebook}.html"
    page = html.unescape(path.read_text("utf-8"))
    return page if with_code else re.sub(r"<details class='code'>.*?</details>", "", page,
                                         flags=re.S)


@pytest.mark.parametrize("student", list(ATTACKS))
def test_attack_gets_its_exact_score(redteam, student):
    src = _src_of(student)
    expected = ATTACKS[student].expected(src)
    rows = _rows(redteam, student, src.name)
    assert set(expected) <= set(rows), "one row per graded cell of the SOURCE notebook"
    wrong = {}
    for gid, (score, status) in expected.items():
        row = rows[gid]
        got = None if row["score"] == "" else float(row["score"])
        ok_score = got is None if score is None else (got is not None
                                                      and abs(got - score) < 1e-6)
        if not ok_score or row["status"] != status:
            wrong[gid] = ((score, status), (got, row["status"], row["message"][:300]))
        assert row["message"].strip()
    assert not wrong, f"{student}: expected vs got {wrong}"


def test_no_attack_read_the_reference(redteam):
    """Every steal attempt ran (its output was captured) and none read the source."""
    for student in ATTACKS:
        if student.startswith("rt_steal"):
            page = _page(redteam, student, SRC.name)
            assert "LEAK" not in page, student
            assert "BLOCKED" in page, f"{student}: the attempt did not run"


def test_frames_hold_nothing_of_the_grader(redteam):
    page = _page(redteam, "rt_frames", SRC.name)
    assert "BLOCKED frames" in page and "LEAK" not in page


def test_raw_memory_attacker_scores_0_and_reaches_nothing(redteam, template_gradebook):
    rows = _rows(redteam, "rt_raw_memory", SRC.name)
    assert rows and all(r["score"] in ("", "0") for r in rows.values())
    assert all(r["status"] in ("unanswered", "manual") for r in rows.values()), rows
    page = _page(redteam, "rt_raw_memory", SRC.name)
    assert "RAW WRITE done" in page, "the raw write ran: student code owns its process"
    assert "BLOCKED read" in page and "LEAK" not in page
    assert not (redteam["root"] / "out" / "feedback" / "planted.html").exists()
    others = [r for (s, nb, gid), r in redteam["rows"].items()
              if s == "rt_zero_d" and nb == SRC.name]
    assert others and all(r["status"] in ("ok", "manual") for r in others)


def test_huge_returns_keep_the_feedback_small(redteam):
    for page in (redteam["root"] / "out" / "feedback").rglob("*.html"):
        assert page.stat().st_size < 2 * 2**20, page


def test_mutating_inputs_changes_no_expected_value(redteam):
    """The feedback's expected values are the reference's on the untouched inputs."""
    name = target_of(SRC)
    rows = redteam["rows"]
    assert rows[("rt_mutate_inputs", SRC.name, f"test_{name}")]["status"] == "ok"
    nb = ATTACKS["rt_mutate_inputs"].build(SRC)
    case = next(c for c in cases_of("rt_mutate_inputs", name, nb) if c.raises is None)
    assert np.all(np.isfinite(np.asarray(REGISTRY[name].expected(case), dtype=float)))


def test_odd_student_ids_are_skipped_and_harm_no_one(redteam):
    students = {s for s, _, _ in redteam["rows"]}
    assert not students & set(ODD_IDS)
    assert set(ATTACKS) <= students
    for odd in ODD_IDS:
        if not odd.startswith("."):
            assert repr(odd) in redteam["proc"].stderr
    feedback = redteam["root"] / "out" / "feedback"
    assert sorted(p.name for p in feedback.iterdir()) == sorted([*ATTACKS, "rt_raw_memory"])


def test_attack_batch_is_bounded(redteam):
    assert redteam["proc"].returncode == 0
    assert redteam["elapsed"] < 240
    peak = re.search(r"grader peak memory (\d+) MB", redteam["proc"].stderr)
    assert peak and int(peak.group(1)) < 1024, "the grader stays small whatever students return"


# --------------------------------------------------------------------------------------------
# printing the hidden inputs, then a lookup table of their answers


@pytest.fixture(scope="module")
def lookup(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("lookup")
    (root / "secret").write_bytes(SECRET + b"\n")
    path = root / "submitted" / "spy" / "tripos2006" / "q5_phong.ipynb"
    first = model_version(src)
    append_cell(first, "phong", payload("spy.txt"))
    write_nb(path, first)
    run_grade(root / "submitted", root / "out1", "--no-gradebook", secret_file=root / "secret")
    page = html.unescape((root / "out1" / "feedback" / "spy" / "q5_phong.html").read_text())
    page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)
    ns: dict = {"np": np}
    exec(payload("key.txt"), ns)                       # the same key the table uses
    ex = REGISTRY["phong"]
    table = {}
    for case in cases_of("spy", "phong", first):       # every input of the first run
        table[ns["_key"](case.args, case.kwargs)] = (
            "RAISE" if case.raises is not None else np.asarray(ex.expected(case)).tolist())
    second = lookup_notebook(src, table)
    write_nb(path, second)
    run_grade(root / "submitted", root / "out2", "--no-gradebook", secret_file=root / "secret")
    return {"page": page, "first": first, "second": second, "key": ns["_key"], "table": table,
            "rows": read_grades(root / "out2"), "src": src}


def test_hidden_inputs_were_never_shown(lookup):
    # a notebook with hidden cases shows none of its code's prints before the deadline
    assert "ARGS-SEEN" not in lookup["page"]
    assert "not shown before the deadline" in lookup["page"]


def test_a_lookup_table_of_the_hidden_cases_gains_nothing(lookup):
    cases = cases_of("spy", "phong", lookup["second"])
    first_hidden = {lookup["key"](c.args, c.kwargs)
                    for c in cases_of("spy", "phong", lookup["first"]) if not c.visible}
    now_hidden = {lookup["key"](c.args, c.kwargs) for c in cases if not c.visible}
    assert now_hidden - first_hidden, "the changed function drew new hidden cases"
    passes = [lookup["key"](c.args, c.kwargs) in lookup["table"] for c in cases]
    row = lookup["rows"][("spy", "q5_phong", "test_phong")]
    pts = points_of(lookup["src"], "phong")
    assert float(row["score"]) == pytest.approx(pts * counted_cases(cases, passes) / len(cases),
                                                abs=1e-6)
    assert sum(passes) < len(cases), "the table does not get full marks"


# --------------------------------------------------------------------------------------------
# the other cases' inputs, read where the worker could find them, returned as a string on a
# visible case (before the deadline: nothing of a hidden case is revealed)


@pytest.fixture(scope="module")
def leak(tmp_path_factory):
    src = _src_of("rt_leak_cases")
    if src is None:
        pytest.skip("no source notebooks with registered exercises yet")
    root = tmp_path_factory.mktemp("leak")
    (root / "secret").write_bytes(SECRET + b"\n")
    nb = ATTACKS["rt_leak_cases"].build(src)
    write_nb(root / "submitted" / "rt_leak_cases" / "tripos2006" / f"{src.name}.ipynb", nb)
    proc = run_grade(root / "submitted", root / "out", "--no-gradebook",
                     secret_file=root / "secret")
    name = ATTACKS["rt_leak_cases"].name_in(src)
    numbers = {True: set(), False: set()}       # visible -> the inputs' numbers
    for case in cases_of("rt_leak_cases", name, nb):
        for value in [*case.args, *case.kwargs.values()]:
            try:
                got = np.asarray(value, dtype=float).ravel()
            except (TypeError, ValueError):
                continue
            # long reprs only: a random input's digits, not a 0.5 that any page may hold
            numbers[bool(case.visible)] |= {repr(float(x)) for x in got if len(repr(float(x))) >= 8}
    hidden = numbers[False] - numbers[True]
    outputs = {str(p.relative_to(root)): p.read_text("utf-8", "replace")
               for p in (root / "out").rglob("*") if p.is_file()}
    outputs.update(stdout=proc.stdout, stderr=proc.stderr)
    return {"hidden": hidden, "outputs": outputs, "rows": read_grades(root / "out"),
            "name": name, "root": root, "src": src}


def test_no_hidden_input_reaches_any_output(leak):
    assert leak["hidden"], "the target has hidden cases with random inputs"
    for where, text in leak["outputs"].items():
        shown = sorted(h for h in leak["hidden"] if h in text)
        assert not shown, f"{where} shows hidden inputs {shown[:5]}"


def test_a_returned_string_is_described_not_shown(leak):
    src = leak["src"]
    row = leak["rows"][("rt_leak_cases", src.name, f"test_{leak['name']}")]
    assert row["status"] == "failed" and float(row["score"]) == 0.0
    assert "returned a str, expected" in row["message"]
    page = html.unescape((leak["root"] / "out" / "feedback" / "rt_leak_cases"
                          / f"{src.name}.html").read_text("utf-8"))
    page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)  # its code
    assert "not of the expected type and shape" in page and "LEAKED" not in page


# --------------------------------------------------------------------------------------------
# one name's worker posts every input it sees (hidden ones last) to a System V message queue; a
# later name's first visible cases raise with what they read there, as the message and as the
# exception's class name (issue 33, finding 5)


def _long_numbers(cases) -> set[str]:
    """The reprs of the cases' input numbers long enough to be a random draw's digits."""
    found = set()
    for case in cases:
        for value in [*case.args, *case.kwargs.values()]:
            try:
                got = np.asarray(value, dtype=float).ravel()
            except (TypeError, ValueError):
                continue
            found |= {repr(float(x)) for x in got if len(repr(float(x))) >= 8}
    return found


@pytest.fixture(scope="module")
def queue(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("queue")
    (root / "secret").write_bytes(SECRET + b"\n")
    nb = model_version(src)
    append_cell(nb, "normalize", payload("queue_post.txt"))
    append_cell(nb, "phong", payload("queue_read.txt"))
    path = root / "submitted" / "rt_queue" / "tripos2006" / "q5_phong.ipynb"
    write_nb(path, nb)
    pages, outputs = {}, {}
    for out, extra in (("before", ()), ("after", ("--reveal-hidden",))):
        proc = run_grade(root / "submitted", root / out, "--no-gradebook", *extra,
                         secret_file=root / "secret")
        pages[out] = html.unescape((root / out / "feedback" / "rt_queue" / "q5_phong.html")
                                   .read_text("utf-8"))
        outputs[out] = [p.read_text("utf-8", "replace") for p in (root / out).rglob("*")
                        if p.is_file()] + [proc.stdout, proc.stderr]
    cases = cases_of("rt_queue", "normalize", path)     # as submitted (its items typed)
    hidden = (_long_numbers([c for c in cases if not c.visible])
              - _long_numbers([c for c in cases if c.visible]))
    return {"pages": pages, "outputs": outputs, "hidden": hidden, "src": src,
            "rows": read_grades(root / "before")}


def test_no_queue_carries_hidden_inputs_to_the_page(queue):
    assert queue["hidden"], "normalize has hidden cases with random inputs"
    for text in queue["outputs"]["before"] + queue["outputs"]["after"]:
        shown = sorted(h for h in queue["hidden"] if h in text)
        assert not shown, f"hidden inputs {shown[:5]} reached an output"
    # the poster's cell ran in every worker and normalize is graded as the model answer
    row = queue["rows"][("rt_queue", "q5_phong", "test_normalize")]
    assert row["status"] == "ok", row["message"]


def test_before_the_deadline_a_visible_case_shows_an_exceptions_type_only(queue):
    before, after = (re.sub(r"<details class='code'>.*?</details>", "", queue["pages"][k],
                            flags=re.S) for k in ("before", "after"))
    assert "raised TypeError" in before and "QUEUE" not in before
    assert "an exception of its own class" in before
    row = queue["rows"][("rt_queue", "q5_phong", "test_phong")]
    assert row["status"] == "error" and "QUEUE" not in row["message"]
    # after the deadline the message is shown as before: the attack ran, the queue was empty
    assert "QUEUE-MARK EMPTY" in after and "QUEUE_EMPTY" in after


# --------------------------------------------------------------------------------------------
# the lookup table behind a helper in ANOTHER cell; the sandbox's /job printed at load time:
# the phong cell itself never changes

CHOICE = "q5_item3"


@pytest.fixture(scope="module")
def elsewhere(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("elsewhere")
    (root / "secret").write_bytes(SECRET + b"\n")
    path = root / "submitted" / "rt_elsewhere" / "tripos2006" / "q5_phong.ipynb"
    first = elsewhere_notebook(src, payload("print_job.txt"), CHOICE)
    write_nb(path, first)
    run_grade(root / "submitted", root / "out1", "--no-gradebook", secret_file=root / "secret")
    page = html.unescape((root / "out1" / "feedback" / "rt_elsewhere" / "q5_phong.html")
                         .read_text())
    page = re.sub(r"<details class='code'>.*?</details>", "", page, flags=re.S)
    ns: dict = {"np": np}
    exec(payload("key.txt"), ns)
    ex = REGISTRY["phong"]
    table = {ns["_key"](c.args, c.kwargs): ("RAISE" if c.raises is not None
                                            else np.asarray(ex.expected(c)).tolist())
             for c in cases_of("rt_elsewhere", "phong", first)}   # a perfect leak, say
    helper = payload("key.txt") + table_phong(table, "_rt_impl")
    second = elsewhere_notebook(src, helper, CHOICE)
    write_nb(path, second)
    run_grade(root / "submitted", root / "out2", "--no-gradebook", secret_file=root / "secret")
    return {"page": page, "first": first, "second": second, "key": ns["_key"], "table": table,
            "rows1": read_grades(root / "out1"), "rows2": read_grades(root / "out2"), "src": src}


def test_the_job_printed_at_load_time_is_not_in_the_feedback(elsewhere):
    row = elsewhere["rows1"][("rt_elsewhere", "q5_phong", "test_phong")]
    assert float(row["score"]) == pytest.approx(points_of(elsewhere["src"], "phong"), abs=1e-6)
    assert "JOB-DUMP" not in elsewhere["page"] and '"cases"' not in elsewhere["page"]


def test_a_table_in_another_cell_gains_nothing(elsewhere):
    cases = cases_of("rt_elsewhere", "phong", elsewhere["second"])
    key = elsewhere["key"]
    first_hidden = {key(c.args, c.kwargs) for c in
                    cases_of("rt_elsewhere", "phong", elsewhere["first"]) if not c.visible}
    # the phong cell is the same in both rounds: only the seed over every cell redraws
    assert cell_of(elsewhere["first"], "phong") == cell_of(elsewhere["second"], "phong")
    assert {key(c.args, c.kwargs) for c in cases if not c.visible} - first_hidden
    passes = [key(c.args, c.kwargs) in elsewhere["table"] for c in cases]
    assert sum(passes) < len(cases)
    row = elsewhere["rows2"][("rt_elsewhere", "q5_phong", "test_phong")]
    pts = points_of(elsewhere["src"], "phong")
    assert float(row["score"]) == pytest.approx(
        pts * counted_cases(cases, passes) / len(cases), abs=1e-6)


# --------------------------------------------------------------------------------------------
# the result cap as an oracle, fake frames against the time limit, a notebook that holds its
# grading slot; a correct victim in the same batch

HOLD_JOB_TIMEOUT = 15


def _phong_with(edits: dict, student: str) -> dict:
    """The model q5 notebook with ``edits`` appended, its number item typed as a literal (so
    loading the cells calls no graded function: only the cases do)."""
    nb = model_version(SOURCES["q5_phong"])
    for name, code in edits.items():
        append_cell(nb, name, code)
    answer = REGISTRY["q5b_your_intensity"].value_for(student).tolist()
    set_cell(nb, "q5b_your_intensity", f"q5b_your_intensity = {answer!r}\n")
    return nb


#: q5's graded functions, from the registry (a typed list would miss one added later)
Q5_FUNCTIONS = tuple(ex.name for ex in for_notebook("q5_phong") if ex.kind == "function")


@pytest.fixture(scope="module")
def hold(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("hold")
    sub = root / "submitted"
    nbs = {"rt_cap_oracle": _phong_with({"normalize": payload("cap_oracle.txt")}, "rt_cap_oracle"),
           "rt_extend": _phong_with({"normalize": payload("extend.txt")}, "rt_extend"),
           "rt_slow": _phong_with({n: payload("slow.txt", name=n) for n in Q5_FUNCTIONS},
                                  "rt_slow"),
           "zz_victim": model_version(src)}
    for student, nb in nbs.items():
        write_nb(sub / student / "tripos2006" / "q5_phong.ipynb", nb)
    (root / "secret").write_bytes(SECRET + b"\n")
    t0 = time.monotonic()
    run_grade(sub, root / "out", "--no-gradebook", "--job-timeout", str(HOLD_JOB_TIMEOUT),
              secret_file=root / "secret")
    return {"rows": read_grades(root / "out"), "elapsed": time.monotonic() - t0, "nbs": nbs,
            "src": src}


def test_the_result_cap_tells_nothing(hold):
    raising, n = raising_fraction("rt_cap_oracle", "normalize", hold["nbs"]["rt_cap_oracle"])
    row = hold["rows"][("rt_cap_oracle", "q5_phong", "test_normalize")]
    pts = points_of(hold["src"], "normalize")
    assert raising >= 1
    # the naive answer is right exactly where no ValueError is due, as without the oracle
    assert float(row["score"]) == pytest.approx(pts * (n - raising) / n, abs=1e-6)
    assert row["status"] == "failed"


def test_fake_start_frames_do_not_beat_the_time_limit(hold):
    row = hold["rows"][("rt_extend", "q5_phong", "test_normalize")]
    n = len(cases_of("rt_extend", "normalize", hold["nbs"]["rt_extend"]))
    pts = points_of(hold["src"], "normalize")
    # the 6 s first case is a timeout; every other case is answered in time and right
    assert float(row["score"]) == pytest.approx(pts * (n - 1) / n, abs=1e-6)
    assert row["status"] == "timeout"
    others = {gid: r for (s, nb, gid), r in hold["rows"].items()
              if s == "rt_extend" and nb == "q5_phong" and gid != "test_normalize"
              and r["status"] != "manual"}
    assert others and all(r["status"] == "ok" for r in others.values()), others


def test_a_slow_notebook_stops_at_the_job_time_limit(hold):
    rows = {gid: r for (s, nb, gid), r in hold["rows"].items()
            if s == "rt_slow" and nb == "q5_phong"}
    for name in Q5_FUNCTIONS:
        assert float(rows[f"test_{name}"]["score"]) == 0.0
    assert any("the notebook used up its time" in r["message"] for r in rows.values())
    # the whole batch took about one job time limit, not 5 names x ~15 cases x 1 s
    assert hold["elapsed"] < HOLD_JOB_TIMEOUT + 60


def test_the_victim_in_the_same_batch_is_unaffected(hold):
    for gid, (score, status) in expect_full_marks(hold["src"]).items():
        row = hold["rows"][("zz_victim", "q5_phong", gid)]
        assert row["status"] == status, (gid, row["message"])
        if score is not None:
            assert float(row["score"]) == pytest.approx(score, abs=1e-6), gid


# --------------------------------------------------------------------------------------------
# neighbours in the same batch: spinning (60 processes, each in a session of its own), sleeping,
# memory-hungry; honest students graded beside them

NEIGHBOURS = {"n1_spin": "spin.txt", "n3_sleep": "sleep.txt", "n5_hog": "hog.txt"}
HONEST = ("n2_honest", "n4_honest", "n6_honest")
PHONG_NAMES = ("normalize", "reflect", "phong", "halfway", "blinn_phong")
NEIGHBOURS_CASE_TIMEOUT = 0.5


@pytest.fixture(scope="module")
def neighbours(tmp_path_factory):
    src = SOURCES.get("q5_phong")
    if src is None:
        pytest.skip("q5_phong is not in the course")
    root = tmp_path_factory.mktemp("neighbours")
    sub = root / "submitted"
    nbs = {student: _phong_with({n: payload(name_of, name=n) for n in PHONG_NAMES}, student)
           for student, name_of in NEIGHBOURS.items()}
    for student, nb in nbs.items():
        write_nb(sub / student / "tripos2006" / "q5_phong.ipynb", nb)
    # the first honest student hands in every notebook (the costlier cases too), graded in the
    # other slot while the spinner holds its own for up to a minute; the others meet the
    # sleeper and the hog
    honest = {HONEST[0]: _ALL} | {student: [src] for student in HONEST[1:]}
    for student, srcs in honest.items():
        for honest_src in srcs:
            write_nb(sub / student / "tripos2006" / f"{honest_src.name}.ipynb",
                     model_version(honest_src))
    (root / "secret").write_bytes(SECRET + b"\n")
    # a tight limit (every honest case needs far less CPU): a case's time is its own CPU time,
    # so the neighbours cannot make it longer; were it wall-clock time, they would
    run_grade(sub, root / "out", "--no-gradebook", "--job-timeout", "60", "--memory-mb", "768",
              timeout=NEIGHBOURS_CASE_TIMEOUT, secret_file=root / "secret")
    return {"rows": read_grades(root / "out"), "honest": honest}


def test_neighbours_cost_an_honest_student_nothing(neighbours):
    """The spinner's 60 sessions share ONE job's CPU (its cgroup), and a case's time is its own
    CPU time: the honest students beside it get full marks, no case timed out."""
    for student, srcs in neighbours["honest"].items():
        for honest_src in srcs:
            for gid, (score, status) in expect_full_marks(honest_src).items():
                row = neighbours["rows"][(student, honest_src.name, gid)]
                assert row["status"] == status, (student, gid, row["message"])
                if score is not None:
                    assert float(row["score"]) == pytest.approx(score, abs=1e-6), (student, gid)


def test_the_neighbours_themselves_score_nothing(neighbours):
    for student in NEIGHBOURS:
        for name in PHONG_NAMES:
            row = neighbours["rows"][(student, "q5_phong", f"test_{name}")]
            assert float(row["score"]) == 0.0, (student, name, row["message"])


# --------------------------------------------------------------------------------------------
# two grading runs at once on one machine


def test_two_grading_runs_at_once_are_both_right(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    name = target_of(SRC)
    wrong = model_version(SRC)
    append_cell(wrong, name, f"def {name}(*args, **kwargs):\n    return 'wrong'\n")
    sets = {}
    for k in range(2):
        sub = tmp_path / f"set{k}"
        write_nb(sub / f"good{k}" / "tripos2006" / f"{SRC.name}.ipynb", model_version(SRC))
        write_nb(sub / f"bad{k}" / "tripos2006" / f"{SRC.name}.ipynb", wrong)
        sets[k] = sub

    def grade(k):
        return run_grade(sets[k], tmp_path / f"out{k}", "--no-gradebook",
                         secret_file=tmp_path / "secret")

    with ThreadPoolExecutor(2) as pool:
        list(pool.map(grade, range(2)))
    for k in range(2):
        rows = read_grades(tmp_path / f"out{k}")
        for student, exp in ((f"good{k}", expect_full_marks(SRC)),
                             (f"bad{k}", {**expect_full_marks(SRC), f"test_{name}": (0.0, None)})):
            for gid, (score, status) in exp.items():
                row = rows[(student, SRC.name, gid)]
                if score is None:
                    assert row["score"] == "" and row["status"] == "manual"
                    continue
                assert float(row["score"]) == pytest.approx(score, abs=1e-6), (k, student, gid)
                if status is not None:
                    assert row["status"] == status, (k, student, gid, row["message"])


# --------------------------------------------------------------------------------------------
# the batch survives any submission: every output for everyone, sentences


def test_no_submission_causes_a_grader_error(redteam):
    errors = {k: r["message"] for k, r in redteam["rows"].items() if r["status"] == "grader-error"}
    assert not errors


def test_uncompilable_and_oversized_cells_say_why(redteam):
    name = target_of(SRC)
    row = redteam["rows"]
    assert "duplicate argument" in row[("rt_dup_arg", SRC.name, f"test_{name}")]["message"]
    assert "nested too deeply" in row[("rt_deep_graded", SRC.name, f"test_{name}")]["message"]
    assert "kB of code" in row[("rt_big_cell", SRC.name, f"test_{name}")]["message"]
    assert "MB of code" in row[("rt_big_notebook", SRC.name, f"test_{name}")]["message"]


def test_every_student_gets_feedback_report_and_gradebook(redteam):
    from autograder.outputs.gradebook import course_root

    root = redteam["root"]
    out = root / "out"
    course = course_root(root / "submitted", out)
    assert "Similar solutions" in (out / "report.html").read_text("utf-8")
    for student in [*ATTACKS, "rt_raw_memory"]:
        assert (out / "feedback" / student / f"{SRC.name}.html").is_file(), student
        auto = course / "autograded" / student / "tripos2006" / f"{SRC.name}.ipynb"
        assert auto.is_file(), student
    assert "\ufffd" in _page(redteam, "rt_surrogate", SRC.name, with_code=True)


def test_flooded_code_is_cut_after_escaping(redteam):
    from autograder.outputs.feedback import CODE_CHARS

    src = _src_of("rt_quote_flood")
    path = redteam["root"] / "out" / "feedback" / "rt_quote_flood" / f"{src.name}.html"
    raw = path.read_text("utf-8")
    blocks = re.findall(r"<details class='code'><summary>[^<]*</summary><pre>(.*?)</pre>", raw,
                        flags=re.S)
    assert len(blocks) == len(src.graded) + len(src.manual)
    assert all(len(b) <= CODE_CHARS + 1 for b in blocks)
    assert path.stat().st_size < 2 * 2**20
