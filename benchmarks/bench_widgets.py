"""Widgets: the compute behind one update of each explorer, and the full update with drawing.

Every explorer class of ``course_lib/widgets/<topic>.py`` (a class named ``*Explorer`` with an
``update()`` method and a matplotlib figure, ``fig``) is built with its defaults under the Agg
backend and driven through its own controls: each of ~50 updates moves one of its numeric
sliders (in turn, to a new value across the slider's range), the way a student drags them.
Four rows per explorer:

- **compute**: the work of one update without drawing: the explorer's separated compute
  method when it has one (``refresh()``), otherwise ``update()`` with a figure view that draws
  nothing: the maths plus setting the artists' data in place;
- **update + draw**: ``update()`` followed by ``fig.canvas.draw()``, the full Agg render a
  student waited for before issue 15 (ipympl's PNG round trip not included);
- **update + blitted Agg redraw**: the first step of issue 15
  (:func:`course_lib.widgets._view.use_blitting`: cached background, changed artists
  rasterised), against the full draw as the peer;
- **update + scene for the browser**: what explorers do now (:class:`~course_lib.widgets._view.
  ScenePainter`): the changed artists recorded as a vector scene and packed into the message
  the page paints, against the full draw as the peer. The browser's side is measured by
  ``bench_browser``.

The compute row gives the median as "ours" against the 50 ms interactive budget as "peer"
(ratio below 1: within budget), with the 95th percentile and the median CPU time in the notes
(wall time above CPU time means the machine was busy with something else).
"""

from __future__ import annotations

import importlib
import inspect
import math
import pkgutil
import statistics
import sys
import time

from .harness import REPO, Row

SECTION = "widgets"
BUDGET_MS = 50.0
UPDATES = 50
SMOKE_UPDATES = 4


def explorer_classes() -> list[tuple[str, type]]:
    """``(module name, class)`` of every explorer in ``course_lib/widgets``."""
    found = []
    folder = REPO / "course_lib" / "widgets"
    for info in sorted(pkgutil.iter_modules([str(folder)]), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"course_lib.widgets.{info.name}")
        for name, cls in inspect.getmembers(mod, inspect.isclass):
            if cls.__module__ == mod.__name__ and callable(getattr(cls, "update", None)) \
                    and name.endswith("Explorer"):
                found.append((info.name, cls))
    return found


def sliders(explorer) -> list:
    """The explorer's numeric sliders (attributes, or inside list, tuple or dict attributes)."""
    import ipywidgets as W

    kinds = (W.FloatSlider, W.IntSlider, W.FloatLogSlider)
    out, seen = [], set()
    for value in vars(explorer).values():
        if isinstance(value, dict):
            items = list(value.values())
        elif isinstance(value, (list, tuple)):
            items = value
        else:
            items = [value]
        for w in items:
            if isinstance(w, kinds) and id(w) not in seen and not getattr(w, "disabled", False):
                seen.add(id(w))
                out.append(w)
    return out


def _target(slider, k: int):
    """The ``k``-th value of a low-discrepancy walk over the slider's range (never its current
    value, so every step is a real change)."""
    import ipywidgets as W

    frac = 0.1 + 0.8 * ((0.5 + k * 0.6180339887498949) % 1.0)
    lo, hi = slider.min, slider.max
    if isinstance(slider, W.FloatLogSlider):
        value = slider.base ** (lo + frac * (hi - lo))
    else:
        value = lo + frac * (hi - lo)
    if isinstance(slider, W.IntSlider):
        value = round(value)
        if value == slider.value:
            value = value + 1 if value < hi else value - 1
    elif getattr(slider, "step", None):
        step = slider.step
        if not isinstance(slider, W.FloatLogSlider):
            value = lo + round((value - lo) / step) * step
        if math.isclose(value, slider.value, abs_tol=1e-12):
            value = lo + (hi - lo) * (1.0 - frac)
    return value


def _move(explorer, controls, k: int) -> None:
    """Move control ``k % len(controls)`` with the explorer's ``update`` held, so that its
    callbacks change the explorer's state but the update itself is left to be timed."""
    explorer.update = lambda *a, **kw: None
    try:
        s = controls[k % len(controls)]
        s.value = _target(s, k)
    finally:
        del explorer.update


def _stats(samples: list[float]) -> tuple[float, float]:
    samples = sorted(samples)
    p95 = samples[min(len(samples) - 1, round(0.95 * (len(samples) - 1)))]
    return statistics.median(samples), p95


