"""Item analysis (``items.csv``, the report's "Items" section) against independent computations:
SciPy's ``pearsonr``, ``chi2``, ``fisher_exact`` and ``chi2_contingency``, alpha and Kelley's
groups worked by hand, and a published worked example."""

from __future__ import annotations

import csv
import math
import statistics
from html.parser import HTMLParser

import numpy as np
import pytest
from scipy import stats as sps

from autograder.model import CellKind, CellResult, Status
from autograder.outputs import item_checks, items, items_html
from course_lib import variants

N = 240
FILLERS = 12


def _result(student, notebook, gid, score, top=1.0, kind=CellKind.FUNCTION, name=None,
            answer=None, status=None, whole=False):
    status = status or (Status.OK if score >= top else Status.FAILED)
    return CellResult(student, notebook, gid, name or gid, score, top, status, "", kind=kind,
                      answer=answer, whole_notebook=whole)


def _typed(name: str, canonical: str, student: str, k: int) -> str:
    """What the student types for canonical option ``canonical``: their own letter, in one of
    the forms the grader accepts (case, spaces, commas ignored)."""
    shown = variants.displayed_letters(name, canonical, 4, student)
    return (shown, f" {shown.upper()} ", f"{shown},")[k % 3]


@pytest.fixture(scope="module")
def klass():
    """240 students of known ability: 12 filler functions that track it (the rest score), and
    five items of known behaviour in q1_imaging."""
    rng = np.random.default_rng(20261203)
    theta = rng.normal(size=N)
    ids = [f"s{i:03d}" for i in range(N)]
    rank = {ids[i]: r for r, i in enumerate(np.argsort(-theta))}    # 0 = strongest
    results = []
    for i, s in enumerate(ids):
        for j in range(FILLERS):
            p = 1 / (1 + math.exp(-(1.7 * theta[i] + 1.0 - 0.15 * j)))
            score = 2.0 if rng.random() < p else (1.0 if rng.random() < 0.3 else 0.0)
            results.append(_result(s, "q5_phong", f"test_f{j:02d}", score, 2.0))
        results.append(_result(s, "q1_imaging", "test_everyone", 1.0))
        results.append(_result(s, "q1_imaging", "test_nobody", 0.0))
        results.append(_result(s, "q1_imaging", "test_strong", 3.0 if theta[i] > 0.6 else 0.0,
                               3.0))
        # pure guess: in each block of 4 students by ability, each option once, rotating
        block, pos = divmod(rank[s], 4)
        pick = "abcd"[(pos + block) % 4]
        results.append(_result(s, "q1_imaging", "test_q1_item2", float(pick == "d"),
                               kind=CellKind.CHOICE, name="q1_item2",
                               answer=_typed("q1_item2", pick, s, i)))
        # key c for the top 30 %, the distractor b for the next 50 %, a for the rest, d never
        r = rank[s] / N
        pick = "c" if r < 0.3 else ("b" if r < 0.8 else "a")
        results.append(_result(s, "q1_imaging", "test_q1_item1", float(pick == "c"),
                               kind=CellKind.CHOICE, name="q1_item1",
                               answer=_typed("q1_item1", pick, s, i)))
    return {"results": results, "theta": dict(zip(ids, theta)), "rank": rank, "ids": ids}


def _oracle(results):
    """Facility, discrimination and upper-lower of every item, computed from scratch."""
    total, by_item = {}, {}
    for r in results:
        total[r.student] = total.get(r.student, 0.0) + r.score
        by_item.setdefault((r.notebook, r.grade_id), []).append(r)
    out = {}
    for key, rs in by_item.items():
        frac = [r.score / r.max_score for r in rs]
        rest = [total[r.student] - r.score for r in rs]
        disc = None if len(set(frac)) < 2 or len(set(rest)) < 2 else sps.pearsonr(frac, rest)[0]
        k = math.ceil(0.27 * len(rs) - 1e-9)
        upper = sorted(zip(rest, [r.student for r in rs], frac), key=lambda t: (-t[0], t[1]))[:k]
        lower = sorted(zip(rest, [r.student for r in rs], frac), key=lambda t: (t[0], t[1]))[:k]
        ul = sum(t[2] for t in upper) / k - sum(t[2] for t in lower) / k
        out[key] = (len(rs), sum(frac) / len(rs), disc, ul)
    return out


