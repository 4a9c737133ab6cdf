"""The images of Q5(d)'s spectral spheres, rendered by the course's spectral Phong model.

:func:`course_lib.plots.shading.plot_spectral_spheres` draws these. In the instructors' copy
they are rendered here, on first use, by
:func:`course_lib.spectral_render.render_sphere_spectral` (which computes with the Phong model's
reference, :mod:`course_lib.shading`). The students'
wheel holds neither (docs/students-copy.md): when it is built, this module is replaced by the
text :func:`students_copy` returns, the same :func:`load` over the same pixels written out as a
literal, so the students' figure is the instructors' one, pixel for pixel. Every input is fixed
(:data:`course_lib.spectral.SPECTRAL_SPHERES`), and the pixels are 8-bit sRGB: they answer no
hidden case of a graded function.
"""

from __future__ import annotations

import base64
import functools
import zlib

import numpy as np


def to_pixels(srgb) -> np.ndarray:
    """sRGB values in [0, 1] as the 8-bit pixels matplotlib draws from them (``int(255 x)``)."""
    return (np.asarray(srgb, dtype=float) * 255).astype(np.uint8)


def compute() -> dict:
    """``{"images": (4, size, size, 3) uint8}``: RGB model, each ``ns``, converged, rendered now
    by the reference (the instructors' copy only)."""
    from . import spectral
    from .spectral_render import render_sphere_spectral

    spec = spectral.SPECTRAL_SPHERES

    def dye(wl):
        return spectral.gaussian_band(wl, *spec["dye"])

    args = (spectral.triband_fluorescent, dye, 1.0, spec["ka"], 1.0, spec["kd"], spec["ks"],
            spec["n"], spec["L"], spec["V"], spec["size"])
    linear = [render_sphere_spectral(*args, rgb_model=True)]
    linear += [render_sphere_spectral(*args, n_samples=k) for k in spec["ns"]]
    linear.append(render_sphere_spectral(*args))
    return {"images": np.stack([to_pixels(spectral.linear_srgb_to_srgb(im)) for im in linear])}


@functools.cache
def load() -> dict:
    """``{"images": read-only uint8 array}`` (see the module docstring)."""
    out = compute()
    for a in out.values():
        a.setflags(write=False)
    return out


STUDENTS_COPY = '''"""The images of Q5(d)'s spectral spheres (8-bit sRGB), rendered by the course's
spectral Phong model when this copy of the library was built (it holds the pixels, not the
model)."""

import base64
import functools
import zlib

import numpy as np

#: {name: (dtype, shape, base64 of the zlib-compressed bytes of the array)}
_ARRAYS = %s


@functools.cache
def load() -> dict:
    """``{"images": read-only uint8 array}``: RGB model, 9 and 16 wavelengths, converged."""
    out = {}
    for name, (dtype, shape, text) in _ARRAYS.items():
        raw = zlib.decompress(base64.b64decode(text))
        a = np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
        a.setflags(write=False)
        out[name] = a
    return out
'''


def students_copy() -> str:
    """The text of this module in the students' wheel: :func:`load` over the literal pixels
    (bit for bit those of :func:`compute`), and nothing that renders them."""
    arrays = {name: (a.dtype.str, list(a.shape),
                     base64.b64encode(zlib.compress(a.tobytes(), 9)).decode("ascii"))
              for name, a in sorted(compute().items())}
    return STUDENTS_COPY % repr(arrays)
