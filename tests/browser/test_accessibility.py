"""Every student can use the course: WCAG 2.1 AA in the notebooks and explorers, in Chromium.

Each release notebook is opened in the student view (``python -m autograder lab --role
student``: nbgrader's release, the students' JupyterLab extensions), Run All is chosen, and:

* axe-core 4 (WCAG 2.0/2.1, levels A and AA) runs on the notebook's content ``.jp-Notebook``
  (not JupyterLab's own menus and panels): no serious or critical violation, except the rules
  named in :data:`EXCEPTIONS` with the reason;
* every figure output is an image whose text alternative is written from its data (more than a
  caption: at least :data:`MIN_ALT_WORDS` words and some numbers), and the explorer's canvas is
  ``role="img"`` with such an ``aria-label``;
* the explorer is driven by the keyboard only (Tab to a control, arrow keys): the figure
  changes, its label follows, its readout is a live region; axe runs on the explorer after the
  presses too.

JupyterLab draws every cell here (``windowingMode: none``), so axe sees the whole notebook.
The violations found are written to ``test-artifacts/browser/axe-<notebook>.json``.
"""

from __future__ import annotations

import json
import re
import socket
import time

import pytest

from a11y import counts, describe, run_axe, save, severe
from autograder.course import nbgrader_env
from labtools import open_notebook, run_all_cells, running_lab, wait_idle
from test_explorers_in_lab import FIGURE_CANVAS, canvas_pixels, wait_for_change

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("browser")]

NOTEBOOKS = ("q1_imaging", "q2_nuclear", "q3_marching_cubes", "q4_splines", "q5_phong",
             "q6_clipping")
#: what axe finds inside ``.jp-Notebook`` that is JupyterLab's own (4.x), not the course's, and
#: that no setting of JupyterLab changes: ``(rule, the element's HTML, why)``. Each names the
#: element, so the same rule on the course's own content still fails.
EXCEPTIONS = (
    ("aria-input-field-name", 'class="cm-content"',
     "JupyterLab's cell editor (CodeMirror 6, role=textbox) has no accessible name"),
    ("button-name", "jp-collapseHeadingButton",
     "JupyterLab's collapse-heading button beside a heading cell is an empty <button>"),
    ("aria-required-children", 'role="feed"',
     "JupyterLab's notebook viewport is role=feed, its cells are not role=article"),
    ("scrollable-region-focusable", "jp-MarkdownOutput",
     "a markdown cell wider than the notebook (a wide table or equation) scrolls in a box "
     "that JupyterLab does not make focusable"),
)
MIN_ALT_WORDS = 12


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def student_lab(tmp_path_factory, repo_root):
    """The student view of the release (this checkout's ``course_lib``, so what is tested is
    what is committed), every cell drawn."""
    tmp = tmp_path_factory.mktemp("a11y-lab")
    settings = tmp / "lab-settings" / "@jupyterlab"
    (settings / "notebook-extension").mkdir(parents=True)
    (settings / "notebook-extension" / "tracker.jupyterlab-settings").write_text(
        json.dumps({"windowingMode": "none"}))
    (settings / "apputils-extension").mkdir(parents=True)
    (settings / "apputils-extension" / "notification.jupyterlab-settings").write_text(
        json.dumps({"fetchNews": "false"}))
    env = dict(nbgrader_env(), JUPYTERLAB_SETTINGS_DIR=str(tmp / "lab-settings"))
    env.pop("MPLBACKEND", None)
    args = ["--role", "student", "--course-root", str(tmp / "course")]
    with running_lab(args, _port(), tmp / "lab.log", repo_root, env, "the student lab") as url:
        yield url.split("/lab", 1)[0], url.split("?", 1)[1]


@pytest.fixture(scope="module", params=NOTEBOOKS)
def ran(request, browser, student_lab, artifacts):
    """``(name, page)``: the release notebook ``name`` after Run All, its kernel idle."""
    name = request.param
    base, query = student_lab
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    page = context.new_page()
    page.set_default_timeout(60_000)
    try:
        open_notebook(page, base, query, f"tripos2006/{name}.ipynb")
        run_all_cells(page, 120, 600)
        page.locator(FIGURE_CANVAS).first.wait_for(timeout=120_000)
        wait_idle(page, 120)
        time.sleep(1.0)
        yield name, page
    finally:
        sessions = page.request.get(f"{base}/api/sessions?{query}").json()
        for s in sessions:
            page.request.delete(f"{base}/api/sessions/{s['id']}?{query}")
        context.close()


