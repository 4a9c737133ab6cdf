"""What a student can *call* in their copy of the course (docs/students-copy.md).

The probe (``tests/wheelprobe.py``) tries every callable reachable from a copy of ``course_lib``
on the cases of every graded function and reports those that answer, judged by the exercise's
own comparison rule:

- on a forged copy it flags a private helper, a static method and a lambda in a sub-package
  that compute a reference's answer under other names, and one that answers after waiting
  (each call's budget is CPU time, not the wall clock of a busy machine), and not a readout
  rounded to display precision, a routine that only draws nor one that never returns;
- on the instructors' copy it finds every graded function's reference (its oracle);
- on the students' wheel it finds nothing: no callable, table or explorer object of the wheel
  answers any graded function (docs/students-copy.md).
"""

from __future__ import annotations

import shutil
import sys
import textwrap

import pytest
import wheelprobe
from nbtools import graded_in

from autograder.exercises import REGISTRY

FUNCTIONS = sorted(n for n, ex in REGISTRY.items() if ex.kind == "function")

FORGED = {
    "forged_copy/__init__.py": """
        from course_lib import shading

        def _mirror(L, N):                   # a private helper under another name
            return shading.reflect(L, N)

        mirror_alias = _mirror               # the same object twice is reported once

        class Scene:
            @staticmethod
            def bounce(L, N):
                return _mirror(L, N)

        def shown(L, N):                     # a readout: three decimals
            import numpy as np
            return np.round(shading.reflect(L, N), 3)

        def draw(L, N):                      # draws, answers nothing
            shading.reflect(L, N)

        def slow_mirror(L, N):               # waits 0.4 s of wall clock, using no CPU (a
            import time                      # busy machine): still an answer
            time.sleep(0.4)
            return shading.reflect(L, N)

        def spin(L, N):                      # never returns: stopped by its CPU budget
            while True:
                pass
        """,
    "forged_copy/deep/__init__.py": "",
    "forged_copy/deep/_inner.py": """
        from course_lib import shading
        unit = lambda v: shading.normalize(v)  # noqa: E731
        """,
}


#: a copy laid out as q3's wheel was before its alternative table left it: a triangle table and
#: its counts (``T[i, :N[i]]`` is ``alternative_triangulation(i)``), an explorer whose object
#: keeps an answer and a method that computes one, and a table and an explorer that answer
#: nothing (rounded readouts, another function's rows)
FORGED_TABLES = {
    "forged_tables/__init__.py": """
        import numpy as np
        from course_lib import _mc_tables, shading

        ALT_TRI_TABLE = _mc_tables.ALT_TRI_TABLE.copy()
        ALT_N_TRIANGLES = _mc_tables.ALT_N_TRIANGLES.copy()
        TRI_TABLE = _mc_tables.TRI_TABLE.copy()            # the table's own rows: no answer
        N_TRIANGLES = _mc_tables.N_TRIANGLES.copy()

        class Explorer:
            def __init__(self, L=(0.0, 0.6, 0.8), N=(0.0, 0.0, 1.0)):
                self.shown = np.round(shading.reflect(L, N), 3)
                self.views = {"joined": ALT_TRI_TABLE.copy()}  # a table inside a dict

            def bounce(self, L, N):                           # a method of the object
                return shading.reflect(L, N)

        class Readout:
            def __init__(self):
                self.level = 0.5
                self.rounded = [np.round(shading.reflect((0.0, 0.6, 0.8), (0.0, 0.0, 1.0)), 3)]

        def forged_explorer():
            return Explorer()
        """,
}


def test_probe_flags_a_triangle_table_and_what_an_explorer_keeps(tmp_path):
    """Today's layout of q3's alternative table (``T[i, :N[i]]``) is flagged, and so are a table
    kept in an explorer object's dict and a method of that object; the table's own rows and a
    rounded readout are not."""
    for rel, text in FORGED_TABLES.items():
        (tmp_path / "copy" / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "copy" / rel).write_text(textwrap.dedent(text))
    result = wheelprobe.find_answers(sys.executable, tmp_path / "work", package="forged_tables",
                                     path=(str(tmp_path / "copy"),))
    assert result["broken"] == {} and result["unscreened"] == []
    assert result["objects"] == 3                        # Explorer(), Readout(), forged_explorer()
    answers = result["answers"]
    assert answers.pop("alternative_triangulation") == [
        "forged_tables.ALT_TRI_TABLE[i, :forged_tables.ALT_N_TRIANGLES[i]]",
        "forged_tables.Explorer().views['joined'][i, :forged_tables.ALT_N_TRIANGLES[i]]",
        "forged_tables.forged_explorer().views['joined'][i, :forged_tables.ALT_N_TRIANGLES[i]]",
    ]
    assert answers == {"reflect": ["forged_tables.Explorer().bounce",
                                   "forged_tables.forged_explorer().bounce"]}


