"""Q6's fixed examples, worked by the course's references: the exam's triangles, a comb, a star.

The figures and cells of the Q6 notebook that show the course's answers on fixed inputs read
them here: triangles A and B of Q6(b) divided by ``w`` with their areas, A clipped (and its
vertex count after each plane), the comb whose scanline has three spans and its ear
clipping, a random star's ear clipping, the explorer's default polygon clipped and fanned
(Q6(c)), and a square fanned into two triangles.

The students' copy of the library holds these results, computed when it was built, and not the
functions that compute them (writing those is the question). Every function here returns the
same arrays in both copies; none takes an input of yours.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["COMB", "COMB_Y", "SQUARE", "comb", "default_clipped", "exam_A_clipped",
           "exam_areas", "exam_screen", "square_fan", "star", "star_polygon"]

#: a comb with two notches: three spans on the scanline ``y = COMB_Y`` (Q6(c))
COMB = np.array([[0, 0], [5, 0], [5, 3], [4, 3], [4, 1], [3, 1], [3, 3], [2, 3], [2, 1],
                 [1, 1], [1, 3], [0, 3]], dtype=float)
COMB.setflags(write=False)
COMB_Y = 2.0
#: a square in pixel coordinates, split along a diagonal to show the top-left fill rule
SQUARE = np.array([[2.5, 2.5], [10.5, 2.5], [10.5, 10.5], [2.5, 10.5]])
SQUARE.setflags(write=False)


@functools.cache
def star_polygon() -> np.ndarray:
    """A simple, non-convex star: 24 vertices at sorted random angles (seed 4), radii in
    ``[0.3, 1)``."""
    rng = np.random.default_rng(4)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 24))
    radii = rng.uniform(0.3, 1.0, 24)
    out = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
    out.setflags(write=False)
    return out


def _data() -> dict:
    from ._clip_results_data import load

    return load()


def exam_screen():
    """``(A, B)``: the exam's triangles of Q6(b) divided by ``w``, ``(3, 3)`` each (Q6(b)(ii))."""
    d = _data()
    return d["exam_screen_A"], d["exam_screen_B"]


def exam_areas() -> dict:
    """``{"screen": (A, B), "camera": (A, B)}``: the signed screen areas of the two triangles
    (both 0: they are seen edge-on) and their areas in camera space, in the ``(y_c, z_c)`` plane
    where they lie (Q6(b)(ii))."""
    d = _data()
    return {kind: tuple(float(v) for v in d[f"exam_{kind}_areas"]) for kind in ("screen", "camera")}


def exam_A_clipped():
    """``(clipped, counts)``: triangle A clipped against the view volume (homogeneous, ``(4, 4)``)
    and its number of vertices before clipping and after each of the six planes (Q6(b)(iii))."""
    d = _data()
    return d["A_clipped"], tuple(int(n) for n in d["A_step_counts"])


def comb():
    """``(polygon, y, spans, triangles)``: :data:`COMB`, its scanline :data:`COMB_Y`, the spans
    there (rows ``(x_left, x_right)``) and its ear clipping (rows of vertex numbers) (Q6(c))."""
    d = _data()
    return COMB, COMB_Y, d["comb_spans"], d["comb_triangles"]


def star():
    """``(polygon, triangles, areas, area)``: :func:`star_polygon`, its ear clipping, each
    triangle's signed area and the polygon's (Q6(c), going further)."""
    d = _data()
    return star_polygon(), d["star_triangles"], d["star_triangle_areas"], float(d["star_area"])


def default_clipped():
    """``(xy, triangles)``: the clipping explorer's default polygon clipped, divided by ``w``
    (``(x_s, y_s)`` per vertex), and its fan of triangles (Q6(c))."""
    d = _data()
    return d["default_clipped_xy"], d["default_fan"]


def square_fan():
    """``(square, triangles)``: :data:`SQUARE` and its fan, two triangles on a diagonal."""
    return SQUARE, _data()["square_fan"]
