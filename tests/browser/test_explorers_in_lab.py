"""The explorers in a real JupyterLab in a real browser (issue: interactive explorers).

For the q4 and q5 notebooks: open the notebook, run all cells, find the explorer's figure,
move a control, and assert that the rendered figure changed (pixels of the explorer's
browser-painted ``canvas.course-figure-canvas``, issue 15).
Also check that nbgrader's JupyterLab extension is there for students (the Validate button and
the Nbgrader menu). Screenshots are kept under ``test-artifacts/browser/``.
"""

from __future__ import annotations

import io
import re
import time

import numpy as np
import pytest

from labtools import open_notebook, run_all_cells

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("browser")]

#: the explorers' figure: a ``FigureCanvas`` widget painted by the page (issue 15)
FIGURE_CANVAS = "canvas.course-figure-canvas"


def open_and_run_all(page, base, token, name, artifacts, timeout_s=240):
    open_notebook(page, base, f"token={token}", name)
    page.wait_for_selector(".jp-Notebook-ExecutionIndicator, .jp-StatusBar-TextItem", timeout=60_000)
    run_all_cells(page, 60, timeout_s)
    page.screenshot(path=str(artifacts / f"{name}-after-run-all.png"), full_page=False)
    errors = page.locator(".jp-OutputArea-output[data-mime-type='application/vnd.jupyter.stderr']")
    tracebacks = [t for t in errors.all_inner_texts() if "Traceback" in t or "Error" in t.split("\n")[0]]
    assert not tracebacks, f"{name}: errors after Run All:\n" + "\n---\n".join(tracebacks)[:3000]




def canvas_pixels(locator) -> np.ndarray:
    from PIL import Image

    locator.scroll_into_view_if_needed()
    png = locator.screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)


def changed_fraction(a: np.ndarray, b: np.ndarray) -> float:
    if a.shape != b.shape:
        return 1.0
    return float(np.mean(np.any(np.abs(a - b) > 8, axis=-1)))


def wait_for_change(locator, before, timeout_s=20.0, min_fraction=0.002):
    deadline = time.monotonic() + timeout_s
    frac = 0.0
    while time.monotonic() < deadline:
        frac = changed_fraction(before, canvas_pixels(locator))
        if frac >= min_fraction:
            return frac
        time.sleep(0.4)
    return frac


def explorer_output(page, control_text):
    """The output area holding the explorer whose controls include ``control_text``."""
    out = page.locator(".jp-OutputArea-output").filter(
        has=page.locator(FIGURE_CANVAS)).filter(has_text=control_text).first
    out.wait_for(timeout=60_000)
    return out


def test_nbgrader_extension_present(page, lab_server, artifacts):
    base, token, _ = lab_server
    open_notebook(page, base, f"token={token}", "q5_phong.ipynb")
    validate = page.locator(".jp-NotebookPanel-toolbar", has_text="Validate")
    validate.first.wait_for(timeout=30_000)
    assert page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").count() == 1
    page.screenshot(path=str(artifacts / "nbgrader-extension.png"))


def test_spline_explorer_end_rule_changes_figure(page, lab_server, artifacts):
    base, token, _ = lab_server
    open_and_run_all(page, base, token, "q4_splines.ipynb", artifacts)
    out = explorer_output(page, "end rule")
    canvas = out.locator(FIGURE_CANVAS).first
    before = canvas_pixels(canvas)
    out.screenshot(path=str(artifacts / "q4-explorer-before.png"))
    # switch the spline kind and the end rule: the curve and its end point must move
    out.locator("button", has_text="B-spline").first.click()
    out.locator("button", has_text="d = 2c").first.click()
    frac = wait_for_change(canvas, before)
    out.screenshot(path=str(artifacts / "q4-explorer-after.png"))
    assert frac >= 0.002, f"the spline figure did not change after moving a control ({frac:.4f})"
    # the formulas, typeset, fit their panel: nothing hides past its right edge
    formulas = out.locator(".widget-htmlmath", has_text="general (Q4(b))").first
    formulas.locator("mjx-container").first.wait_for(timeout=20_000)
    assert formulas.locator("mjx-container").count() >= 9   # three rows of p, p', p''
    width, inner = formulas.evaluate("el => [el.clientWidth, el.scrollWidth]")
    assert inner <= width, f"the formulas are {inner} px wide in a {width} px panel"


def test_phong_explorer_controls_change_figure(page, lab_server, artifacts):
    base, token, _ = lab_server
    open_and_run_all(page, base, token, "q5_phong.ipynb", artifacts)
    out = explorer_output(page, "ka (ambient)")
    canvas = out.locator(FIGURE_CANVAS).first
    before = canvas_pixels(canvas)
    out.screenshot(path=str(artifacts / "q5-explorer-before.png"))
    # move the light-azimuth slider with the keyboard, as a user would
    slider = out.locator(".widget-slider", has_text="light azimuth").first
    handle = slider.locator(".noUi-handle, .ui-slider-handle, [role='slider']").first
    handle.focus()
    for _ in range(30):
        handle.press("ArrowRight")
    frac = wait_for_change(canvas, before)
    out.screenshot(path=str(artifacts / "q5-explorer-slider.png"))
    assert frac >= 0.002, f"the sphere did not change after moving the light ({frac:.4f})"
    # the exam's worked example is one click away and shows the exam's numbers
    before = canvas_pixels(canvas)
    out.locator("button", has_text="Exam Q5(b)").first.click()
    wait_for_change(canvas, before)
    # the explorer's own readout (not the notebook's prose) shows the exam's answer
    readout = out.locator(".widget-html", has_text="0.0931")
    readout.first.wait_for(timeout=20_000)
    assert re.search(r"0\.69[89]", readout.first.inner_text())
    out.screenshot(path=str(artifacts / "q5-explorer-exam.png"))


def test_each_key_press_brings_one_frame_and_the_light_follows(page, lab_server, artifacts):
    """Issue 15: a slider key gives exactly one new frame (nothing queued or flickering), and
    the explorer's readout shows the light direction of the slider's new azimuth."""
    from benchmarks.bench_browser import run_notebook, measure_presses, write_notebook
    from course_lib.widgets.shading import direction

    base, token, root = lab_server
    write_notebook(root / "phong-keys.ipynb", "course_lib", "shading", "phong_explorer", None)
    run_notebook(page, base, token, "phong-keys.ipynb")
    presses = measure_presses(page, "light azimuth°", "ArrowRight", 4)
    page.screenshot(path=str(artifacts / "phong-keys.png"))
    assert presses["missed"] == 0, presses
    assert presses["frames"] == [1, 1, 1, 1], presses
    # four steps of 0.5 degrees from the default azimuth of -45
    readout = page.locator(".widget-html", has_text="L = (").first.inner_text()
    shown = [float(x) for x in re.search(r"L = \(([^)]*)\)", readout).group(1).split(",")]
    np.testing.assert_allclose(shown, direction(-43.0, 35.0), atol=6e-4)
