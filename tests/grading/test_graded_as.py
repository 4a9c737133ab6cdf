"""The remedy for an honest wrong id: ``grade --graded-as STUDENT=ID --reason ...``.

bob2 worked the whole assignment under alice's id (``STUDENT_ID = "alice"``, alice's numbers
and option letters typed), and handed it in as bob2. Graded as usual, the items whose right
answer differs between the two ids are wrong (decided here with the registry's references for
both ids, not by the grader), and the feedback page tells bob2 that the notebook names another
id. Graded with ``--graded-as bob2=alice``, every item scores (the source's points), each says
whose numbers judged it, ``graded-as.log`` holds the decision, its reason and the evidence, and
``report.html`` shows it after the "Own numbers" evidence.
"""

from __future__ import annotations

import datetime as dt
import getpass
import html
import re
import shutil

import pytest

from autograder.exercises import REGISTRY
from autograder.grade import remedy
from autograder.grade.remedy import LOG_NAME, Decision, merge, parse_graded_as, standing
from autograder.model import Batch
from autograder.outputs.variants import graded_as_html
from gradingtools import read_grades, run_grade, write_nb
from test_own_numbers import _differs, literal_version

pytestmark = [pytest.mark.xdist_group("graded_as"), pytest.mark.slow]


def _items(src):
    return [(name, tid, pts) for name, tid, pts in src.graded
            if name in REGISTRY and REGISTRY[name].kind in ("choice", "value")]


REASON = "typed a friend's id; worked alone (emails of 3 Dec)"


@pytest.fixture(scope="module")
def wrong_id(tmp_path_factory, sources):
    root = tmp_path_factory.mktemp("graded-as")
    used = [s for s in sources if _items(s)]
    for src in used:
        write_nb(root / "submitted" / "bob2" / "tripos2006" / f"{src.name}.ipynb",
                 literal_version(src, "alice"), type_answers=False)
    run_grade(root / "submitted", root / "plain", "--no-gradebook")
    remedied = run_grade(root / "submitted", root / "remedied", "--no-gradebook",
                         "--graded-as", "bob2=alice", "--reason", REASON)
    return root, used, remedied


def test_graded_as_usual_the_other_ids_items_are_wrong_and_the_page_says_why(wrong_id):
    root, used, _ = wrong_id
    rows = read_grades(root / "plain")
    differing = [(src, name, tid) for src in used for name, tid, _ in _items(src)
                 if _differs(name, "alice", "bob2")]
    assert differing, "alice's and bob2's numbers differ somewhere"
    for src, name, tid in differing:
        assert rows[("bob2", src.name, tid)]["status"] == "failed", name
    page = html.unescape((root / "plain" / "feedback" / "bob2" / f"{used[0].name}.html")
                         .read_text(encoding="utf-8"))
    assert "this notebook names alice" in page and 'STUDENT_ID = "bob2"' in page


def test_graded_as_the_id_it_was_worked_for_every_item_scores(wrong_id):
    root, used, remedied = wrong_id
    rows = read_grades(root / "remedied")
    for src in used:
        for name, tid, points in _items(src):
            row = rows[("bob2", src.name, tid)]
            assert float(row["score"]) == pytest.approx(points, abs=1e-9), (name, row)
            assert "option letters of alice" in row["message"]
    log = (root / "remedied" / LOG_NAME).read_text(encoding="utf-8")
    assert "bob2 graded on the numbers and option letters of alice" in log
    assert "reason: typed a friend's id; worked alone (emails of 3 Dec)" in log
    assert f"{used[0].name} names alice" in log                  # the evidence
    for output in (LOG_NAME, "report.html", "grades.csv", "feedback pages"):
        assert output in remedied.stderr.split("wrote:")[-1], output   # named at the end
    page = html.unescape((root / "remedied" / "feedback" / "bob2" / f"{used[0].name}.html")
                         .read_text(encoding="utf-8"))
    assert "Graded on the numbers and option letters of alice" in page


def _cells(row: str) -> list[str]:
    return [html.unescape(re.sub(r"<[^>]+>", "", c)) for c in re.findall(r"<td>(.*?)</td>", row)]


def test_the_report_shows_the_decision_beside_the_own_numbers_evidence(wrong_id):
    root, _, _ = wrong_id
    report = (root / "remedied" / "report.html").read_text(encoding="utf-8")
    logged = remedy.read_log(root / "remedied")
    assert len(logged) == 1
    start = report.index("<section class='graded-as'>")
    section = report[start:report.index("</section>", start)]
    assert report.index("<section class='own-numbers'>") < start
    rows = re.findall(r"<tr><td>.*?</tr>", section, re.S)
    assert len(rows) == 1
    student, graded_on, reason, by, when, evidence, applied = _cells(rows[0])
    assert (student, graded_on, reason, by) == ("bob2", "alice", REASON, getpass.getuser())
    assert when == logged[0]["when"] and dt.datetime.fromisoformat(when).tzinfo is not None
    assert "names alice" in evidence and applied == "applied"
    # graded as usual, the report has no such section
    assert "graded-as" not in (root / "plain" / "report.html").read_text(encoding="utf-8")


