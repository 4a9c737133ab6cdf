"""The course's static figures as the notebooks draw them (the same calls, the same numbers),
for the headless tests of their text alternatives and colours."""

from __future__ import annotations

import numpy as np


def _ultrasound():
    from course_lib.plots import ultrasound as us

    yield "phantom_and_bscan", lambda: us.phantom_and_bscan(seed=4)
    yield "phantom_and_bscan_tgc", lambda: us.phantom_and_bscan(
        seed=4, tgc_db_per_cm_mhz=0.5, show_displayed=True)
    yield "aline_figure", lambda: us.aline_figure(seed=4)


def _gamma_camera():
    from course_lib import gamma_camera as gc
    from course_lib.plots import gamma_camera as q2

    holes = gc.ring_hole_positions(10.0, 4)
    yield "pmt_cascade", lambda: q2.plot_pmt_cascade(delta=4.0, n_dynodes=10, volts_per_stage=100.0)
    yield "similar_triangles", lambda: q2.plot_similar_triangles(d=1.0, L=200.0, z=200.0)
    yield "hole_rings", lambda: q2.plot_hole_rings(holes, 1.0, 40.0, 1000.0, 50.0, colour_by="open")
    yield "hole_lens", lambda: q2.plot_hole_lens(10.0, 1.0, 40.0, 1000.0)
    yield "model_comparison", lambda: q2.plot_model_comparison(
        holes, 1.0, 40.0, np.linspace(50.0, 3000.0, 60), 50.0)


def _marching_cubes():
    from course_lib.plots import marching_cubes as mc

    yield "cube_numbering", mc.plot_cube_numbering
    yield "base_cases", lambda: mc.plot_base_cases(mark_ambiguous=False)
    yield "ambiguous_face", mc.plot_ambiguous_face
    yield "ambiguous_cases", mc.plot_ambiguous_cases
    yield "hole", mc.plot_hole
    yield "projected_prism", mc.plot_projected_prism


def _splines():
    import matplotlib.pyplot as plt

    from course_lib.plots import splines as sp

    yield "compare_splines", sp.compare_splines
    yield "blending_functions", lambda: sp.plot_blending_functions(plt.subplots()[1])
    yield "end_rules", sp.plot_end_rules


def _shading():
    from course_lib import spectral
    from course_lib.plots import shading as sh

    yield "reflection_vectors", lambda: sh.plot_reflection_vectors(incidence_deg=40.0, view_deg=-15.0)
    yield "sphere_pair", lambda: sh.sphere_pair(
        colour=(0.2, 0.35, 1.0), Ia=1.0, ka=0.2, Ip=1.0, kd=0.6, ks=0.8, n=40,
        L=(1.0, -1.0, 1.0), V=(0.0, -1.0, 0.25), size=64)
    yield "spectra", lambda: sh.plot_spectra(
        spectral.triband_fluorescent,
        lambda wl: spectral.gaussian_band(wl, 610.0, 30.0, 0.9, 0.05), n=9)
    yield "aliasing_swatches", lambda: sh.plot_aliasing_swatches(ns=(9, 16, 81))


def _clipping():
    from course_lib import clip_results
    from course_lib import clipping as clip
    from course_lib.plots import clipping as q6

    A = np.array(clip.EXAM_Q6["A"])
    A_clipped, _ = clip_results.exam_A_clipped()
    comb, y, spans, _ = clip_results.comb()
    yield "view_volume", q6.plot_view_volume
    yield "clipping_2d", lambda: q6.plot_clipping_2d(A, A_clipped, dims=(1, 2), title="side view")
    yield "polygon_spans", lambda: q6.plot_polygon_spans(comb, y, spans)
    yield "raster", lambda: q6.plot_raster([[2.3, 1.2], [17.6, 6.1], [6.2, 14.7]], 20, 16)


def figures():
    """``[(name, draw)]``: ``draw()`` draws one figure (its return value is not used)."""
    out = []
    for group in (_ultrasound, _gamma_camera, _marching_cubes, _splines, _shading, _clipping):
        out.extend(group())
    return out