def test_notebook_has_no_serious_violations(ran, artifacts):
    name, page = ran
    found = run_axe(page, ".jp-NotebookPanel .jp-Notebook")
    save(artifacts / f"axe-{name}.json", found)
    print(f"{name}: serious/critical", dict(counts(found)))
    bad = severe(found, EXCEPTIONS)
    assert not bad, f"{name}: axe found\n{describe(bad)}"


def _alt_texts(page) -> list[tuple[str, str]]:
    """``(kind, text)`` of every figure in the notebook's outputs: images and canvases."""
    return page.evaluate("""() => {
      const out = [];
      for (const img of document.querySelectorAll('.jp-Notebook .jp-OutputArea-output img'))
        out.push(['img', img.getAttribute('alt') || '']);
      for (const c of document.querySelectorAll('.jp-Notebook canvas.course-figure-canvas')) {
        const host = c.closest('[role=img]') || c;
        out.push(['canvas', host.getAttribute('role') === 'img'
                  ? (host.getAttribute('aria-label') || '') : '']);
      }
      return out;
    }""")


def test_every_figure_has_a_text_alternative_from_its_data(ran):
    name, page = ran
    figures = _alt_texts(page)
    print(f"{name}: {sum(k == 'img' for k, _ in figures)} figures, "
          f"{sum(k == 'canvas' for k, _ in figures)} explorer canvases")
    assert any(kind == "img" for kind, _ in figures), f"{name}: no static figure drawn"
    assert any(kind == "canvas" for kind, _ in figures), f"{name}: no explorer drawn"
    thin = [(kind, text) for kind, text in figures
            if len(text.split()) < MIN_ALT_WORDS or not re.search(r"\d", text)]
    assert not thin, f"{name}: figures without a text alternative written from data: {thin}"


def _explorer(page):
    """The explorer's output area (marked ``data-a11y-explorer`` for axe), scrolled into view."""
    out = page.locator(".jp-OutputArea-output").filter(has=page.locator(FIGURE_CANVAS)).first
    out.wait_for(timeout=60_000)
    out.evaluate("el => el.setAttribute('data-a11y-explorer', '')")
    out.scroll_into_view_if_needed()
    return out


def _focused(page) -> dict:
    return page.evaluate("""() => {
      const el = document.activeElement;
      const box = el && el.closest('[data-a11y-explorer]');
      return {inside: !!box, role: el ? el.getAttribute('role') : null,
              name: el ? (el.getAttribute('aria-label') || el.textContent || '').trim() : '',
              now: el ? el.getAttribute('aria-valuenow') : null};
    }""")


def _tab_to_slider(page, out, limit=60) -> dict:
    """From the explorer's first control, Tab until a slider has the focus; returns it."""
    out.locator("button, select, input, [role=slider]").first.focus()
    for _ in range(limit):
        here = _focused(page)
        assert here["inside"], f"Tab left the explorer before reaching a slider: {here}"
        if here["role"] == "slider":
            return here
        page.keyboard.press("Tab")
    raise AssertionError(f"no slider within {limit} Tab presses")