def test_statistics_match_an_independent_computation(klass):
    stats = items.item_statistics(items.responses(klass["results"]))
    oracle = _oracle(klass["results"])
    assert len(stats) == FILLERS + 5
    for s in stats:
        n, facility, disc, ul = oracle[(s.notebook, s.grade_id)]
        assert s.n == n == N
        assert s.facility == pytest.approx(facility, abs=1e-12)
        if disc is None:
            assert s.discrimination is None
        else:
            assert s.discrimination == pytest.approx(disc, abs=1e-9)
        assert s.upper_lower == pytest.approx(ul, abs=1e-12)


def test_the_flags_come_out_as_designed(klass):
    stats = {s.grade_id: s for s in items.item_statistics(items.responses(klass["results"]))}
    assert stats["test_everyone"].flag == "review" and stats["test_everyone"].facility == 1.0
    assert stats["test_everyone"].discrimination is None      # no variance: no correlation
    assert stats["test_everyone"].upper_lower == pytest.approx(0.0, abs=1e-12)
    assert stats["test_nobody"].flag == "review" and stats["test_nobody"].facility == 0.0
    strong = stats["test_strong"]
    assert strong.flag == "" and strong.discrimination > 0.5
    # top 27 % by rest score are mostly above theta 0.6 (the top 27 % of a normal class)
    assert strong.upper_lower > 0.6
    guess = stats["test_q1_item2"]
    assert guess.facility == pytest.approx(0.25, abs=0.01)
    assert abs(guess.discrimination) < DISCRIMINATION and guess.flag == "review"
    popular = stats["test_q1_item1"]
    assert popular.facility == pytest.approx(0.3, abs=0.005) and popular.flag == ""
    assert sum(s.flag == "review" for s in stats.values() if s.grade_id.startswith("test_f")) \
        <= 2    # the fillers work (a few may be easy)


DISCRIMINATION = items.DISCRIMINATION_LOW


def test_the_csv_has_exactly_the_columns_and_no_nan(klass, tmp_path):
    stats = items.item_statistics(items.responses(klass["results"]))
    path = items.write_items_csv(stats, tmp_path / "items.csv")
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["notebook", "grade_id", "kind", "max_score", "n", "facility",
                       "discrimination", "upper_lower", "flag"]
    by_id = {r[1]: r for r in rows[1:]}
    assert by_id["test_everyone"][6] == ""          # empty, not nan
    assert by_id["test_strong"][2:5] == ["function", "3", str(N)]
    assert by_id["test_q1_item1"][2] == "choice"
    assert not any("nan" in cell.lower() for row in rows for cell in row)


def _alpha_by_hand(matrix):
    k = len(matrix[0])
    item_var = sum(statistics.variance([row[j] for row in matrix]) for j in range(k))
    total_var = statistics.variance([sum(row) for row in matrix])
    return k / (k - 1) * (1 - item_var / total_var)


def test_cronbach_alpha_by_hand():
    # four students, three items: item variances (n - 1) 1/4, 1/3, 1/4 sum to 5/6; totals
    # 3, 2, 1, 0 have variance 5/3; alpha = 3/2 (1 - (5/6) / (5/3)) = 3/4
    assert items.cronbach_alpha([[1, 1, 1], [1, 1, 0], [1, 0, 0], [0, 0, 0]]) == \
        pytest.approx(0.75, abs=1e-12)
    assert items.cronbach_alpha([[1, 2], [1, 2]]) is None           # totals all equal
    assert items.cronbach_alpha([[1, 2, 3]]) is None                # one student
    assert items.cronbach_alpha([[1], [0]]) is None                 # one item
    with pytest.raises(ValueError, match="students x items"):
        items.cronbach_alpha([1, 2, 3])


def test_alpha_per_notebook_and_assignment(klass):
    m = items.score_matrix(items.responses(klass["results"]))
    got = {nb: (k, n, a) for nb, k, n, a in items.alphas(m)}
    for nb, k in (("q5_phong", FILLERS), ("q1_imaging", 5), ("assignment", FILLERS + 5)):
        cols = [j for j, (b, _) in enumerate(m.items) if nb == "assignment" or b == nb]
        matrix = [[float(m.scores[i, j]) for j in cols] for i in range(N)]
        assert got[nb][:2] == (k, N)
        assert got[nb][2] == pytest.approx(_alpha_by_hand(matrix), abs=1e-9)
    assert got["q5_phong"][2] > 0.6     # the fillers measure one ability


