"""Q3's shipped results (``course_lib.mc_results``): the students' copy holds the numbers the
references give on the notebook's fixed inputs. Checked here against the references, against
independent formulas (the divergence theorem by tetrahedra, the analytic sphere, Euler's
formula) and against the readable one-cell-at-a-time march, and the generated students' module
is checked to give the same arrays bit for bit while naming none of the maths."""

from __future__ import annotations

import numpy as np
import pytest

from autograder import student_bundle
from course_lib import _mc_results_data, mc_results
from course_lib import marching_cubes as mc
from course_lib import mesh


def _tetra_volume(verts, faces) -> float:
    """The divergence theorem by tetrahedra from the origin: sum det(a, b, c) / 6 (not eq. (4))."""
    tri = np.asarray(verts)[np.asarray(faces)]
    return float(np.linalg.det(tri).sum() / 6.0)


def _euler(faces) -> int:
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return len(np.unique(faces)) - len(np.unique(edges, axis=0)) + len(faces)


@pytest.fixture(scope="module")
def students_load():
    """``load`` of the module text the students' wheel gets, run here."""
    text = _mc_results_data.students_copy()
    namespace = {"__name__": "students_copy"}
    exec(compile(text, "students_copy", "exec"), namespace)
    return namespace["load"]


def test_students_copy_gives_the_references_arrays_bit_for_bit(students_load):
    ours, theirs = _mc_results_data.compute(), students_load()
    assert sorted(ours) == sorted(theirs)
    for name in ours:
        assert theirs[name].dtype == ours[name].dtype, name
        np.testing.assert_array_equal(theirs[name], ours[name], err_msg=name)
        assert not theirs[name].flags.writeable, name


def test_students_copy_names_none_of_the_maths(tmp_path):
    """The generated text passes the build's own checks and defines nothing but ``load``."""
    rel = next(p for p in student_bundle.library_files()
               if student_bundle.module_name(p) == "course_lib._mc_results_data")
    withheld = student_bundle.left_out()
    gone = {n for names in withheld.values() for n in names}
    text = student_bundle.staged_text(rel, withheld, gone)
    imported = student_bundle.imported_modules(text, "course_lib._mc_results_data")
    assert {m.partition(".")[0] for m in imported} == {"base64", "functools", "numpy"}, imported
    used = student_bundle.names_used(text)
    assert not used & {"compute", "marching_cubes", "mesh", "mesh_volume", "hole_demo"}


def test_sphere_figure_is_the_reference_mesh_and_its_volume():
    verts, faces, volume = mc_results.sphere_mesh()
    n, r = mc_results.SPHERE_FIGURE["n"], mc_results.SPHERE_FIGURE["radius"]
    c = (n - 1) / 2 + 0.1
    field = mc.sphere_field((n, n, n), (c, c, c))
    # the readable march (a different implementation) makes the same triangles
    loop_v, loop_f = mc.marching_cubes_loop(field, r ** 2)
    np.testing.assert_array_equal(mesh.canonical_triangles(verts, faces),
                                  mesh.canonical_triangles(loop_v, loop_f))
    assert mesh.is_closed_consistent(faces) and _euler(faces) == 2
    assert volume == pytest.approx(_tetra_volume(verts, faces), rel=1e-12)
    # inscribed in the sphere, within a few per cent of 4/3 pi r^3
    assert 0.9 * mc.sphere_volume(r) < volume < mc.sphere_volume(r)


def test_convergence_table_is_second_order_and_closed():
    spec = mc_results.SPHERE_CONVERGENCE
    rows = mc_results.sphere_convergence()
    assert [row["h"] for row in rows] == list(spec["h"])
    exact = mc.sphere_volume(spec["radius"])
    errors = []
    for row in rows:
        assert row["closed"]
        # the same volume along every direction: a closed mesh
        np.testing.assert_allclose(row["volumes"], row["volumes"][0], rtol=1e-9, atol=0)
        errors.append(exact - row["volumes"][0])
    assert all(e > 0 for e in errors)               # inscribed: from below
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.0) & (ratios < 5.0)), ratios   # error ~ h^2
    # triangle counts grow as 1 / h^2 (the surface's area over a cell face)
    counts = np.array([row["triangles"] for row in rows], float)
    np.testing.assert_allclose(counts[1:] / counts[:-1], 4.0, rtol=0.1, atol=0)
    # the coarsest row, recomputed here by the reference
    n_samples = int(round(spec["box"] / spec["h"][0])) + 1
    v, f = mc.marching_cubes(mc.sphere_field((n_samples,) * 3, (spec["centre"],) * 3),
                             spec["radius"] ** 2)
    assert rows[0]["triangles"] == len(f)
    assert rows[0]["volumes"][0] == pytest.approx(_tetra_volume(v, f), rel=1e-12)


def test_hole_is_open_with_a_four_edge_outline_and_no_single_volume():
    verts, faces, hole = mc_results.hole_mesh()
    _, ref_v, ref_f = mc.hole_demo()
    np.testing.assert_array_equal(verts, ref_v)
    np.testing.assert_array_equal(faces, ref_f)
    assert hole.shape == (4, 2)
    # the outline is a closed loop in the shared face x = 2
    np.testing.assert_allclose(verts[hole][:, :, 0], 2.0, atol=1e-12)
    assert sorted(np.bincount(hole.ravel()).tolist())[-4:] == [2, 2, 2, 2]
    closed, volumes = mc_results.hole_volumes()
    assert not closed
    assert len({round(v, 6) for v in volumes}) == 3       # a different "volume" per direction
    for v, n in zip(volumes, mc_results.DIRECTIONS):
        assert v == pytest.approx(mesh.mesh_volume(ref_v, ref_f, n), abs=1e-12)


def test_saddle_mesh_is_two_separate_closed_pieces():
    verts, faces = mc_results.saddle_mesh()
    v, f = mc.marching_cubes(mc_results.saddle_volume(), 0.0)
    np.testing.assert_array_equal(verts, v)
    np.testing.assert_array_equal(faces, f)
    assert mesh.is_closed_consistent(faces) and _euler(faces) == 4   # two spheres


def test_results_are_read_only():
    verts, _, _ = mc_results.sphere_mesh()
    with pytest.raises(ValueError):
        verts[0, 0] = 1.0