def test_a_logged_decision_this_run_did_not_apply_is_marked(tmp_path):
    """The log is appended across runs; the report shows each student's latest decision and
    whether the run applied it (a re-grade without ``--graded-as`` does not)."""
    empty = Batch(results=[], submissions={}, students=[])
    remedy.log(tmp_path, [Decision("bob2", "carol", "first\tthought")], empty)
    why = "typed a friend's id;\n\tworked alone"
    remedy.log(tmp_path, [Decision("bob2", "alice", why), Decision("dan", "erin", why)], empty)
    assert len((tmp_path / LOG_NAME).read_text(encoding="utf-8").splitlines()) == 3
    rows = remedy.decisions(tmp_path, {"bob2": "alice"})
    assert [(d["student"], d["graded_as"], d["applied"]) for d in rows] == \
        [("bob2", "alice", True), ("dan", "erin", False)]
    assert rows[0]["reason"] == "typed a friend's id; worked alone"   # one line in the log
    assert rows[0]["evidence"] == "none found in the notebooks"
    assert [d["applied"] for d in remedy.decisions(tmp_path, {})] == [False, False]
    page = graded_as_html(rows)
    assert "(1 in this run" in page and page.count("NOT applied") == 1
    assert graded_as_html([]) == "" and remedy.decisions(tmp_path / "none", {}) == []


@pytest.mark.parametrize("pairs, reason, why", [
    (["bob2=alice"], "", "--reason"),
    (["bob2=alice:  "], "", "--reason"),
    (["bob2"], "r", "is not STUDENT=ID"),
    (["bob2=alice", "bob2=carol"], "r", "two ids"),
    (["nobody=alice"], "r", "no submission of nobody"),
    (["bob2=../x"], "r", "is not STUDENT=ID"),
])
def test_graded_as_refuses_what_it_cannot_log_clearly(tmp_path, pairs, reason, why):
    (tmp_path / "bob2" / "tripos2006").mkdir(parents=True)
    with pytest.raises(ValueError, match=why):
        parse_graded_as(pairs, reason, tmp_path)


def test_each_decision_has_its_own_reason_and_a_withdrawal_is_a_decision(tmp_path):
    for s in ("bob2", "carol"):
        (tmp_path / s / "tripos2006").mkdir(parents=True)
    got = parse_graded_as(["bob2=alice:typed alice's id", "carol=carol"], "withdrawn: wrong",
                          tmp_path)
    assert (got["bob2"].other, got["bob2"].reason) == ("alice", "typed alice's id")
    assert got["carol"].withdrawn and got["carol"].reason == "withdrawn: wrong"


def test_the_log_is_read_back_latest_line_per_student_withdrawals_end_a_decision(tmp_path):
    (tmp_path / LOG_NAME).write_text(
        "2026-12-01T10:00:00+00:00\tby ann\tbob2 graded on the numbers and option letters of "
        "alice\treason: slip\tevidence: q1 names alice\n"
        "2026-12-01T10:00:00+00:00\tby ann\tcarol graded on the numbers and option letters of "
        "dan\treason: slip too\tevidence: none\n"
        "not a decision line\n"
        "2026-12-02T09:00:00+00:00\tby tom\tcarol withdrawn: graded on its own id again\t"
        "reason: carol worked her own id after all\tevidence: none\n", encoding="utf-8")
    now = standing(tmp_path)
    assert list(now) == ["bob2"]
    assert (now["bob2"].other, now["bob2"].by, now["bob2"].when) == (
        "alice", "ann", "2026-12-01T10:00:00+00:00")
    assert now["bob2"].describe() == ("graded bob2 as alice, decided 2026-12-01T10:00:00+00:00 "
                                      "by ann: slip")
    (tmp_path / "bob2" / "tripos2006").mkdir(parents=True)
    same = parse_graded_as(["bob2=alice"], "again", tmp_path)
    applied, changes = merge(now, same)
    assert changes == [] and applied == now             # the same decision is not logged twice
    applied, changes = merge(now, parse_graded_as(["bob2=bob2"], "undo", tmp_path))
    assert applied == {} and [d.student for d in changes] == ["bob2"]


def test_a_decision_stands_on_every_later_grade_until_withdrawn(wrong_id):
    root, used, _ = wrong_id
    again = root / "again"
    again.mkdir()
    shutil.copy(root / "remedied" / LOG_NAME, again / LOG_NAME)
    run = run_grade(root / "submitted", again, "--no-gradebook")        # no --graded-as
    assert "graded bob2 as alice, decided 20" in run.stderr
    assert "typed a friend's id; worked alone (emails of 3 Dec)" in run.stderr
    rows = read_grades(again)
    for src in used:
        for _name, tid, points in _items(src):
            assert float(rows[("bob2", src.name, tid)]["score"]) == pytest.approx(points, abs=1e-9)
    run_grade(root / "submitted", again, "--no-gradebook", "--graded-as",
              "bob2=bob2:on reflection not a slip")
    log = (again / LOG_NAME).read_text(encoding="utf-8")
    assert "bob2 withdrawn: graded on its own id again\treason: on reflection not a slip" in log
    rows, plain = read_grades(again), read_grades(root / "plain")
    for src in used:
        for _name, tid, _ in _items(src):
            key = ("bob2", src.name, tid)
            assert (rows[key]["status"], rows[key]["score"]) == (plain[key]["status"],
                                                                 plain[key]["score"])
    assert standing(again) == {}
