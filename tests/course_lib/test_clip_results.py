"""Q6's shipped results (``course_lib.clip_results``): the students' copy holds the numbers the
references give on the notebook's fixed inputs. Checked against independent oracles (the
exam's worked solutions, shapely, mapbox-earcut, the divide done here) and the generated
students' module is checked to give the same arrays bit for bit while naming none of the maths."""

from __future__ import annotations

import mapbox_earcut
import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

from autograder import student_bundle
from course_lib import _clip_results_data, clip_results
from course_lib.widgets.clipping import DEFAULT_POLYGON


@pytest.fixture(scope="module")
def students_load():
    """``load`` of the module text the students' wheel gets, run here."""
    namespace = {"__name__": "students_copy"}
    exec(compile(_clip_results_data.students_copy(), "students_copy", "exec"), namespace)
    return namespace["load"]


def test_students_copy_gives_the_references_arrays_bit_for_bit(students_load):
    ours, theirs = _clip_results_data.compute(), students_load()
    assert sorted(ours) == sorted(theirs)
    for name in ours:
        assert theirs[name].dtype == ours[name].dtype, name
        np.testing.assert_array_equal(theirs[name], ours[name], err_msg=name)
        assert not theirs[name].flags.writeable, name


def test_students_copy_names_none_of_the_maths():
    """The generated text passes the build's own checks and defines nothing but ``load``."""
    rel = next(p for p in student_bundle.library_files()
               if student_bundle.module_name(p) == "course_lib._clip_results_data")
    withheld = student_bundle.left_out()
    gone = {n for names in withheld.values() for n in names}
    text = student_bundle.staged_text(rel, withheld, gone)
    imported = student_bundle.imported_modules(text, "course_lib._clip_results_data")
    assert {m.partition(".")[0] for m in imported} == {"base64", "functools", "numpy"}, imported
    used = student_bundle.names_used(text)
    assert not used & {"compute", "clipping", "_polygons", "clip_polygon", "to_screen",
                       "ear_clip", "fan_triangulate", "screen_area"}


def test_exam_triangles_divided_and_their_areas():
    """Q6(b)(ii), the worked solutions: A is (0, 0, 0.5), (0, 0.5, 0.5), (0, 0.5, 1.5) and B the
    same 0.5 nearer; both edge-on (screen area 0); in camera space A is 8 and B 2.25 (half base
    times height in the (y_c, z_c) plane)."""
    A, B = clip_results.exam_screen()
    np.testing.assert_array_equal(A, [[0, 0, 0.5], [0, 0.5, 0.5], [0, 0.5, 1.5]])
    np.testing.assert_array_equal(B, [[0, 0, 0], [0, 0.5, 0], [0, 0.5, 1]])
    areas = clip_results.exam_areas()
    assert areas["screen"] == (0.0, 0.0)
    assert np.abs(areas["camera"]) == pytest.approx([0.5 * 2 * 8, 0.5 * 1.5 * 3])


def test_exam_A_clipped_is_the_worked_solution():
    """Q6(b)(iii): only the far plane cuts A, leaving (0, 0, 0.5), (0, 0.5, 0.5), (0, 0.5, 1),
    (0, 0.25, 1) after the divide."""
    clipped, counts = clip_results.exam_A_clipped()
    assert counts == (3, 3, 3, 3, 3, 3, 4)
    screen = clipped[:, :3] / clipped[:, 3:]
    expected = np.array([[0, 0, 0.5], [0, 0.5, 0.5], [0, 0.5, 1], [0, 0.25, 1]])
    assert any(np.allclose(np.roll(screen, k, axis=0), expected, atol=1e-12) for k in range(4))


def _check_triangulation(poly, tris, n_expected):
    """Every triangle non-negative in the polygon's orientation, areas summing to the
    polygon's, the union the polygon (shapely)."""
    assert tris.shape == (n_expected, 3) and tris.dtype.kind == "i"
    ref = Polygon(poly)
    pieces = [Polygon(poly[t]) for t in tris]
    assert sum(p.area for p in pieces) == pytest.approx(ref.area, rel=1e-12)
    assert shapely.union_all([p for p in pieces if p.area > 0]).symmetric_difference(
        ref).area < 1e-9


def test_comb_spans_and_ear_clipping():
    """Q6(c): the comb's scanline y = 2 crosses its three teeth; ear clipping gives 10
    triangles covering it, as many as mapbox-earcut's."""
    comb, y, spans, tris = clip_results.comb()
    line = LineString([(-1, y), (6, y)]).intersection(Polygon(comb))
    np.testing.assert_allclose(sorted(g.bounds[0::2] for g in line.geoms), spans, atol=1e-12)
    np.testing.assert_array_equal(spans, [[0, 1], [2, 3], [4, 5]])
    earcut = mapbox_earcut.triangulate_float64(np.array(comb), np.array([len(comb)], dtype=np.uint32))
    _check_triangulation(comb, tris, len(earcut) // 3)


def test_star_ear_clipping_and_areas():
    star, tris, areas, area = clip_results.star()
    assert star.shape == (24, 2) and Polygon(star).is_valid
    _check_triangulation(star, tris, 22)
    tri_areas = [Polygon(star[t]).area for t in tris]
    np.testing.assert_allclose(np.abs(areas), tri_areas, atol=1e-15)
    assert area == pytest.approx(Polygon(star).area, rel=1e-12)
    assert sum(areas) == pytest.approx(area, rel=1e-12)


def _clip_in_screen_space(s):
    """Textbook Sutherland-Hodgman *after* the divide, against the box [-1, 1]^2 x [0, 1]
    (right when every w > 0: a projective map keeps segments and their crossings)."""
    poly = [np.asarray(v, float) for v in s]
    for axis, bound, sign in ((0, -1, 1), (0, 1, -1), (1, -1, 1), (1, 1, -1), (2, 0, 1),
                              (2, 1, -1)):
        out = []
        for i, a in enumerate(poly):
            b = poly[(i + 1) % len(poly)]
            da, db = sign * (a[axis] - bound), sign * (b[axis] - bound)
            if da >= 0:
                out.append(a)
            if da * db < 0:
                out.append(a + da / (da - db) * (b - a))
        poly = out
    return np.array(poly)


def test_default_polygon_clipped_and_fanned():
    """The explorer's default polygon lies in front of the eye (w > 0), so clipping it in
    homogeneous coordinates and dividing is clipping its image after the divide: the same
    vertices, in the same order. The fan is (0, i, i + 1)."""
    P = DEFAULT_POLYGON
    assert np.all(P[:, 3] > 0)
    ref = _clip_in_screen_space(P[:, :3] / P[:, 3:])
    xy, fan = clip_results.default_clipped()
    assert len(ref) == len(xy) == 7
    np.testing.assert_allclose(xy, ref[:, :2], atol=1e-12)
    m = len(xy)
    np.testing.assert_array_equal(fan, [[0, i, i + 1] for i in range(1, m - 1)])
    square, sq_fan = clip_results.square_fan()
    np.testing.assert_array_equal(sq_fan, [[0, 1, 2], [0, 2, 3]])
    assert square.shape == (4, 2)
