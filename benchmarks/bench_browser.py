"""Browser: key press on a slider to changed pixels, for every explorer, in Chromium via JupyterLab.

What a student feels when dragging a control (issue 15). For each explorer a scratch notebook
(the explorer as its last expression, as in the course's notebooks) runs in a real JupyterLab on
localhost; Debian's Chromium, driven by Playwright, focuses one slider's handle and presses an
arrow key ``PRESSES`` times. Inside the page a capture-phase ``keydown`` listener notes the
event's time and a ``requestAnimationFrame`` loop compares the figure canvas' pixels with the
frame shown before the press: the latency is the time to the first frame that differs. The
loop reads the pixels back only on frames after a drawing call on that canvas (counted by
wrapping the 2-D context's drawing methods, ``_WATCH_JS``): reading 2.5 MB on every frame made
the probe itself a load on the two cores. After
that the loop watches until the canvas has been still for ``SETTLE_MS``, counting the frames
that changed (one per press: no intermediate or flickering frame), before the next press.

Each explorer is measured twice in the same run: as it is now ("ours", painted by the browser)
and as it was before issue 15 ("peer"): the ``course_lib`` package of commit ``BEFORE_REF``
(override with the environment variable ``BENCH_BROWSER_BEFORE``; ``none`` skips it), exported
from git into the scratch folder under another name, whose figures are ipympl canvases (its
notebook starts with ``%matplotlib widget``). The target is a p90 below ``TARGET_MS``.

At smoke sizes one explorer gets three presses and no "before" run. Without Chromium, or
outside a git checkout for the "before" code, the rows say what was not measured.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import socket
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
import urllib.request
from contextlib import contextmanager
from pathlib import Path

from .harness import REPO, Row

SECTION = "browser"
CHROMIUM = Path("/usr/bin/chromium")
BEFORE_REF = "3c4f87f"          # the last commit before the explorers blitted (issue 15)
TARGET_MS = 100.0
PRESSES = 30
SMOKE_PRESSES = 3
SETTLE_MS = 400
#: the figure's canvas: the browser-painted one (``FigureCanvas``) or, before it, ipympl's
CANVAS = "canvas.course-figure-canvas, .jupyter-matplotlib-canvas-div canvas"
PRESS_TIMEOUT_MS = 5000

#: ``(module, factory, slider description, keys)``: the control each explorer is driven by, and
#: the arrow key(s) pressed in turn (two keys go back and forth, for a short slider). The
#: collimator's pitch is a second row: its face views step through fixed sizes, so a press
#: between 10 and 10.5 mm keeps their limits and the background (one that crosses a size
#: draws a new background, the one costly kind of update left).
EXPLORERS = (
    ("shading", "phong_explorer", "light azimuth°", "ArrowRight"),
    ("splines", "spline_end_explorer", "x", "ArrowRight"),
    ("ultrasound", "bscan_explorer", "fat speed (m/s)", "ArrowRight"),
    ("gamma_camera", "collimator_explorer", "source distance z (mm)", "ArrowLeft"),
    ("gamma_camera", "collimator_explorer", "ring pitch (mm)", ("ArrowRight", "ArrowLeft")),
    ("clipping", "clipping_explorer", "X", "ArrowRight"),
    ("marching_cubes", "case_explorer", "iso-level", "ArrowRight"),
)

# In the page, once: count the drawing calls made on each canvas. A canvas' pixels can change
# only through its context's drawing calls or a resize, so the probe below reads the pixels
# back (getImageData, 2.5 MB for the widest figure) only on animation frames after one: read
# on every frame, the probe itself took ~40 % of a core from the two the kernel, the server
# and the browser share, and slowed every explorer (before and now alike) by 10-30 ms.
_WATCH_JS = """
() => {
  if (window.__benchDrawn) return;
  const drawn = window.__benchDrawn = new WeakMap();
  const bump = (canvas) => { if (canvas) drawn.set(canvas, (drawn.get(canvas) || 0) + 1); };
  const proto = CanvasRenderingContext2D.prototype;
  for (const name of ['clearRect', 'fillRect', 'strokeRect', 'fill', 'stroke', 'drawImage',
                      'putImageData', 'fillText', 'strokeText', 'reset']) {
    const original = proto[name];
    if (typeof original !== 'function') continue;
    proto[name] = function (...args) { bump(this.canvas); return original.apply(this, args); };
  }
  for (const name of ['width', 'height']) {
    const d = Object.getOwnPropertyDescriptor(HTMLCanvasElement.prototype, name);
    Object.defineProperty(HTMLCanvasElement.prototype, name, {
      ...d, set(value) { bump(this); d.set.call(this, value); } });
  }
}
"""

# In the page: one press measured from its keydown to the first changed canvas frame.
_MEASURE_JS = """
async ([canvas, settleMs, timeoutMs]) => {
  const ctx = canvas.getContext('2d');
  const drawnOn = () => window.__benchDrawn.get(canvas) || 0;
  const grab = () => new Uint32Array(
      ctx.getImageData(0, 0, canvas.width, canvas.height).data.buffer);
  const differs = (a, b) => {
    if (a.length !== b.length) return true;
    for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return true;
    return false;
  };
  let seen = drawnOn();
  let last = grab();
  let t0 = null;
  const onKey = (e) => { if (t0 === null) t0 = performance.now(); };
  window.addEventListener('keydown', onKey, {capture: true});
  window.__benchArmed = true;
  const frame = () => new Promise(r => requestAnimationFrame(r));
  let first = null, frames = 0, lastChange = null;
  const start = performance.now();
  while (performance.now() - start < timeoutMs) {
    await frame();
    if (t0 === null) continue;
    const now = performance.now();
    if (drawnOn() !== seen) {              // drawn on since the last look: compare the pixels
      seen = drawnOn();
      const pixels = grab();
      if (differs(pixels, last)) {
        frames += 1; lastChange = now; last = pixels;
        if (first === null) first = now;
      }
    }
    if (first !== null && now - lastChange > settleMs) break;
  }
  window.removeEventListener('keydown', onKey, {capture: true});
  window.__benchArmed = false;
  return {latency: first === null ? null : first - t0, frames: frames};
}
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def _jupyter_lab(root: Path):
    """A JupyterLab on localhost serving ``root``: yields ``(base_url, token)``."""
    port, token = _free_port(), secrets.token_hex(16)
    bin_dir = Path(sys.executable).parent
    env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}",
               JUPYTER_CONFIG_DIR=str(root / ".jupyter-config"),
               JUPYTERLAB_SETTINGS_DIR=str(root / ".lab-settings"))
    env.pop("MPLBACKEND", None)
    settings = root / ".lab-settings" / "@jupyterlab" / "apputils-extension"
    settings.mkdir(parents=True, exist_ok=True)
    (settings / "notification.jupyterlab-settings").write_text('{"fetchNews": "false"}')
    log = open(root / "lab.log", "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}",
         "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={token}",
         f"--ServerApp.root_dir={root}", "--LabApp.news_url=None", "--allow-root"],
        env=env, stdout=log, stderr=subprocess.STDOUT, cwd=root)
    base = f"http://127.0.0.1:{port}"
    try:
        _wait_for(f"{base}/api/status?token={token}", proc, root / "lab.log")
        yield base, token
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def _wait_for(url: str, proc, log_path: Path, timeout_s: float = 120.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            with urllib.request.urlopen(url, timeout=2) as r:
                if r.status == 200:
                    return
        except OSError:
            time.sleep(0.5)
    raise RuntimeError(f"JupyterLab did not start:\n{log_path.read_text()[-2000:]}")


def export_before(ref: str, dest: Path) -> str | None:
    """``course_lib`` at git ``ref`` as the package ``course_lib_before`` under ``dest``;
    returns the package name, or ``None`` when git or the ref is not available."""
    try:
        archive = subprocess.run(["git", "archive", ref, "course_lib"], cwd=REPO,
                                 capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    dest.mkdir(parents=True, exist_ok=True)
    tar_path = dest / "before.tar"
    tar_path.write_bytes(archive)
    with tarfile.open(tar_path) as tar:
        tar.extractall(dest, filter="data")
    (dest / "course_lib").rename(dest / "course_lib_before")
    return "course_lib_before"


def write_notebook(path: Path, package: str, module: str, factory: str,
                   extra_path: Path | None) -> None:
    """A two-cell notebook: set-up (``%matplotlib widget`` for the "before" code, whose
    explorers were ipympl canvases), then the explorer as the last expression."""
    setup = "" if package == "course_lib" else "%matplotlib widget\n"
    if extra_path is not None:
        setup += f"import sys\nsys.path.insert(0, {str(extra_path)!r})\n"
    import nbformat

    cells = [setup, f"from {package}.widgets.{module} import {factory}\n{factory}()"]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in cells])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    nbformat.write(nb, path)