def test_distractor_table_in_canonical_options(klass):
    m = items.score_matrix(items.responses(klass["results"]))
    j = m.items.index(("q1_imaging", "test_q1_item1"))
    rest = dict(zip(m.students, m.rest(j)))
    chosen = {r.student: items_html.canonical_choice(r.name, r.answer, r.student)
              for r in klass["results"] if r.name == "q1_item1"}
    table = {o.option: o for o in item_checks.option_table(chosen, "c", "abcd", rest)}
    top30, next50 = round(0.3 * N), round(0.8 * N) - round(0.3 * N)
    assert [table[x].chosen for x in "abcd"] == [N - top30 - next50, next50, top30, 0]
    assert table["c"].key and not any(table[x].key for x in "abd")
    assert "chosen more often than the key" in table["b"].notes
    assert any("non-functioning" in note for note in table["d"].notes)
    assert table["no answer"].chosen == 0
    ids = sorted(chosen)
    for x in "abc":
        picked = [float(x in chosen[s]) for s in ids]
        assert table[x].point_biserial == pytest.approx(
            sps.pearsonr(picked, [rest[s] for s in ids])[0], abs=1e-9)
    assert table["d"].point_biserial is None and table["c"].point_biserial > 0.5
    assert table["a"].point_biserial < 0


def test_a_letter_that_is_no_option_is_no_answer():
    assert items_html.canonical_choice("q1_item1", "z", "s001") is None
    assert items_html.canonical_choice("q1_item1", None, "s001") is None
    assert items_html.canonical_choice("not_a_choice", "a", "s001") is None
    shown = variants.displayed_letters("q1_item5", "ac", 4, "ab12")
    assert items_html.canonical_choice("q1_item5", ", ".join(shown.upper()),
                                       "ab12") == "ac"


# The Item Analysis Worksheet (ten students, ten right/wrong questions, listed from the highest
# total to the lowest), https://studylib.net/doc/25270846/item-anaylsis- : its answers give the
# difficulty p and the discrimination D = (correct in the upper half - correct in the lower
# half) / 5 of every question.
WORKSHEET = {
    "Joe": "1111111111", "Dave": "1111111101", "Sujie": "1101111100", "Darrell": "0111110101",
    "Eliza": "1110111001", "Zoe": "1110110100", "Grace": "0110110101", "Hannah": "0111001010",
    "Ricky": "1110100001", "Anita": "0100010010"}
PUBLISHED_P = [0.6, 1.0, 0.8, 0.5, 0.8, 0.8, 0.5, 0.6, 0.3, 0.6]
PUBLISHED_D = [0.4, 0.0, 0.0, 0.6, 0.4, 0.4, 0.6, 0.4, -0.2, 0.4]


def _worksheet_rows():
    return [items.Response(s, "quiz", f"Q{q + 1}", "choice", float(a[q]), 1.0)
            for s, a in WORKSHEET.items() for q in range(10)]


def test_a_published_worked_example():
    stats = items.item_statistics(_worksheet_rows())
    assert [s.facility for s in stats] == pytest.approx(PUBLISHED_P, abs=1e-12)
    # the worksheet's D: halves (5 students each) by total score, through the same function
    m = items.score_matrix(_worksheet_rows())
    for j in range(10):
        d = items.upper_lower(m.scores[:, j], m.totals, m.students, k=5)
        assert d == pytest.approx(PUBLISHED_D[j], abs=1e-12)
    # Kelley's 27 % groups on the rest score, by hand: ceil(2.7) = 3 students each.
    # Q9 (1 for Joe, Hannah, Anita): rest = total - Q9 = Joe 9, Dave 9, Sujie 7, Darrell 7,
    # Eliza 7, Zoe 6, Grace 6, Ricky 5, Hannah 4, Anita 2. Upper: Dave, Joe (9; Dave's id
    # first), Darrell (7: first id of Darrell, Eliza, Sujie) -> 1/3. Lower: Anita, Hannah,
    # Ricky -> 2/3. U - L = -1/3: the item works the wrong way, flagged.
    q9 = stats[8]
    assert q9.upper_lower == pytest.approx(-1 / 3, abs=1e-12) and q9.flag == "review"
    assert q9.discrimination < 0
    # Q2 (everyone right): facility 1, no discrimination, both groups 1 -> U - L = 0, flagged
    assert (stats[1].discrimination, stats[1].flag) == (None, "review")
    assert stats[1].upper_lower == pytest.approx(0.0, abs=1e-12)
    # Q4 (1 for Joe, Dave, Sujie, Darrell, Hannah): rest Joe 9, Dave 8, Sujie 6, Darrell 6,
    # Eliza 7 ... upper Joe, Dave, Eliza -> 2/3; lower Anita 3, Ricky 5, Hannah 4 -> 1/3
    assert stats[3].upper_lower == pytest.approx(1 / 3, abs=1e-12)