def _label_changes(canvas, before: str, timeout_s: float = 20.0) -> bool:
    """Whether the canvas' ``aria-label`` leaves ``before`` (the kernel rewrites it a moment
    after the frame)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if (canvas.get_attribute("aria-label") or "") != before:
            return True
        time.sleep(0.2)
    return False


def _tab_to_canvas(page, out, canvas, limit=60) -> bool:
    """Focus the explorer's 3-D figure by keys: Tab on from its first control (a figure below
    the controls), else Shift+Tab back from it (a figure before them)."""
    on_canvas = "el => document.activeElement === el"
    out.locator("button, select, input, [role=slider]").first.focus()
    for _ in range(limit):
        page.keyboard.press("Tab")
        if canvas.evaluate(on_canvas):
            return True
        if not _focused(page)["inside"]:
            break
    out.locator("button, select, input, [role=slider]").first.focus()
    page.keyboard.press("Shift+Tab")
    return canvas.evaluate(on_canvas)


def test_explorer_by_keyboard_only(ran, artifacts):
    """Tab reaches a named slider, arrow keys move it and the figure and its text alternative
    change; the readouts are live regions; Tab goes on out of the explorer (no trap)."""
    name, page = ran
    out = _explorer(page)
    canvas = out.locator(FIGURE_CANVAS).first
    label_before = canvas.get_attribute("aria-label") or ""
    pixels_before = canvas_pixels(canvas)
    slider = _tab_to_slider(page, out)
    assert len(slider["name"]) >= 2, f"{name}: a slider without a name: {slider}"
    for key in ("ArrowRight", "ArrowLeft"):
        for _ in range(8):
            page.keyboard.press(key)
        if _focused(page)["now"] != slider["now"]:
            break
    moved = _focused(page)
    assert moved["now"] != slider["now"], f"{name}: arrow keys did not move '{slider['name']}'"
    frac = wait_for_change(canvas, pixels_before)
    out.screenshot(path=str(artifacts / f"a11y-{name}-keys.png"))
    assert frac >= 0.002, f"{name}: the figure did not change under the keys ({frac:.4f})"
    assert _label_changes(canvas, label_before), \
        f"{name}: the canvas' text alternative did not follow the figure"
    assert out.locator("[aria-live=polite]").count() >= 1, f"{name}: no live readout"
    if canvas.get_attribute("tabindex") == "0":   # a 3-D view: its arrow keys turn it
        assert _tab_to_canvas(page, out, canvas), f"{name}: the keyboard never reaches the 3-D figure"
        label, pixels = canvas.get_attribute("aria-label"), canvas_pixels(canvas)
        for _ in range(3):
            page.keyboard.press("ArrowRight")
        assert wait_for_change(canvas, pixels) >= 0.002, f"{name}: the 3-D view did not turn"
        assert _label_changes(canvas, label), f"{name}: the 3-D view's description did not turn"
        assert re.search(r"azimuth -?[\d.]+ degrees", canvas.get_attribute("aria-label") or "")
    for _ in range(80):                       # no focus trap: Tab leaves the explorer
        page.keyboard.press("Tab")
        if not _focused(page)["inside"]:
            break
    assert not _focused(page)["inside"], f"{name}: Tab never leaves the explorer"


def test_explorer_has_no_serious_violations_after_keys(ran, artifacts):
    name, page = ran
    out = _explorer(page)
    _tab_to_slider(page, out)
    for key in ("ArrowRight", "ArrowRight", "ArrowLeft"):
        page.keyboard.press(key)
    time.sleep(1.0)
    found = run_axe(page, "[data-a11y-explorer]")
    save(artifacts / f"axe-{name}-explorer.json", found)
    bad = severe(found)
    assert not bad, f"{name} explorer: axe found\n{describe(bad)}"


# --- what a screen reader says: Chromium's own accessibility tree -------------------------

_MARK_CONTROLS_JS = """(out) => {
  // every keyboard-reachable control of the explorer, tagged, with its visible label
  const clean = (s) => (s || '').replace(/[\\u200b\\ue000-\\uf8ff]/g, '').trim();
  const labelOf = (el) => {
    if (el.getAttribute('role') === 'slider') {
      const s = el.closest('.widget-slider');
      return clean(s && s.querySelector('.widget-label').textContent);
    }
    if (el.type === 'checkbox') return clean(el.closest('label') && el.closest('label').textContent);
    if (el.tagName === 'BUTTON') return clean(el.textContent);
    const box = el.closest('.widget-inline-hbox');
    const l = box && box.querySelector(':scope > .widget-label');
    return clean(l && l.textContent);
  };
  const found = [];
  const selector = '[role=slider], button, select, input, textarea, [contenteditable=true]';
  for (const el of out.querySelectorAll(selector)) {
    if (el.tabIndex < 0 || !el.offsetParent) continue;
    const i = found.length;
    el.setAttribute('data-a11y-ctl', String(i));
    const slider = el.closest('.widget-slider');
    const readout = slider && slider.querySelector('.widget-readout');
    found.push({i, tag: el.tagName, label: labelOf(el),
                readout: readout ? readout.textContent.trim() : null,
                valuetext: el.getAttribute('aria-valuetext'),
                pressed: el.classList.contains('mod-active'),
                toggle: !!el.closest('.widget-toggle-buttons')});
  }
  return found;
}"""


def _ax_node(page, cdp, index: int) -> dict:
    """Chromium's accessibility node of the control tagged ``index``: role, name, properties."""
    obj = cdp.send("Runtime.evaluate", {
        "expression": f"document.querySelector('[data-a11y-ctl=\"{index}\"]')"})["result"]
    node = cdp.send("Accessibility.getPartialAXTree",
                    {"objectId": obj["objectId"], "fetchRelatives": False})["nodes"][0]
    props = {p["name"]: p["value"].get("value") for p in node.get("properties", [])}
    return {"role": node.get("role", {}).get("value"),
            "name": (node.get("name") or {}).get("value", ""),
            "value": (node.get("value") or {}).get("value"), **props}


def _controls(page, out):
    cdp = page.context.new_cdp_session(page)
    cdp.send("Accessibility.enable")
    controls = out.evaluate(_MARK_CONTROLS_JS)
    return [(c, _ax_node(page, cdp, c["i"])) for c in controls]