def test_probe_flags_helpers_under_other_names_and_not_readouts(tmp_path):
    for rel, text in FORGED.items():
        (tmp_path / "copy" / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "copy" / rel).write_text(textwrap.dedent(text))
    result = wheelprobe.find_answers(sys.executable, tmp_path / "work", package="forged_copy",
                                     path=(str(tmp_path / "copy"),))
    assert result["broken"] == {}
    assert result["answers"] == {
        "reflect": ["forged_copy.Scene.bounce", "forged_copy._mirror",
                    "forged_copy.slow_mirror"],
        "normalize": ["forged_copy.deep._inner.unit"],
    }


@pytest.mark.slow
def test_probe_finds_every_reference_in_the_instructors_copy(tmp_path):
    result = wheelprobe.find_answers(sys.executable, tmp_path)
    assert result["broken"] == {}, result["broken"]
    for name in FUNCTIONS:
        ref = REGISTRY[name].reference
        assert f"{ref.__module__}.{ref.__qualname__}" in result["answers"].get(name, []), name


@pytest.fixture(scope="module")
def wheel_answers(tmp_path_factory):
    """The probe's result in the students' environment (their wheel alone)."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import studentenv

    result = wheelprobe.find_answers(studentenv.python(), tmp_path_factory.mktemp("probe"),
                                     env=studentenv.env_vars())
    assert result["broken"] == {}, result["broken"]
    assert result["unscreened"] == [], result["unscreened"]
    return result


@pytest.mark.slow
@pytest.mark.timeout(1800)      # the wheel's build (cached) and the probe, objects and tables
@pytest.mark.xdist_group("student_env")
def test_students_wheel_answers_no_graded_function(wheel_answers):
    """No callable, table or explorer object of the wheel answers any graded function, and the
    wheel leaves out every graded function's reference (the probe's own oracle finds them all
    in the instructors' copy)."""
    from autograder import student_bundle

    withheld = {n for names in student_bundle.withheld_functions().values() for n in names}
    assert len(withheld) == len(FUNCTIONS), sorted(withheld)
    assert wheel_answers["answers"] == {}, wheelprobe.summary(wheel_answers)