class _NoRedraw:
    """A figure view that draws nothing: what an update costs without its redraw."""

    def redraw(self, fig) -> None:
        pass


def _redrawn_updates(explorer, controls, updates: int, view) -> list[float]:
    """ms of ``update()`` redrawn by ``view`` (its first redraw, which draws everything, is
    not timed)."""
    from course_lib.widgets._view import set_view

    set_view(explorer, view)
    explorer.update()
    samples = []
    for k in range(updates):
        _move(explorer, controls, 2 * updates + k)
        t0 = time.perf_counter()
        explorer.update()
        samples.append((time.perf_counter() - t0) * 1e3)
    if view.blitter.blits == 0:
        raise RuntimeError("no update reused the background")
    return samples


def measure(cls, updates: int) -> dict:
    """Median and 95th percentile (ms) of the compute and of update + draw for one explorer."""
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    from course_lib.widgets._view import FigureView, set_view

    explorer = cls()
    fig = getattr(explorer, "fig", None)
    if not isinstance(fig, Figure):
        fig = next((v for v in vars(explorer).values() if isinstance(v, Figure)), None)
    if fig is None:
        raise RuntimeError("no matplotlib figure found on the explorer")
    canvas = fig.canvas
    try:
        fig.canvas.draw()                            # first draw: fonts, caches
        controls = sliders(explorer)
        if not controls:
            raise RuntimeError("no numeric slider to drive")
        has_refresh = callable(getattr(explorer, "refresh", None))
        set_view(explorer, _NoRedraw())
        compute, full, cpu = [], [], []
        for k in range(updates):
            _move(explorer, controls, 2 * k)
            c0, t0 = time.process_time(), time.perf_counter()
            explorer.refresh() if has_refresh else explorer.update()
            compute.append((time.perf_counter() - t0) * 1e3)
            cpu.append((time.process_time() - c0) * 1e3)
            _move(explorer, controls, 2 * k + 1)
            t0 = time.perf_counter()
            explorer.update()
            canvas.draw()
            full.append((time.perf_counter() - t0) * 1e3)
        blitted = _redrawn_updates(explorer, controls, updates, FigureView(blit=True))
        scene = _redrawn_updates(explorer, controls, updates, FigureView())
        return {"compute": _stats(compute), "full": _stats(full), "cpu": _stats(cpu)[0],
                "blit": _stats(blitted), "scene": _stats(scene),
                "n": updates,
                "what": "refresh()" if has_refresh else "update(), no redraw",
                "controls": len(controls)}
    finally:
        plt.close(fig)


def run(smoke: bool = False) -> list[Row]:
    import matplotlib

    matplotlib.use("Agg")
    rows = []
    updates = SMOKE_UPDATES if smoke else UPDATES
    for topic, cls in explorer_classes():
        case = f"{topic}: {cls.__name__}"
        try:
            m = measure(cls, updates)
        except Exception as exc:  # noqa: BLE001 - one broken explorer is reported
            print(f"warning: {case} could not be measured: {exc!r}", file=sys.stderr)
            rows.append(Row(SECTION, case, "compute per update", float("nan"),
                            notes=f"not measured: {type(exc).__name__}: {exc}"[:160]))
            continue
        (c_med, c_p95), (f_med, f_p95) = m["compute"], m["full"]
        base = f"{m['n']} updates over {m['controls']} sliders"
        rows.append(Row(SECTION, case, "compute per update (median)", c_med, BUDGET_MS,
                        "budget", notes=f"p95 {c_p95:.1f} ms, CPU median {m['cpu']:.1f} ms; "
                                        f"{m['what']}; {base}"))
        rows.append(Row(SECTION, case, "update + canvas.draw (median)", f_med,
                        notes=f"p95 {f_p95:.1f} ms; full Agg render (not part of the 50 ms "
                              f"compute target); {base}"))
        b_med, b_p95 = m["blit"]
        rows.append(Row(SECTION, case, "update + blitted Agg redraw (median)", b_med, f_med,
                        "update + canvas.draw", notes=f"p95 {b_p95:.1f} ms; cached background, "
                        f"changed artists rasterised in the kernel (PNG not included); {base}"))
        s_med, s_p95 = m["scene"]
        rows.append(Row(SECTION, case, "update + scene for the browser (median)", s_med, f_med,
                        "update + canvas.draw", notes=f"p95 {s_p95:.1f} ms; what explorers do: "
                        f"changed artists recorded and packed for the page to paint; {base}"))
    return rows