#: a slider's unit as its description shows it, and as its value text must say it
_UNIT = re.compile(r"\((mm|m/s|MHz)\)\s*$|(°)\s*$")


def test_every_control_is_named_by_its_visible_label(ran):
    """The accessible name (what a screen reader says) holds the control's visible label and
    is never "null", "undefined" or blank (WCAG 2.5.3, label in name)."""
    name, page = ran
    out = _explorer(page)
    time.sleep(0.5)
    controls = _controls(page, out)
    assert controls, f"{name}: no control found in the explorer"
    bad = []
    for c, ax in controls:
        spoken = ax["name"].strip().replace("\u200b", "")
        if (not spoken or re.search(r"\b(null|undefined)\b", spoken)
                or re.search(r"[\ue000-\uf8ff]", spoken)
                or (c["label"] and c["label"].lower() not in spoken.lower())):
            bad.append((c["tag"], c["label"], ax["role"], ax["name"]))
    assert not bad, f"{name}: controls whose spoken name is not their label: {bad}"


def test_slider_values_are_spoken_as_shown_with_units(ran):
    """A slider's value text is its readout as shown (rounded, no float noise; a log slider's
    value, not its logarithm) followed by its unit."""
    name, page = ran
    out = _explorer(page)
    sliders = [c for c, ax in _controls(page, out) if ax["role"] == "slider"]
    assert sliders, f"{name}: no slider"
    for c in sliders:
        # Chromium's DevTools tree leaves its "valuetext" property empty even where the
        # platform tree says aria-valuetext, so the attribute itself is read
        text = c["valuetext"] or ""
        assert text.startswith(c["readout"]), \
            f"{name}: '{c['label']}' says {text!r}, shows {c['readout']!r}"
        assert not re.search(r"\.\d{5,}", text), f"{name}: float noise in {text!r}"
        unit = _UNIT.search(c["label"])
        if unit:
            want = unit.group(1) or "degrees"
            assert text.endswith(" " + want), f"{name}: '{c['label']}' says {text!r}, no unit"


def test_the_chosen_toggle_is_exposed(ran):
    """ToggleButtons (q4's spline kind and end rule): the chosen button is pressed in the
    accessibility tree, the others not, and a key press moves the pressed state."""
    name, page = ran
    out = _explorer(page)
    toggles = [(c, ax) for c, ax in _controls(page, out) if c["toggle"]]
    if not toggles:
        pytest.skip(f"{name}: no toggle buttons")
    for c, ax in toggles:
        assert ax.get("pressed") == ("true" if c["pressed"] else "false"), (c, ax)
    assert out.locator(".widget-toggle-buttons[role=group][aria-label]").count() >= 1
    first_off = next(c for c, _ in toggles if not c["pressed"])
    out.locator(f'[data-a11y-ctl="{first_off["i"]}"]').focus()
    page.keyboard.press("Space")
    cdp = page.context.new_cdp_session(page)
    deadline = time.monotonic() + 10
    while _ax_node(page, cdp, first_off["i"]).get("pressed") != "true":
        assert time.monotonic() < deadline, f"{name}: the chosen toggle is not exposed as pressed"
        time.sleep(0.2)


def test_arrow_keys_stay_in_the_explorer(ran):
    """ArrowUp/Down on the closed "move" drop-down (q4, q6) change its choice and leave the
    focus on it (not JupyterLab's move to another cell); the same for a slider's handle."""
    name, page = ran
    out = _explorer(page)
    selects = out.locator("select")
    targets = ([selects.first] if selects.count() else []) + [out.locator("[role=slider]").first]
    value = "el => el.tagName === 'SELECT' ? el.value : el.getAttribute('aria-valuenow')"
    for target in targets:
        target.focus()
        seen = {target.evaluate(value)}
        # one of the two keys moves a drop-down whatever its choice; on a slider (moved by
        # arrows in test_explorer_by_keyboard_only) Up/Down must not take the focus away
        keys = ("ArrowUp", "ArrowDown", "ArrowDown", "ArrowUp")
        is_select = target.evaluate("el => el.tagName === 'SELECT'")
        for key in keys:
            page.keyboard.press(key)
            assert target.evaluate("el => document.activeElement === el"), \
                f"{name}: {key} took the focus out of the explorer ({_focused(page)})"
            deadline = time.monotonic() + 3
            while is_select and len(seen) < 2 and time.monotonic() < deadline:
                seen.add(target.evaluate(value))
                time.sleep(0.1)
        assert len(seen) >= 2 or not is_select, f"{name}: the arrow keys did not change {seen}"