Q3_IN_STUDENT_ENV = r'''
import pickle, sys
import numpy as np
from course_lib import marching_cubes, mc_results
from course_lib._mc_results_data import load
from course_lib.plots.marching_cubes import case_values, drawn_triangles
from course_lib.widgets.marching_cubes import CaseExplorer
try:
    import course_lib.mesh
    mesh = "importable"
except ImportError:
    mesh = "absent"
from course_lib import _mc_tables
gone = [n for n in GRADED_IN_MODULE + ("marching_cubes_loop",
                    "cell_triangles", "hole_demo", "probe_triangulation", "cube_symmetries",
                    "_orbit_labels", "ALT_TRI_TABLE") if hasattr(marching_cubes, n)]
gone += [n for n in ("ALT_TRI_TABLE", "ALT_N_TRIANGLES", "case_triangles") if hasattr(_mc_tables, n)]
drawn = {(i, iso, alt): drawn_triangles(i, iso, alt) for i in range(256) for iso in (0.13, 0.5, 0.98)
         for alt in (False, True) if not alt or i in (5, 67, 26, 195, 135, 165)}
labels = [marching_cubes.case_of(i) for i in range(256)]
ex = CaseExplorer(index=165, iso=0.31)
ex.alternative.value = True
alt5 = marching_cubes.TRI_TABLE[250, :marching_cubes.N_TRIANGLES[250], ::-1]   # joined
with open(sys.argv[1], "wb") as f:
    pickle.dump({"data": dict(load()), "drawn": drawn, "explorer": ex.triangles, "mesh": mesh,
                 "labels": labels,
                 "gone": gone, "closes": [marching_cubes.closes_up(5, alt5),
                                          marching_cubes.closes_up(5, alt5[:, ::-1])],
                 "convergence": mc_results.sphere_convergence()}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("marching_cubes")))


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q3_figures_are_the_instructors(tmp_path):
    """In the students' environment: q3's shipped results are the references' bit for bit, the
    case figures and explorer draw the references' triangles (to display precision, 1e-4; the
    alternative for the six shown representatives), ``case_of`` labels every case as the
    orbits do, ``closes_up`` works, and the march, the symmetry group, the alternative table,
    the graded functions and ``course_lib.mesh`` are absent."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import pickle

    import numpy as np
    import studentenv

    from course_lib import _mc_case_data, _mc_results_data
    from course_lib import marching_cubes as mc
    from course_lib.plots.marching_cubes import case_values

    out = tmp_path / "q3.pkl"
    proc = studentenv.run(Q3_IN_STUDENT_ENV, str(out), cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = pickle.loads(out.read_bytes())
    assert got["mesh"] == "absent" and got["gone"] == []
    assert got["labels"] == [int(label) for label in _mc_case_data.compute()["case_of"]]
    assert got["closes"] == [True, False]
    ref = _mc_results_data.compute()
    assert sorted(got["data"]) == sorted(ref)
    for name, array in ref.items():
        np.testing.assert_array_equal(got["data"][name], array, err_msg=name)
    assert [r["triangles"] for r in got["convergence"]] == ref["convergence"][:, 1].astype(int).tolist()
    for (index, iso, alt), tris in got["drawn"].items():
        want = mc.cell_triangles(case_values(index), iso, alternative=alt)
        np.testing.assert_allclose(tris, want, rtol=0, atol=0.5e-4, err_msg=str((index, iso, alt)))
    np.testing.assert_allclose(got["explorer"], mc.cell_triangles(case_values(165), 0.31, True),
                               rtol=0, atol=0.5e-4)


Q6_IN_STUDENT_ENV = r'''
import importlib.util, pickle, sys
import numpy as np
from course_lib import clipping
from course_lib._clip_results_data import load
from course_lib.widgets.clipping import ClippingExplorer, clip_display
polygons = pickle.load(open(sys.argv[2], "rb"))
shown = [clip_display(P) for P in polygons]
ex = ClippingExplorer(polygons[0], dims=(1, 2))
ex.step.value = 6
gone = [n for n in GRADED_IN_MODULE + (
                    "clip_steps", "clip_polygons", "shoelace_area",
                    "_clip_rows") if hasattr(clipping, n)]