def test_a_missing_notebook_is_no_answer_to_its_items(klass):
    results = list(klass["results"])
    gone = {"s000", "s001", "s002"}
    results = [r if not (r.student in gone and r.notebook == "q1_imaging") else
               _result(r.student, r.notebook, r.grade_id, 0.0, r.max_score, r.kind, r.name,
                       status=Status.MISSING, whole=True) for r in results]
    stats = {s.grade_id: s for s in items.item_statistics(items.responses(results))}
    answered = [r for r in results if not r.whole_notebook]
    oracle = _oracle(answered)
    # the rest score of the fillers still counts the missing notebook as 0 (it is)
    assert stats["test_strong"].n == N - 3 and stats["test_f00"].n == N
    for gid in ("test_strong", "test_q1_item2"):
        n, facility, _, _ = oracle[("q1_imaging", gid)]
        assert stats[gid].facility == pytest.approx(facility, abs=1e-12)
    # a notebook nobody handed in: n = 0, every number empty
    none = [_result(r.student, r.notebook, r.grade_id, 0.0, r.max_score, r.kind, r.name,
                    status=Status.MISSING, whole=True) if r.notebook == "q1_imaging" else r
            for r in results]
    empty = {s.grade_id: s for s in items.item_statistics(items.responses(none))}
    assert (empty["test_strong"].n, empty["test_strong"].facility,
            empty["test_strong"].discrimination, empty["test_strong"].flag) == (0, None, None, "")