def run_notebook(page, base: str, token: str, name: str) -> None:
    """Open notebook ``name`` in JupyterLab, run all its cells and wait for the figure."""
    page.goto(f"{base}/lab/tree/{name}?token={token}&reset")
    page.wait_for_selector(".jp-NotebookPanel .jp-Notebook .jp-Cell")
    page.locator(".jp-StatusBar-Widget", has_text="Idle").first.wait_for(timeout=120_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.locator(".lm-Menu-itemLabel", has_text="Run All Cells").first.click()
    page.locator(CANVAS).first.wait_for(timeout=120_000)


def _slider_handle(page, description: str):
    label = page.locator(".widget-label").filter(has_text=re.compile(rf"^{re.escape(description)}$"))
    slider = page.locator(".widget-slider").filter(has=label).first
    return slider.locator(".noUi-handle, [role='slider']").first


def _keys(key) -> tuple:
    """The keys of an ``EXPLORERS`` entry, pressed in turn: one key, or a tuple of them."""
    return key if isinstance(key, tuple) else (key,)


def measure_presses(page, description: str, key, presses: int) -> dict:
    """Press ``key`` (or, for a tuple, its keys in turn) on the slider ``description``
    ``presses`` times, one after the other.

    Returns ``{"latencies": [ms, ...], "frames": [changed frames per press], "missed": n}``
    (a press whose canvas did not change within ``PRESS_TIMEOUT_MS`` is missed).
    """
    canvas = page.locator(CANVAS).first
    canvas.scroll_into_view_if_needed()
    time.sleep(2.0)                                   # the first frames, fonts, caches
    page.evaluate("src => { window.__benchMeasure = (0, eval)('(' + src + ')'); }",
                  _MEASURE_JS.strip())
    page.evaluate(_WATCH_JS.strip())
    handle = _slider_handle(page, description)
    handle.focus()
    keys = _keys(key)
    latencies, frames, missed = [], [], 0
    for press in range(presses):
        canvas.evaluate("(el, a) => { window.__benchResult = window.__benchMeasure([el, ...a]); }",
                        [SETTLE_MS, PRESS_TIMEOUT_MS])
        page.wait_for_function("window.__benchArmed === true")
        handle.press(keys[press % len(keys)])
        result = page.evaluate("window.__benchResult")
        if result["latency"] is None:
            missed += 1
        else:
            latencies.append(result["latency"])
            frames.append(result["frames"])
    return {"latencies": latencies, "frames": frames, "missed": missed}


def _shut_down_kernels(page, base: str, token: str) -> None:
    sessions = page.request.get(f"{base}/api/sessions?token={token}").json()
    for s in sessions:
        page.request.delete(f"{base}/api/sessions/{s['id']}?token={token}")


def _p90(samples: list[float]) -> float:
    samples = sorted(samples)
    return samples[min(len(samples) - 1, round(0.9 * (len(samples) - 1)))]


def _summary(m: dict | None) -> dict | None:
    if not m or not m["latencies"]:
        return None
    return {"median": statistics.median(m["latencies"]), "p90": _p90(m["latencies"]),
            "max_frames": max(m["frames"]), "n": len(m["latencies"]), "missed": m["missed"]}


def measure_explorer(browser, base, token, root, package, spec, presses, extra_path=None):
    """Open the explorer ``spec`` from ``package`` in a fresh page and measure it."""
    module, factory, description, key = spec
    name = f"{package}-{module}.ipynb"
    write_notebook(root / name, package, module, factory, extra_path)
    context = browser.new_context(viewport={"width": 1500, "height": 1100})
    page = context.new_page()
    page.set_default_timeout(60_000)
    try:
        run_notebook(page, base, token, name)
        return measure_presses(page, description, key, presses)
    finally:
        _shut_down_kernels(page, base, token)
        context.close()


def _missed(summary: dict) -> str:
    return f", {summary['missed']} missed" if summary["missed"] else ""


def _row(spec, ours, before, ref) -> Row:
    module, _, description, key = spec
    keys = _keys(key)
    case = f"{module}: {description}"
    if ours is None:
        return Row(SECTION, case, "key press to pixels, p90", float("nan"),
                   notes="not measured: no frame changed")
    verdict = "met" if ours["p90"] < TARGET_MS else "NOT met"
    notes = (f"median {ours['median']:.0f} ms; {ours['n']} presses of {'/'.join(keys)}"
             f"{_missed(ours)}; "
             f"at most {ours['max_frames']} changed frame(s) per press; "
             f"target p90 < {TARGET_MS:.0f} ms: {verdict}")
    if before is None:
        return Row(SECTION, case, "key press to pixels, p90", ours["p90"], notes=notes)
    notes += f"; before: median {before['median']:.0f} ms, at most {before['max_frames']} frame(s)"
    return Row(SECTION, case, "key press to pixels, p90", ours["p90"], before["p90"],
               f"before, {ref}", notes=notes)


def _not_measured(reason: str) -> list[Row]:
    return [Row(SECTION, f"{spec[0]}: {spec[2]}", "key press to pixels, p90", float("nan"),
                notes=f"not measured: {reason}") for spec in EXPLORERS]


def run(smoke: bool = False) -> list[Row]:
    if not CHROMIUM.exists():
        return _not_measured("Debian's chromium is not installed (make test installs it)")
    from playwright.sync_api import sync_playwright

    specs = EXPLORERS[:1] if smoke else EXPLORERS
    presses = SMOKE_PRESSES if smoke else PRESSES
    ref = os.environ.get("BENCH_BROWSER_BEFORE", BEFORE_REF)
    root = Path(tempfile.mkdtemp(prefix="bench-browser-"))
    try:
        before_pkg = None if smoke or ref == "none" else export_before(ref, root / "before")
        rows = []
        with _jupyter_lab(root) as (base, token), sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(CHROMIUM),
                                         args=["--headless", "--no-sandbox", "--disable-gpu"])
            try:
                for spec in specs:
                    print(f"   {spec[0]} ...", file=sys.stderr, flush=True)
                    ours = _summary(measure_explorer(browser, base, token, root, "course_lib",
                                                     spec, presses))
                    before = None
                    if before_pkg:
                        before = _summary(measure_explorer(browser, base, token, root,
                                                           before_pkg, spec, presses,
                                                           root / "before"))
                    rows.append(_row(spec, ours, before, ref))
            finally:
                browser.close()
        return rows
    finally:
        shutil.rmtree(root, ignore_errors=True)