with open(sys.argv[1], "wb") as f:
    pickle.dump({"data": dict(load()), "shown": shown, "status": ex.status.get_text(),
                 "drawn": ex.art2d["clipped"].get_xy(), "gone": gone,
                 "polygons": importlib.util.find_spec("course_lib._polygons") is not None}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("clipping")))


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q6_figures_are_the_instructors(tmp_path):
    """In the students' environment: q6's shipped results are the references' bit for bit, the
    explorer's display routine (C-level copies of the clipping references) shows what the
    instructors' shows, number for number and word for word, and the graded functions, the
    clipping machinery and ``course_lib._polygons`` are absent."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import pickle

    import numpy as np
    import studentenv

    from course_lib import _clip_results_data, clipping
    from course_lib.widgets.clipping import clip_display

    rng = np.random.default_rng(6)
    polygons = [clipping.EXAM_Q6["A"], np.array([[0.0, 0, 0, 0], [1, 0, 0.5, 1], [0, 1, 0.5, 1]])]
    polygons += [np.c_[rng.uniform(-3, 3, (n, 3)), rng.uniform(-1, 3, (n, 1))] for n in (3, 5, 8)]
    (tmp_path / "in.pkl").write_bytes(pickle.dumps(polygons))
    out = tmp_path / "q6.pkl"
    proc = studentenv.run(Q6_IN_STUDENT_ENV, str(out), str(tmp_path / "in.pkl"), cwd=tmp_path,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = pickle.loads(out.read_bytes())
    assert got["gone"] == [] and got["polygons"] is False
    ref = _clip_results_data.compute()
    assert sorted(got["data"]) == sorted(ref)
    for name, array in ref.items():
        np.testing.assert_array_equal(got["data"][name], array, err_msg=name)
    for P, theirs in zip(polygons, got["shown"]):
        ours = clip_display(P)
        assert theirs["tables"] == ours["tables"] and theirs["inside"] == ours["inside"]
        assert (theirs["error"] is None) == (ours["error"] is None)
        for key in ("steps", "screen"):
            for a, b in zip(theirs[key], ours[key]):
                np.testing.assert_array_equal(a, b)
    assert "after plane 6 of 6, far" in got["status"] and "4 vertices" in got["status"]
    drawn, want = got["drawn"][:-1], np.array([[0, 0.5], [0.5, 0.5], [0.5, 1], [0.25, 1]])
    assert any(np.allclose(np.roll(drawn, k, axis=0), want, atol=1e-12) for k in range(4)), drawn


Q5_IN_STUDENT_ENV = r'''
import pickle, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
from course_lib import shading, spectral
from course_lib._spectral_spheres_data import load
from course_lib.plots.shading import drawn_vectors
from course_lib.widgets.shading import PhongExplorer, angles
try:
    import course_lib.spectral_render
    spectral_render = "importable"
except ImportError:
    spectral_render = "absent"
gone = [n for n in GRADED_IN_MODULE + ("phong_terms",
                    "render_sphere", "highlight_pixel", "highlight_normal", "view_basis",
                    "sphere_normals", "_shade", "_unit", "_normalised")
        if hasattr(shading, n)]
gone += [n for n in ("spectral_phong", "render_sphere_spectral") if hasattr(spectral, n)]
ex = PhongExplorer(size=64)
views = []
for settings in SETTINGS:
    ex.set(**settings)
    views.append({"images": [np.array(im.get_array()) for im in ex.art["images"]],
                  "peaks": list(ex.peaks), "probe": dict(ex.probe_values),
                  "H": ex.halfway_shown, "readout": ex.readout.value,
                  "crosses": [(a.get_xdata(), a.get_ydata()) for a in ex.art["analytic"]]})
ex.load_exam()
with open(sys.argv[1], "wb") as f:
    pickle.dump({"gone": gone, "spectral_render": spectral_render, "views": views,
                 "exam": ex.readout.value, "pixels": load()["images"],
                 "vectors": drawn_vectors(40.0, -15.0), "angles": angles([1.0, -1.0, 1.0])}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("shading")))

Q5_SETTINGS = [
    {"colour": "#3366ff", "ka": 0.2, "kd": 0.6, "ks": 0.8, "n": 20.0},
    {"light_azimuth": 60.0, "light_elevation": 40.0, "view_azimuth": 100.0, "view_elevation": 20.0},
    {"n": 500.0, "colour": "#ff0000", "kd": 0.0},
    {"view_azimuth": 0.0, "view_elevation": 0.0, "light_azimuth": 180.0, "light_elevation": 0.0},
]


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q5_figures_are_the_instructors(tmp_path):
    """In the students' environment: the Phong explorer draws the instructors' spheres byte for
    byte and shows the same readouts, the spectral spheres are the references' pixels, and
    neither the five graded functions, their helpers nor course_lib.spectral_render are there."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import pickle

    import matplotlib
    import numpy as np
    import studentenv

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from course_lib import _spectral_spheres_data
    from course_lib.plots.shading import drawn_vectors
    from course_lib.widgets.shading import PhongExplorer, angles

    out = tmp_path / "q5.pkl"
    script = Q5_IN_STUDENT_ENV.replace("SETTINGS", repr(Q5_SETTINGS))
    proc = studentenv.run(script, str(out), cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = pickle.loads(out.read_bytes())
    assert got["gone"] == [] and got["spectral_render"] == "absent"
    np.testing.assert_array_equal(got["pixels"], _spectral_spheres_data.compute()["images"])
    ex = PhongExplorer(size=64)
    try:
        for settings, view in zip(Q5_SETTINGS, got["views"]):
            ex.set(**settings)
            for k in (0, 1):
                np.testing.assert_array_equal(view["images"][k], ex.art["images"][k].get_array())
                np.testing.assert_array_equal(view["crosses"][k][0], ex.art["analytic"][k].get_xdata())
            assert view["peaks"] == ex.peaks and view["readout"] == ex.readout.value
            for key, values in ex.probe_values.items():
                np.testing.assert_array_equal(view["probe"][key], values)
        ex.load_exam()
        assert got["exam"] == ex.readout.value and "0.0931" in got["exam"]
    finally:
        plt.close(ex.fig)
    want = drawn_vectors(40.0, -15.0)
    for name, v in want.items():
        np.testing.assert_array_equal(got["vectors"][name], v)
    assert got["angles"] == angles([1.0, -1.0, 1.0])


Q2_SETTINGS = [(1.0, 40.0, 1000.0, 10.0, 4), (0.7, 33.0, 770.0, 7.5, 5), (2.3, 120.0, 260.0, 6.0, 8),
               (0.4, 5.0, 3000.0, 2.0, 0), (3.1, 17.0, 90.0, 19.5, 2)]

Q2_IN_STUDENT_ENV = r'''
import pickle, sys
import numpy as np
from course_lib import collimator_results, gamma_camera
from course_lib._collimator_results_data import load
from course_lib.plots import gamma_camera as pg
from course_lib.widgets.gamma_camera import CollimatorExplorer, collimator_model
settings = SETTINGS
gone = [n for n in GRADED_IN_MODULE + ("pmt_cascade", "exam_cutoff_radius",
                    "exact_cutoff_radius", "transmission_profile", "compare_models")
        if hasattr(gamma_camera, n)]
holes = collimator_results.exam_holes()
ex = CollimatorExplorer()
ex.set(d=0.7, L=33.0, z=770.0, pitch=7.5, n_rings=5)
with open(sys.argv[1], "wb") as f:
    pickle.dump({"gone": gone, "data": dict(load()),
                 "models": [collimator_model(*s) for s in settings],
                 "labels": [pg.cascade_labels(4.0, 10), pg.cascade_labels(2.7, 7)],
                 "resolution": [pg.shown_resolution(*s[:3]) for s in settings],
                 "verdicts": pg.hole_verdicts(holes, 1.0, 40.0, 1000.0),
                 "profile": pg.profile_curves(1.0, 40.0, 1000.0),
                 "curves": pg.model_curves(holes, 1.0, 40.0, np.linspace(50.0, 3000.0, 24), 50.0),
                 "readout": ex.readout.value, "results": ex.results}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("gamma_camera")))


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q2_figures_are_the_instructors(tmp_path):
    """In the students' environment: q2's routines give what they give in the instructors'
    copy (the references inlined as C functions), the shipped results are the references' bit
    for bit, the explorer reads out the same text, and the graded functions and their helpers
    are absent from ``course_lib.gamma_camera``."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import pickle

    import numpy as np
    import studentenv

    from course_lib import _collimator_results_data
    from course_lib.plots import gamma_camera as pg
    from course_lib.widgets import gamma_camera as wg

    out = tmp_path / "q2.pkl"
    code = Q2_IN_STUDENT_ENV.replace("SETTINGS", repr(Q2_SETTINGS))
    proc = studentenv.run(code, str(out), cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = pickle.loads(out.read_bytes())
    assert got["gone"] == []
    ref = _collimator_results_data.load()
    assert sorted(got["data"]) == sorted(ref)
    for name, array in ref.items():
        np.testing.assert_array_equal(got["data"][name], array, err_msg=name)
    for setting, model in zip(Q2_SETTINGS, got["models"]):
        want = wg.collimator_model(*setting)
        assert model["results"] == want["results"], setting
        for key in ("holes", "exam_open", "exact_share"):
            np.testing.assert_array_equal(model[key], want[key], err_msg=f"{setting} {key}")
    assert got["labels"] == [pg.cascade_labels(4.0, 10), pg.cascade_labels(2.7, 7)]
    assert got["resolution"] == [pg.shown_resolution(*s[:3]) for s in Q2_SETTINGS]
    holes = ref["exam_holes"]
    verdicts = pg.hole_verdicts(holes, 1.0, 40.0, 1000.0)
    for key in ("exam", "exact"):
        np.testing.assert_array_equal(got["verdicts"][key], verdicts[key], err_msg=key)
    assert got["verdicts"]["cutoffs"] == verdicts["cutoffs"] == (25.0, 25.5)
    profile = pg.profile_curves(1.0, 40.0, 1000.0)
    for key in ("r", "exact", "exam"):
        np.testing.assert_array_equal(got["profile"][key], profile[key], err_msg=key)
    np.testing.assert_array_equal(
        got["curves"], pg.model_curves(holes, 1.0, 40.0, np.linspace(50.0, 3000.0, 24), 50.0))
    assert got["results"] == wg.collimator_model(0.7, 33.0, 770.0, 7.5, 5)["results"]
    assert "open fraction" in got["readout"] and got["results"]["n_holes"] == 121
    import matplotlib.pyplot as plt

    ours = wg.CollimatorExplorer(d=0.7, L=33.0, z=770.0, pitch=7.5, n_rings=5)
    try:
        assert got["readout"] == ours.readout.value
    finally:
        plt.close(ours.fig)


Q4_IN_STUDENT_ENV = r'''
import pickle, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
from course_lib import spline_weights, splines
from course_lib.plots import splines as plots
from course_lib.widgets.splines import SplineEndExplorer, formulas_html
gone = [n for n in GRADED_IN_MODULE + ("basis_matrix", "end_weights", "extend_with_phantoms",
                                       "segment_geometries", "evaluate_curve")
        if hasattr(splines, n)]
arrays = [(m.__name__, k) for m in (splines, plots) for k, v in vars(m).items()
          if isinstance(v, np.ndarray) and v.shape == (4, 4)]
P = np.array(sys.argv[2:], dtype=float).reshape(-1, 2)
scenes = {(kind, rule): plots.spline_scene(P, kind, rule, phantoms=P[:2], n_per_segment=8)
          for kind in splines.KINDS for rule in (None, "d=b", "d=2c-b", "d=c", "free")}
lines = [ln.get_ydata() for ln in plots.plot_blending_functions()]
ex = SplineEndExplorer(P, kind="b-spline", rule="d=c")
ex.rule.value = "free"
with open(sys.argv[1], "wb") as f:
    pickle.dump({"gone": gone, "arrays": arrays, "scenes": scenes, "lines": lines,
                 "tables": {c: spline_weights.end_weights_text(*c) for c in
                            [(k, r) for k in spline_weights.KINDS for r in spline_weights.RULES]},
                 "formulas": formulas_html("catmull-rom", "d=b", ex.scene["end"]),
                 "explorer": (ex.phantoms, ex.scene["end"])}, f)
'''.replace(
    "GRADED_IN_MODULE", repr(graded_in("splines")))


@pytest.mark.slow
@pytest.mark.xdist_group("student_env")
def test_students_q4_figures_are_the_instructors(tmp_path):
    """In the students' environment: q4's curves, ends, blending functions and weight tables are
    the instructors' ones (figures at display precision, 1e-4 of the points' span), while the
    graded functions, their helpers and any 4 x 4 basis matrix are absent from the modules."""
    if shutil.which("gcc") is None:
        pytest.skip("no C compiler (make wheel-deps)")
    import pickle

    import matplotlib
    import numpy as np
    import studentenv

    matplotlib.use("Agg")
    from course_lib import spline_weights
    from course_lib import splines as S
    from course_lib.plots import splines as plots
    from course_lib.widgets.splines import formulas_html

    P = np.random.default_rng(4).normal(scale=3.0, size=(6, 2)).round(6)
    out = tmp_path / "q4.pkl"
    proc = studentenv.run(Q4_IN_STUDENT_ENV, str(out), *map(repr, P.ravel().tolist()),
                          cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = pickle.loads(out.read_bytes())
    assert got["gone"] == [] and got["arrays"] == []
    for (kind, rule), scene in got["scenes"].items():
        quantum = 10.0 ** -plots.display_decimals(scene["extended"])
        ext = (np.vstack([P[0], P, P[1]]) if rule == "free" else
               P if rule is None else S.extend_with_phantoms(P, rule))
        M = S.basis_matrix(kind)
        t = np.linspace(0.0, 1.0, 9)
        want = {"extended": ext,
                "segments": [S.spline_eval(M, G, t) for G in S.segment_geometries(ext)],
                "end": S.end_derivatives(M, *ext[-4:])}
        for name, ref in want.items():
            np.testing.assert_allclose(np.asarray(scene[name]), np.asarray(ref), rtol=0,
                                       atol=0.5 * quantum * (1 + 1e-9), err_msg=str((kind, rule, name)))
    t = np.linspace(0.0, 1.0, 101)
    ref = [w for kind in ("b-spline", "catmull-rom")
           for w in (S.parameter_row(t) @ S.basis_matrix(kind)).T]
    np.testing.assert_allclose(got["lines"], ref, rtol=0, atol=0.5e-4 + 1e-12)
    assert got["tables"] == {c: spline_weights.end_weights_text(*c) for c in got["tables"]}
    assert got["formulas"].startswith(formulas_html("catmull-rom", "d=b"))
    phantoms, end = got["explorer"]
    quantum = 10.0 ** -plots.display_decimals(np.vstack([phantoms, P]))
    np.testing.assert_allclose(phantoms, [P[0], P[-1]], rtol=0, atol=0.5 * quantum)
    np.testing.assert_allclose(end[0], (P[-2] + 5 * P[-1]) / 6, rtol=0, atol=0.5 * quantum)