def test_a_wholly_blank_notebook_is_no_answer_to_its_items(klass):
    """Every other student of the stronger half hands q1_imaging in untouched (every cell
    ``unanswered``): counted as answers, their zeros against high rest scores would make
    ``test_strong`` look like a bad item; left out, the numbers are those of the students who
    attempted it. A notebook with one attempted cell stays an answer to every item."""
    results = list(klass["results"])
    blank = {s for s, r in klass["rank"].items() if r < N // 2 and r % 2 == 0}
    half = next(s for s, r in klass["rank"].items() if r == 1)   # attempted one cell only

    def untouched(r):
        return _result(r.student, r.notebook, r.grade_id, 0.0, r.max_score, r.kind, r.name,
                       status=Status.UNANSWERED)
    results = [untouched(r) if r.notebook == "q1_imaging" and (
        r.student in blank or (r.student == half and r.grade_id != "test_everyone")) else r
        for r in results]
    stats = {s.grade_id: s for s in items.item_statistics(items.responses(results))}
    oracle = _oracle([r for r in results
                      if not (r.student in blank and r.notebook == "q1_imaging")])
    for gid in ("test_strong", "test_everyone", "test_q1_item1"):
        n, facility, disc, ul = oracle[("q1_imaging", gid)]
        assert stats[gid].n == n == N - len(blank), gid
        assert stats[gid].facility == pytest.approx(facility, abs=1e-12)
        assert (stats[gid].discrimination is None) == (disc is None)
        if disc is not None:
            assert stats[gid].discrimination == pytest.approx(disc, abs=1e-9)
        assert stats[gid].upper_lower == pytest.approx(ul, abs=1e-12)
    assert stats["test_f00"].n == N                      # their other notebook still counts
    assert stats["test_strong"].discrimination > 0.3
    # counted as answers, the blank notebooks would give the item everyone who tried it got
    # right a negative discrimination (zeros against high rest scores)
    assert _oracle(results)[("q1_imaging", "test_everyone")][2] < -0.3
    assert stats["test_everyone"].discrimination is None and stats["test_everyone"].facility == 1


def test_one_student_and_all_equal_scores(tmp_path):
    one = [_result("kim", "q1_imaging", "test_a", 1.0), _result("kim", "q1_imaging", "test_b", 0.0)]
    stats = items.item_statistics(items.responses(one))
    assert [(s.n, s.facility, s.discrimination, s.upper_lower) for s in stats] == \
        [(1, 1.0, None, None), (1, 0.0, None, None)]
    same = [_result(f"s{i}", "q1_imaging", f"test_{j}", 0.5) for i in range(30) for j in "abc"]
    stats = items.item_statistics(items.responses(same))
    assert all(s.discrimination is None and s.facility == 0.5 and s.flag == "" for s in stats)
    assert all(s.upper_lower == pytest.approx(0.0, abs=1e-12) for s in stats)
    m = items.score_matrix(items.responses(same))
    assert all(a is None for *_, a in items.alphas(m))
    text = items.write_items_csv(stats, tmp_path / "items.csv").read_text()
    assert "nan" not in text.lower()
    html = items_html.section_html(one + same)
    assert "nan" not in html.lower()


def test_bad_rows_are_refused():
    ok = items.Response("kim", "q1", "t", "function", 1.0, 1.0)
    with pytest.raises(ValueError, match="two rows"):
        items.item_statistics([ok, ok])
    with pytest.raises(ValueError, match="not within"):
        items.item_statistics([items.Response("kim", "q1", "t", "function", 2.0, 1.0)])
    with pytest.raises(ValueError, match="max_score"):
        items.item_statistics([items.Response("kim", "q1", "t", "function", 0.0, -1.0)])


def test_attempts_to_full_marks_when_recorded(klass):
    rows = items.responses(klass["results"][:FILLERS + 5])
    attempts = {(r.student, r.notebook, r.grade_id): 3 for r in rows}
    attempts[(rows[0].student, rows[0].notebook, rows[0].grade_id)] = None
    stats = items.item_statistics(rows, attempts)
    assert stats[0].attempts is None and stats[0].full_marks == 0
    assert stats[1].attempts == 3.0 and stats[1].full_marks == 1
    assert items.item_statistics(rows)[1].attempts is None      # no grading service: none
    with pytest.raises(ValueError, match="attempts"):
        items.item_statistics(rows, {(rows[0].student, rows[0].notebook, rows[0].grade_id): 0})
    rows = [items.Response(f"s{i}", "q", "t", "function", 1.0, 1.0) for i in range(5)]
    stats = items.item_statistics(rows, {(f"s{i}", "q", "t"): a for i, a in
                                         enumerate([1, 4, 2, None, 7])})
    assert (stats[0].attempts, stats[0].full_marks) == (3.0, 4)    # median of 1, 2, 4, 7
    results = klass["results"][:FILLERS + 5]
    assert "median attempts to full marks" not in items_html.section_html(results)
    shown = items_html.section_html(results, attempts={(r.student, r.notebook, r.grade_id): 2
                                                       for r in results})
    assert "median attempts to full marks</button>" in shown and ">2.0</td>" in shown


@pytest.mark.parametrize("df", [1, 2, 3, 4, 5, 7, 10])
def test_chi2_tail_against_scipy(df):
    for x in (0.0, 0.3, 1.0, 3.84, 7.5, 20.0, 60.0):
        assert item_checks.chi2_sf(x, df) == pytest.approx(sps.chi2.sf(x, df), rel=1e-9,
                                                            abs=1e-15)


@pytest.mark.parametrize("table", [[[3, 1], [1, 3]], [[10, 2], [3, 15]], [[0, 5], [6, 1]],
                                   [[8, 2], [1, 5]], [[12, 0], [0, 12]]])
def test_fisher_against_scipy(table):
    assert item_checks.fisher_exact(table) == pytest.approx(
        sps.fisher_exact(table)[1], rel=1e-9, abs=1e-15)


def test_draw_test_chi_square_against_scipy():
    groups = {"x": [1.0] * 30 + [0.0] * 20, "y": [1.0] * 15 + [0.5] * 25, "z": [1.0] * 25 +
              [0.0] * 25, "tiny": [0.0] * 3}
    t = item_checks.draw_test(groups)
    chi2, p, dof, _ = sps.chi2_contingency([[30, 20], [15, 25], [25, 25]], correction=False)
    assert t.test == "chi-square" and dof == 2
    assert t.statistic == pytest.approx(chi2, rel=1e-9) and t.p == pytest.approx(p, rel=1e-9)
    assert ("tiny", 3, 0.0) in t.groups     # shown, not tested
    # expected counts 5.5 and 4.5 in each row: half the cells under 5, so Fisher's test
    small = item_checks.draw_test({"a": [1.0] * 9 + [0.0], "b": [0.0] * 8 + [1.0] * 2})
    assert small.test == "Fisher"
    assert small.p == pytest.approx(sps.fisher_exact([[9, 1], [2, 8]])[1], rel=1e-9)
    assert item_checks.draw_test({"a": [1.0] * 40}).p is None


def test_an_unfair_draw_is_flagged_and_a_fair_one_is_not():
    """Q4's own-numbers item, failed by most students whose spline is a B-spline with d = b,
    against Q2's, passed at random (one in two, in id order)."""
    results = []
    for i in range(400):
        s = f"u{i:03d}"
        kind = variants.variant("q4_splines", s)
        hard = (kind.kind, kind.rule) == ("b-spline", "d=b")
        passed = (i % 5 == 0) if hard else (i % 5 != 0)
        results.append(_result(s, "q4_splines", "test_q4ci_your_end", float(passed),
                               kind=CellKind.VALUE, name="q4ci_your_end"))
        results.append(_result(s, "q2_nuclear", "test_q2c_your_length", float(i % 2),
                               kind=CellKind.VALUE, name="q2c_your_length"))
    found = {(name, feature): (t, unfair) for _, name, feature, t, unfair
             in items_html.draw_tests(results)}
    t, unfair = found[("q4ci_your_end", "spline and end rule")]
    assert unfair and t.test == "chi-square" and t.p < 1e-10
    t, unfair = found[("q2c_your_length", "hole diameter d (mm)")]
    assert not unfair and t.p > 0.01
    html = items_html.draws_html(results)
    assert html.count("possibly unfair draw</span>") == 1


def test_a_practice_items_draw_is_still_tested():
    """The number items carry 0 points: their draws are judged on right (ok) or wrong."""
    results = []
    for i in range(400):
        s = f"u{i:03d}"
        kind = variants.variant("q4_splines", s)
        hard = (kind.kind, kind.rule) == ("b-spline", "d=b")
        right = (i % 5 == 0) if hard else (i % 5 != 0)
        results.append(_result(s, "q4_splines", "test_q4ci_your_end", 0.0, top=0.0,
                               kind=CellKind.VALUE, name="q4ci_your_end",
                               status=Status.OK if right else Status.FAILED))
    found = {(name, feature): (t, unfair) for _, name, feature, t, unfair
             in items_html.draw_tests(results)}
    t, unfair = found[("q4ci_your_end", "spline and end rule")]
    assert unfair and t.p < 1e-10


def test_a_practice_items_feedback_says_no_marks():
    from autograder.outputs import feedback

    right = _result("ab123", "q5_phong", "test_q5b_your_intensity", 0.0, top=0.0,
                    kind=CellKind.VALUE, name="q5b_your_intensity", status=Status.OK)
    graded = _result("ab123", "q5_phong", "test_phong", 3.0, top=3.0)
    page = feedback.render("ab123", "q5_phong", [right, graded], reveal_hidden=False)
    assert "practice, no marks" in page and "0 / 0" not in page
    assert "automatically graded <b>3 / 3</b>" in page


class _Audit(HTMLParser):
    """What an accessibility check needs of the Items section."""

    def __init__(self):
        super().__init__()
        self.tables = self.captions = 0
        self.th_scopes, self.buttons, self.svgs = [], [], []
        self._button = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self.tables += 1
        elif tag == "caption":
            self.captions += 1
        elif tag == "th":
            self.th_scopes.append(a.get("scope"))
        elif tag == "button":
            self._button = [a.get("type"), ""]
        elif tag == "svg":
            self.svgs.append((a.get("role"), a.get("aria-label", "")))

    def handle_data(self, data):
        if self._button is not None:
            self._button[1] += data

    def handle_endtag(self, tag):
        if tag == "button":
            self.buttons.append(tuple(self._button))
            self._button = None


def test_the_section_is_accessible(klass):
    html = items_html.section_html(klass["results"])
    audit = _Audit()
    audit.feed(html)
    assert audit.tables >= 4 and audit.captions == audit.tables    # items, alpha, 2 choices
    assert all(scope in ("col", "row") for scope in audit.th_scopes)
    assert len(audit.buttons) == 9 and all(t == "button" and text.strip()
                                           for t, text in audit.buttons)
    (role, label), = audit.svgs
    assert role == "img" and "facility" in label and "triangles" in label
    assert "<script src" not in html and "http" not in html.split("<script>")[1]
    # a flagged item says so in words, not only in colour
    assert html.count("⚑ review") == sum(s.flag == "review" for s in items.item_statistics(
        items.responses(klass["results"])))
    assert "✓ key" in html and "aria-sort='none'" in html and "role='status'" in html


def _cell(student, notebook, gid, score, top, marked="yes"):
    return {"student": student, "notebook": notebook, "grade_id": gid, "score": str(score),
            "max_score": str(top), "marked": marked}


def test_export_joins_the_written_answers(tmp_path, sources):
    """``export/items.csv``: the final marks, written answers included, the same columns; an
    unmarked answer is no answer to its item but counts 0 in the rest score."""
    from autograder.cli_export import cell_kinds
    from autograder.outputs import export

    kinds = cell_kinds(sources)
    src = sources[0]
    (name, test_id, _), (written, _) = src.graded[0], src.manual[0]
    from autograder.exercises import REGISTRY
    assert kinds[(src.name, test_id)] == REGISTRY[name].kind
    assert kinds[(src.name, written)] == "manual"
    rows = []
    for i in range(40):
        auto, manual = float(i % 4 == 0), (i % 10) / 2     # 0 .. 4.5 of 5
        cells = [_cell(f"s{i:02d}", src.name, test_id, auto, 1),
                 _cell(f"s{i:02d}", src.name, written, manual, 5, "no" if i == 39 else "yes"),
                 _cell(f"s{i:02d}", "q2_nuclear", "test_x", float(i >= 20), 1)]
        rows.append(export.StudentGrades(f"s{i:02d}", cells=cells))
    path = export.write_items(rows, {**kinds, ("q2_nuclear", "test_x"): "value"}, tmp_path)
    with open(path, newline="") as f:
        got = {r["grade_id"]: r for r in csv.DictReader(f)}
    assert list(next(iter(got.values()))) == list(items.ITEM_COLUMNS)
    w = got[written]
    assert (w["kind"], w["n"], w["max_score"]) == ("manual", "39", "5")
    marks = [(i % 10) / 2 for i in range(39)]
    assert float(w["facility"]) == pytest.approx(sum(marks) / 39 / 5, abs=1e-4)
    rest = [float(i % 4 == 0) + float(i >= 20) for i in range(39)]
    assert float(w["discrimination"]) == pytest.approx(sps.pearsonr(marks, rest)[0], abs=1e-4)
    x = got["test_x"]
    rest_x = [float(i % 4 == 0) + (0.0 if i == 39 else (i % 10) / 2) for i in range(40)]
    assert float(x["discrimination"]) == pytest.approx(
        sps.pearsonr([float(i >= 20) for i in range(40)], rest_x)[0], abs=1e-4)


@pytest.mark.slow
def test_grade_writes_items_csv_and_the_section(tmp_path, sources, monkeypatch):
    """``python -m autograder grade`` on two students' q1: ``items.csv`` beside
    ``grades.csv``, and the report's distractor table in the canonical options."""
    import argparse

    from gradingtools import SECRET, model_version, set_cell, write_nb

    from autograder.grade import cli
    from autograder.isolation import IsolationUnavailable

    def probe():
        raise IsolationUnavailable("not needed for this test")
    monkeypatch.setattr(cli, "probe", probe)
    src = sources[0]
    for student, canonical in (("kim", "c"), ("lee", "a")):
        shown = variants.displayed_letters("q1_item1", canonical, 4, student)
        nb = set_cell(model_version(src), "q1_item1", f'q1_item1 = "{shown}"')
        write_nb(tmp_path / "submitted" / student / "tripos2006" / f"{src.name}.ipynb", nb)
    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    args = parser.parse_args([str(tmp_path / "submitted"), "--out", str(tmp_path / "out"),
                              "--secret-file", str(tmp_path / "secret"), "--no-gradebook",
                              "--quiet", "--jobs", "1", "--timeout", "5", "--source",
                              str(src.path.parent), "--unsafe-no-isolation"])
    assert cli.main(args) == 0
    with open(tmp_path / "out" / "items.csv", newline="") as f:
        got = {(r["notebook"], r["grade_id"]): r for r in csv.DictReader(f)}
    with open(tmp_path / "out" / "grades.csv", newline="") as f:
        written = {(s.name, gid) for s in sources for gid, _ in s.manual}
        auto = {(r["notebook"], r["grade_id"]) for r in csv.DictReader(f)
                if r["student"] == "kim" and (r["notebook"], r["grade_id"]) not in written}
    assert set(got) == auto
    x = got[(src.name, "test_q1_item1")]
    assert (x["kind"], x["n"], x["facility"]) == ("choice", "2", "0.5000")
    assert got[("q6_clipping", "test_clip_polygon")]["n"] == "0"     # not handed in
    report = (tmp_path / "out" / "report.html").read_text()
    table = report.split("q1_item1 (key c; 2 students)")[1].split("</table>")[0]
    rows = {row.split("</th>")[0].split(">")[-1][:3]: row for row in table.split("<tr>")[2:]}
    assert "✓ key" in rows["(c)"] and "<td class='num'>1</td>" in rows["(c)"]
    assert "<td class='num'>1</td>" in rows["(a)"] and "<td class='num'>0</td>" in rows["(b)"]


@pytest.mark.parametrize("builder, title", [("items_html", "Items"),
                                             ("similar_solutions_html", "Similar solutions"),
                                             ("own_numbers_html", "Own numbers")])
def test_a_failing_section_costs_only_itself(klass, monkeypatch, capsys, builder, title):
    """A section that fails on what students typed (a red team's 3,700-digit number item
    stopped the whole report, its "Similar solutions" evidence included) costs that section."""
    from autograder.outputs import report

    def broken(*_a, **_k):
        raise RuntimeError("boom")
    monkeypatch.setattr(report, builder, broken)
    page = report.render(klass["results"][:FILLERS + 5], [])
    assert f"<h2>{title}</h2><p>This section could not be built (RuntimeError)" in page
    assert "Statuses</h2>" in page and "Score distribution" in page
    assert f"section {title!r} failed" in capsys.readouterr().err


@pytest.mark.slow
def test_export_items_from_a_real_gradebook(tmp_path, sources, template_gradebook, monkeypatch):
    """Grade three students' q1 into nbgrader's gradebook, mark a written answer for two of
    them, export: ``export/items.csv`` has the written answer's row on the markers' scores (the
    unmarked one left out of its ``n``) and the automatic rows on the final scores."""
    import argparse
    import shutil

    from gradingtools import SECRET, model_version, write_nb
    from nbgrader.api import Gradebook

    from autograder import cli_export
    from autograder.grade import cli
    from autograder.isolation import IsolationUnavailable

    def probe():
        raise IsolationUnavailable("not needed for this test")
    monkeypatch.setattr(cli, "probe", probe)
    src = sources[0]
    students = ("ann", "ben", "cat")
    for student in students:
        write_nb(tmp_path / "submitted" / student / "tripos2006" / f"{src.name}.ipynb",
                 model_version(src))
    db = tmp_path / "gradebook.db"
    shutil.copy(template_gradebook, db)
    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    assert cli.main(parser.parse_args([
        str(tmp_path / "submitted"), "--out", str(tmp_path / "out"), "--secret-file",
        str(tmp_path / "secret"), "--db-url", f"sqlite:///{db}", "--quiet", "--jobs", "1",
        "--timeout", "5", "--source", str(src.path.parent), "--unsafe-no-isolation"])) == 0
    written, top = src.manual[0]
    with Gradebook(f"sqlite:///{db}", course_id="4f9") as gb:
        for student, mark in (("ann", top), ("ben", 0.5 * top)):
            grade = gb.find_grade(written, src.name, "tripos2006", student)
            grade.manual_score, grade.needs_manual_grade = mark, False
        gb.db.commit()
    parser = argparse.ArgumentParser()
    cli_export.add_arguments(parser)
    assert cli_export.main(parser.parse_args([
        "--out", str(tmp_path / "export"), "--course", str(tmp_path), "--db-url",
        f"sqlite:///{db}", "--allow-unmarked"])) == 0
    with open(tmp_path / "export" / "items.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert tuple(reader.fieldnames) == items.ITEM_COLUMNS
        got = {(r["notebook"], r["grade_id"]): r for r in reader}
    row = got[(src.name, written)]
    assert (row["kind"], row["n"]) == ("manual", "2")
    assert float(row["facility"]) == pytest.approx(0.75, abs=1e-4)
    name, test_id, points = src.graded[0]
    auto = got[(src.name, test_id)]
    assert auto["n"] == "3" and float(auto["facility"]) == pytest.approx(1.0, abs=1e-4)
    assert auto["discrimination"] == "" and auto["flag"] == "review"    # the model earns all
