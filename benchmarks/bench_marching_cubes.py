"""Marching cubes: course_lib's vectorised marching_cubes vs scikit-image (lorensen, lewiner).

Two volumes at 64³, 128³ and 256³ samples (16³ with ``--smoke``):

- **sphere**: the distance from the centre of the box, iso-level 0.7 of the half-width: one
  smooth closed surface, the easy case;
- **CT phantom**: a CT-like volume in Hounsfield-like units: air around a smooth elliptic body
  (soft tissue), a contrast-enhanced liver and two kidneys, a spine of bone, blurred the way a
  scanner's point spread function blurs them, plus mild Gaussian noise. The iso-level (80.3)
  separates the enhanced organs from soft tissue and lies off every data value; the noise
  makes many tiny extra surfaces in the soft tissue, which is what a real threshold does.

For every volume and method the section reports the median wall time of several runs (the
methods taking turns, run after run, so that a change in the machine's load hits all of them)
and the peak memory of one call measured in a fresh process
(:func:`benchmarks.harness.peak_memory_mib`), as ratios ours / scikit-image. scikit-image's
``marching_cubes`` also returns per-vertex normals and values, which course_lib does not
compute. Both use one vertex per crossed grid edge, so ours and ``lorensen`` must give the same
vertices; their faces differ only in ambiguous cells, which the two tables triangulate
differently (noisy data has many), and ``lewiner`` resolves ambiguous cells with its own
tables. The notes give the counts.
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from .harness import Row, peak_memory_mib

SECTION = "marching cubes"
SIZES = (64, 128, 256)
SMOKE_SIZES = (16,)
#: timed runs per method: more for the small volumes, whose few milliseconds a busy machine blurs
REPEATS = {64: 15, 128: 9, 256: 5}
#: (label, iso-level) of each volume kind
KINDS = {"sphere": 0.7, "ct": 80.3}
METHODS = ("ours", "lorensen", "lewiner")
PEERS = ("lorensen", "lewiner")


# ------------------------------------------------------------------------------------------------
# the volumes


def sphere_volume(n: int) -> np.ndarray:
    """Distance from the centre of the cube ``[-1, 1]^3`` sampled on ``n^3`` points."""
    x = np.linspace(-1.0, 1.0, n)
    return np.sqrt(x[:, None, None] ** 2 + x[None, :, None] ** 2 + x[None, None, :] ** 2)


def ct_phantom(n: int, seed: int = 0) -> np.ndarray:
    """A CT-like phantom in Hounsfield-like units, ``n^3`` samples of ``[-1, 1]^3``.

    Air (-1000) around an elliptic body of soft tissue (40), a liver (130, contrast-enhanced),
    two kidneys (150), a spine (700): blurred by a Gaussian of about 1.5 % of the field of view
    (the scanner's point spread), then Gaussian noise of standard deviation 12.
    """
    from scipy import ndimage

    x = np.linspace(-1.0, 1.0, n)
    X, Y, Z = x[:, None, None], x[None, :, None], x[None, None, :]

    def ellipsoid(c, a):
        return (((X - c[0]) / a[0]) ** 2 + ((Y - c[1]) / a[1]) ** 2
                + ((Z - c[2]) / a[2]) ** 2) <= 1.0

    vol = np.full((n, n, n), -1000.0)
    body = ((X / 0.85) ** 2 + (Y / 0.6) ** 2 <= 1.0) & (np.abs(Z) <= 0.9)
    vol[body] = 40.0
    vol[ellipsoid((-0.3, -0.05, 0.25), (0.35, 0.28, 0.3))] = 130.0      # liver
    vol[ellipsoid((0.35, 0.2, -0.1), (0.12, 0.08, 0.18))] = 150.0       # kidneys
    vol[ellipsoid((-0.35, 0.2, -0.1), (0.12, 0.08, 0.18))] = 150.0
    spine = ((X / 0.1) ** 2 + ((Y - 0.38) / 0.1) ** 2 <= 1.0) & (np.abs(Z) <= 0.85)
    vol[spine] = 700.0
    vol = ndimage.gaussian_filter(vol, sigma=max(0.6, 0.015 * n), mode="nearest")
    rng = np.random.default_rng(seed)
    vol += rng.normal(0.0, 12.0, vol.shape)
    return vol


def make_volume(kind: str, n: int) -> np.ndarray:
    return sphere_volume(n) if kind == "sphere" else ct_phantom(n)


# ------------------------------------------------------------------------------------------------
# the measured calls (module-level so that peak_memory_mib can run them in a fresh process)


def _call(method: str, volume: np.ndarray, iso: float):
    if method == "ours":
        from course_lib.marching_cubes import marching_cubes

        return marching_cubes(volume, iso)
    from skimage.measure import marching_cubes

    return marching_cubes(volume, iso, method=method)


def march_setup(path: str, iso: float, method: str):
    """Load the volume (saved by :func:`run`) and warm the method up on a tiny volume, so that
    neither the input nor the imports count towards the measured peak."""
    volume = np.load(path)
    _call(method, sphere_volume(8), 0.7)
    return volume


def march(volume, path: str, iso: float, method: str):
    out = _call(method, volume, iso)
    return len(out[0]), len(out[1])


# ------------------------------------------------------------------------------------------------


def peak_memory(path: str, iso: float, method: str) -> float:
    """Extra peak RSS (MiB) of one ``march`` call in a fresh process (the harness resets the
    kernel's high-water mark after the input is loaded, so only the call itself counts)."""
    return peak_memory_mib(__name__, "march", path, iso, method)


def _interleaved(volume, iso, repeat: int) -> dict:
    """Median wall time (ms) of each method, the methods taking turns run after run so that
    a change in the machine's load affects all of them alike."""
    samples = {m: [] for m in METHODS}
    for _ in range(repeat):
        for m in METHODS:
            t0 = time.perf_counter()
            _call(m, volume, iso)
            samples[m].append((time.perf_counter() - t0) * 1e3)
    return {m: statistics.median(v) for m, v in samples.items()}


def run(smoke: bool = False) -> list[Row]:
    rows: list[Row] = []
    tmp = Path(tempfile.mkdtemp(prefix="bench-mc-"))
    try:
        for n in SMOKE_SIZES if smoke else SIZES:
            repeat = REPEATS.get(n, 5)
            for kind, iso in KINDS.items():
                volume = make_volume(kind, n)
                path = tmp / f"{kind}{n}.npy"
                np.save(path, volume)
                label = f"{'sphere' if kind == 'sphere' else 'CT phantom'} {n}³"
                sizes = {m: march(volume, str(path), iso, m) for m in METHODS}   # warm-up too
                times = _interleaved(volume, iso, repeat)
                mems = {m: peak_memory(str(path), iso, m) for m in METHODS}
                ours_mesh = f"{sizes['ours'][0]:,} verts, {sizes['ours'][1]:,} faces"
                for peer in PEERS:
                    v, f = sizes[peer]
                    if sizes[peer] == sizes["ours"]:
                        mesh = f"{ours_mesh}, same as {peer}"
                    elif peer == "lewiner":   # its tables resolve ambiguous cells differently
                        mesh = f"{ours_mesh}; lewiner {v:,}/{f:,} (ambiguous cells resolved)"
                    elif v == sizes["ours"][0]:   # same crossed edges, other ambiguous triangles
                        mesh = (f"{ours_mesh}; {peer}: same vertices, {f:,} faces (ambiguous "
                                "cells triangulated differently)")
                    else:
                        mesh = f"{ours_mesh}; {peer} {v:,}/{f:,}: VERTEX COUNTS DIFFER"
                    rows.append(Row(SECTION, label, "time (median)", times["ours"], times[peer],
                                    f"skimage {peer}", unit="ms",
                                    notes=f"{mesh}; median of {repeat}, methods interleaved"))
                for peer in PEERS:
                    rows.append(Row(SECTION, label, "peak memory", mems["ours"], mems[peer],
                                    f"skimage {peer}", unit="MiB",
                                    notes=f"peak RSS growth, fresh process; input "
                                          f"{volume.nbytes / 2**20:.0f} MiB not counted"))
                del volume
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return rows
