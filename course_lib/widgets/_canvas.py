"""The explorers' figure in the browser: a ``<canvas>`` that paints the kernel's scenes.

:class:`FigureCanvas` is an `anywidget <https://anywidget.dev>`_ widget (JupyterLab, Notebook 7,
VS Code, Colab). The kernel sends it two things:

* ``background``: a PNG of the figure without its changing artists (axes, ticks, labels,
  grids), drawn by Agg when the figure's geometry changes (rarely: a new axis range);
* ``scene``: every changing artist as vector paths, markers and images in display pixels
  (:mod:`course_lib.widgets._scene`), sent after each update, a few kB.

The page paints the background and then the scene in one JavaScript task, so the browser never
shows a half-drawn frame; a scene that arrives before a new background is decoded waits for it.
Mouse presses, drags and releases on the canvas go back to the kernel as matplotlib mouse
events (the spline explorer's draggable points use them). The canvas has ``devicePixelRatio``
times as many pixels as its CSS size, so figures are sharp on high-density screens.
"""

from __future__ import annotations

import anywidget
import traitlets

__all__ = ["FigureCanvas"]

_ESM = r"""
const MOVETO = 1, LINETO = 2, CURVE3 = 3, CURVE4 = 4, CLOSEPOLY = 79;

function unpack(view) {
  const bytes = new Uint8Array(view.buffer, view.byteOffset, view.byteLength);
  if (bytes.length < 8 || String.fromCharCode(...bytes.subarray(0, 4)) !== "4F9S") return null;
  const dv = new DataView(view.buffer, view.byteOffset, view.byteLength);
  const n = dv.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(bytes.subarray(8, 8 + n)));
  let offset = 8 + n;
  const nv = header.nv;
  const V = new Float32Array(bytes.slice(offset, offset + 8 * nv).buffer);
  offset += 8 * nv;
  const C = bytes.slice(offset, offset + nv);
  offset += nv + ((4 - (nv % 4)) % 4);
  header.V = V; header.C = C; header.images = bytes.subarray(offset);
  return header;
}

// A Path2D of vertices [start, start + count) of (V, C); y -> y0 + sy * y.
function tracePath(V, C, ref, y0, sy) {
  const p = new Path2D();
  const [start, count] = ref;
  const end = start + count;
  for (let i = start; i < end;) {
    const c = C[i], x = V[2 * i], y = y0 + sy * V[2 * i + 1];
    if (c === MOVETO) { p.moveTo(x, y); i += 1; }
    else if (c === LINETO) { p.lineTo(x, y); i += 1; }
    else if (c === CURVE3 && i + 1 < end) {
      p.quadraticCurveTo(x, y, V[2 * i + 2], y0 + sy * V[2 * i + 3]); i += 2;
    } else if (c === CURVE4 && i + 2 < end) {
      p.bezierCurveTo(x, y, V[2 * i + 2], y0 + sy * V[2 * i + 3],
                      V[2 * i + 4], y0 + sy * V[2 * i + 5]); i += 3;
    } else if (c === CLOSEPOLY) { p.closePath(); i += 1; }
    else { i += 1; }
  }
  return p;
}

function hatchPattern(ctx, scene, hatch, ref, cache) {
  const key = JSON.stringify(hatch);
  if (!cache.has(key)) {
    const size = Math.max(1, Math.round(hatch.size));
    const tile = document.createElement("canvas");
    tile.width = tile.height = size;
    const t = tile.getContext("2d");
    t.strokeStyle = hatch.color || "black";
    t.lineWidth = hatch.lw;
    t.stroke(tracePath(scene.V, scene.C, ref, size, -1));
    cache.set(key, ctx.createPattern(tile, "repeat"));
  }
  return cache.get(key);
}

function applyClip(ctx, scene, index, H) {
  if (index === null || index === undefined) return;
  const clip = scene.clips[index];
  if (clip.rect) {
    const [x, y, w, h] = clip.rect;
    const r = new Path2D();
    r.rect(x, H - y - h, w, h);
    ctx.clip(r);
  }
  if (clip.v) ctx.clip(tracePath(scene.V, scene.C, clip.v, H, -1));
}

function paintShape(ctx, scene, item, shape, hatches) {
  if (item.fill) {
    ctx.fillStyle = item.fill; ctx.fill(shape);
    if (item.aa === false && !item.stroke) {   // no antialiasing asked (a colour bar's cells):
      ctx.strokeStyle = item.fill;             // a canvas always smooths edges, so cover the
      ctx.lineWidth = 1; ctx.setLineDash([]);  // seams between neighbours with their colour
      ctx.stroke(shape);
    }
  }
  if (item.hatch) {
    ctx.fillStyle = hatchPattern(ctx, scene, item.hatch, item.hv, hatches);
    ctx.fill(shape);
  }
  if (item.stroke && item.lw > 0) {
    ctx.strokeStyle = item.stroke;
    ctx.lineWidth = item.lw;
    ctx.lineCap = item.cap;
    ctx.lineJoin = item.join;
    if (item.dash) { ctx.lineDashOffset = item.dash[0]; ctx.setLineDash(item.dash.slice(1)); }
    else ctx.setLineDash([]);
    ctx.stroke(shape);
  }
}

function paintScene(ctx, scene, scratch, hatches) {
  const H = scene.height;
  for (const item of scene.items) {
    ctx.save();
    applyClip(ctx, scene, item.clip, H);
    if (item.k === "path") {
      paintShape(ctx, scene, item, tracePath(scene.V, scene.C, item.v, H, -1), hatches);
    } else if (item.k === "paths") {          // a collection: one colour per path
      let start = item.v[0];
      const one = {lw: item.lw, cap: item.cap, join: item.join, aa: item.aa};
      for (let i = 0; i < item.n.length; i++) {
        const shape = tracePath(scene.V, scene.C, [start, item.n[i]], H, -1);
        start += item.n[i];
        one.fill = item.fills.length ? item.fills[i % item.fills.length] : null;
        one.stroke = item.strokes.length ? item.strokes[i % item.strokes.length] : null;
        paintShape(ctx, scene, one, shape, hatches);
      }
    } else if (item.k === "markers") {
      const marker = tracePath(scene.V, scene.C, item.v, 0, -1);
      const [start, count] = item.at;
      for (let i = start; i < start + count; i++) {
        ctx.setTransform(1, 0, 0, 1, scene.V[2 * i], H - scene.V[2 * i + 1]);
        paintShape(ctx, scene, item, marker, hatches);
      }
    } else if (item.k === "image") {
      const n = item.w * item.h;
      let data;
      if (item.gray) {                        // one grey byte per pixel: expand to RGBA
        const grey = scene.images.subarray(item.o, item.o + n);
        const rgba = new Uint32Array(n);
        for (let i = 0; i < n; i++) rgba[i] = 0xff000000 | (grey[i] * 0x010101);
        data = new Uint8ClampedArray(rgba.buffer);
      } else {
        data = new Uint8ClampedArray(scene.images.slice(item.o, item.o + 4 * n).buffer);
      }
      scratch.width = item.w; scratch.height = item.h;
      scratch.getContext("2d").putImageData(new ImageData(data, item.w, item.h), 0, 0);
      const [a, b, c, d, e, f] = item.m;      // image pixels -> display -> canvas (y down)
      ctx.setTransform(a, -b, c, -d, e, H - f);
      ctx.imageSmoothingEnabled = item.smooth;
      ctx.imageSmoothingQuality = "high";
      ctx.drawImage(scratch, 0, 0);
    }
    ctx.restore();
  }
}

// Accessibility of the explorer around the canvas: ipywidgets 8 gives a slider's handle (a
// noUiSlider <div role="slider">) no accessible name, and an HTML readout no live region. The
// controls are ipywidgets' own views, so the names are set here, on the explorer's outermost
// widget box, and again whenever its views re-render (a MutationObserver).

// A label's text as a name: ipywidgets writes a missing tooltip into `title` as the string
// "null", and an empty description as a zero-width space; neither is a name.
function labelName(label, useTitle) {
  if (!label) return "";
  const clean = (s) => (s || "").replace(/[\u200b\u200c\u200d\ufeff]/g, "").trim();
  const title = useTitle ? clean(label.title) : "";
  return title && title !== "null" && title !== "undefined" ? title : clean(label.textContent);
}

// The unit a screen reader says after a slider's value, read from its description: the last
// "(...)" when it is a unit (short, or with a "/" or a digit: "mm", "m/s", "MHz"), not a word
// that names the quantity ("exponent", "ambient"); or a trailing degree sign.
function unitOf(description) {
  if (/°\s*$/.test(description)) return "degrees";
  const m = /\(([^()]*)\)\s*$/.exec(description);
  if (!m) return "";
  const inside = m[1].trim();
  return inside.length <= 3 || /[\/\d]/.test(inside) ? inside : "";
}

// aria-valuetext: the readout as shown (rounded as the readout rounds it; a log slider's
// readout is the value, not its logarithm) with the unit. Hooked on noUiSlider's own "update"
// event, which runs after ipywidgets' handler has rewritten the readout and after noUiSlider
// has written its raw number, so the text is current as the value is announced.
function speakValues(slider, handles) {
  const readout = slider.querySelector(".widget-readout");
  const description = labelName(slider.querySelector(".widget-label"), false);
  const unit = unitOf(description);
  const text = () => {
    const shown = readout ? readout.textContent.trim() : "";
    return shown && unit ? `${shown} ${unit}` : shown;
  };
  const sync = () => {
    const t = text();
    if (!t) return;
    for (const h of handles) if (h.getAttribute("aria-valuetext") !== t) h.setAttribute("aria-valuetext", t);
  };
  const target = slider.querySelector(".noUi-target");
  const api = target && target.noUiSlider;
  if (api && !api.courseSpoken) {
    api.courseSpoken = true;
    api.on("update.coursea11y", sync);
  }
  sync();
}

function nameSliders(root) {
  for (const slider of root.querySelectorAll(".widget-slider")) {
    const label = slider.querySelector(".widget-label");
    // the slider's tooltip (ipywidgets puts it on the label) when it has one: a fuller name
    const name = labelName(label, true);
    if (!name) continue;
    const handles = slider.querySelectorAll(".noUi-handle, [role=slider]");
    for (const handle of handles)
      if (handle.getAttribute("aria-label") !== name) handle.setAttribute("aria-label", name);
    const readout = slider.querySelector(".widget-readout");
    if (readout) {
      if (readout.getAttribute("aria-label") !== `${name}, value`)
        readout.setAttribute("aria-label", `${name}, value`);
      // the value box stays editable by mouse; for the keyboard the handle (arrows, Page
      // Up/Down, Home, End) sets the same value, so the box is not a second Tab stop
      if (readout.getAttribute("tabindex") !== "-1") readout.setAttribute("tabindex", "-1");
    }
    speakValues(slider, handles);
  }
}

// ToggleButtons: which option is chosen is shown only by a class; say it with aria-pressed,
// and name the group by its description.
function markToggles(root) {
  for (const group of root.querySelectorAll(".widget-toggle-buttons")) {
    const name = labelName(group.querySelector(":scope > .widget-label"), false);
    if (group.getAttribute("role") !== "group") group.setAttribute("role", "group");
    if (name && group.getAttribute("aria-label") !== name) group.setAttribute("aria-label", name);
    for (const b of group.querySelectorAll("button")) {
      const pressed = b.classList.contains("mod-active") ? "true" : "false";
      if (b.getAttribute("aria-pressed") !== pressed) b.setAttribute("aria-pressed", pressed);
    }
  }
}

function nameControls(root) {
  nameSliders(root);
  markToggles(root);
  // other inputs beside a description (a colour picker's <input type="color">, ...); a
  // checkbox inside its own <label> is named by that label already
  for (const box of root.querySelectorAll(".widget-inline-hbox")) {
    const label = box.querySelector(":scope > .widget-label");
    const name = labelName(label, false);
    for (const input of box.querySelectorAll("input, select, textarea")) {
      if (input.closest("label") || (input.id && label && label.htmlFor === input.id)) {
        if (/^[\s\u200b]*$/.test(input.getAttribute("aria-label") || "x"))
          input.removeAttribute("aria-label");
        continue;
      }
      if (name && !input.getAttribute("aria-label")) input.setAttribute("aria-label", name);
    }
  }
  // an icon-font glyph (Font Awesome's private-use character) is no part of a button's name
  for (const icon of root.querySelectorAll("button i, button .fa"))
    if (icon.getAttribute("aria-hidden") !== "true") icon.setAttribute("aria-hidden", "true");
  for (const live of root.querySelectorAll(".course-live"))
    if (live.getAttribute("aria-live") !== "polite") {
      live.setAttribute("aria-live", "polite"); live.setAttribute("role", "status");
    }
}

// Arrow keys and their kin belong to the focused control (a slider, a closed drop-down, a
// text box): JupyterLab's notebook would otherwise take them to move to another cell.
const KEPT_KEYS = new Set(["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", "PageUp",
                           "PageDown", "Home", "End"]);
function keepKeys(root) {
  if (root.courseKeysKept) return;
  root.courseKeysKept = true;
  root.addEventListener("keydown", (e) => { if (KEPT_KEYS.has(e.key)) e.stopPropagation(); });
}

function explorerRoot(el) {
  let root = el.parentElement || el;
  for (let p = el.parentElement; p; p = p.parentElement)
    if (p.classList.contains("widget-box") || p.classList.contains("widget-container")) root = p;
  return root;
}

function watchControls(el) {
  let observer = null, tries = 0, pending = false;
  const attach = () => {
    if (!el.isConnected) { if (tries++ < 200) setTimeout(attach, 50); return; }
    const root = explorerRoot(el);
    keepKeys(root);
    nameControls(root);
    // readouts change with every frame: look again once they have settled, not per change
    observer = new MutationObserver(() => {
      markToggles(root);        // a chosen option is said at once, not a moment later
      if (pending) return;
      pending = true;
      setTimeout(() => { pending = false; nameControls(root); }, 100);
    });
    observer.observe(root, {childList: true, subtree: true, attributes: true,
                            attributeFilter: ["class"]});
  };
  attach();
  return () => { if (observer) observer.disconnect(); tries = 1e9; };
}

function render({ model, el }) {
  const canvas = document.createElement("canvas");
  canvas.className = "course-figure-canvas";
  canvas.style.display = "block";
  canvas.style.touchAction = "none";
  // the figure's text alternative, written by the kernel from the figure's data every frame
  canvas.setAttribute("role", "img");
  const describe = () => canvas.setAttribute("aria-label", model.get("alt") || "figure");
  describe();
  model.on("change:alt", describe);
  const unwatch = watchControls(el);
  // a figure with a 3-D view: a Tab stop whose arrow keys turn the view (as dragging does)
  const keyable = () => {
    if (model.get("turnable")) {
      canvas.tabIndex = 0;
      canvas.setAttribute("aria-keyshortcuts", "ArrowLeft ArrowRight ArrowUp ArrowDown");
    } else { canvas.removeAttribute("tabindex"); canvas.removeAttribute("aria-keyshortcuts"); }
  };
  keyable();
  model.on("change:turnable", keyable);
  canvas.addEventListener("keydown", (e) => {
    if (!model.get("turnable") || !e.key.startsWith("Arrow")) return;
    e.preventDefault(); e.stopPropagation();   // not JupyterLab's move to another cell
    model.send({type: "key", key: e.key, shift: e.shiftKey});
  });
  el.classList.add("course-figure");
  el.appendChild(canvas);
  const ctx = canvas.getContext("2d");
  const scratch = document.createElement("canvas");
  const hatches = new Map();
  let background = null, backgroundBytes = null, loading = null;

  function paint() {
    const bytes = model.get("background");
    if (bytes !== backgroundBytes) {       // a new background: decode it, then paint
      backgroundBytes = bytes;
      if (!bytes || bytes.byteLength === 0) { background = null; loading = null; return paint(); }
      const blob = new Blob([new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength)],
                            {type: "image/png"});
      const mine = loading = createImageBitmap(blob).then((bitmap) => {
        if (loading !== mine) return;
        background = bitmap; loading = null; paint();
      }).catch(() => {
        if (loading === mine) { loading = null; background = null; paint(); }
      });
      return;
    }
    if (loading) return;                   // the frame waits for its background
    const tStart = performance.now();
    const scene = unpack(model.get("scene"));
    const ratio = model.get("ratio") || 1;
    const w = model.get("width"), h = model.get("height");
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w; canvas.height = h;
      // the figure's size, shrunk (aspect kept) to a narrower notebook: never cut off
      canvas.style.width = `${w / ratio}px`; canvas.style.maxWidth = "100%";
      canvas.style.height = "auto";
    }
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, w, h);
    if (background) ctx.drawImage(background, 0, 0);
    if (scene) paintScene(ctx, scene, scratch, hatches);
    canvas.dataset.frame = String(model.get("frame"));
    (window.__cfT ||= []).push([tStart, performance.now()]);
  }

  // the mouse, as matplotlib events (display pixels from the bottom-left corner)
  let pressed = false, pendingMove = null;
  const where = (e) => {
    const r = canvas.getBoundingClientRect();
    const sx = canvas.width / r.width, sy = canvas.height / r.height;
    return [(e.clientX - r.left) * sx, canvas.height - (e.clientY - r.top) * sy];
  };
  const send = (name, e, button) => {     // one drag move per animation frame at most
    const [x, y] = where(e);
    model.send({type: "mouse", name, x, y, button: button || e.button + 1});
  };
  canvas.addEventListener("pointerdown", (e) => {
    pressed = true; canvas.setPointerCapture(e.pointerId); send("button_press_event", e);
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!pressed) return;
    if (pendingMove === null) requestAnimationFrame(() => {
      const ev = pendingMove; pendingMove = null;
      if (ev) send("motion_notify_event", ev, 1);
    });
    pendingMove = e;
  });
  const release = (e) => {
    if (!pressed) return;
    pressed = false; pendingMove = null; send("button_release_event", e);
  };
  canvas.addEventListener("pointerup", release);
  canvas.addEventListener("pointercancel", release);

  // every frame the kernel sends moves `frame` (its scene and background, when they changed,
  // arrive in the same message, set before this runs): paint once per frame
  model.on("change:frame", paint);
  model.on("change:ratio", paint);
  paint();
  const ratio = window.devicePixelRatio || 1;
  if (ratio !== model.get("ratio")) model.send({type: "ratio", ratio});
  return () => {
    model.off("change:frame", paint); model.off("change:ratio", paint);
    model.off("change:alt", describe); model.off("change:turnable", keyable); unwatch();
  };
}

export default { render };
"""


class FigureCanvas(anywidget.AnyWidget):
    """A figure painted in the browser: a PNG ``background`` plus a vector ``scene`` on top.

    Attributes
    ----------
    width, height : int
        The canvas' size in pixels (the figure's size at its dpi).
    ratio : float
        Canvas pixels per CSS pixel (the page's ``devicePixelRatio``, reported by the page).
    background : bytes
        PNG of the figure's static part.
    scene : bytes
        The changing artists, packed by :func:`course_lib.widgets._scene.pack`.
    frame : int
        Counts the frames sent (shown by the page as the canvas' ``data-frame``).
    alt : str
        The figure's text alternative (the canvas is ``role="img"`` with it as ``aria-label``),
        written from the figure's data by :func:`course_lib.plots.describe.alt_text`.
    turnable : bool
        The canvas takes the focus and sends its arrow keys to the kernel (a 3-D view, which
        they turn).
    """

    _esm = _ESM
    _css = (".course-figure { line-height: 0; }"
            " .course-figure-canvas:focus-visible { outline: 3px solid #0072b2; }")
    width = traitlets.Int(0).tag(sync=True)
    height = traitlets.Int(0).tag(sync=True)
    ratio = traitlets.Float(1.0).tag(sync=True)
    background = traitlets.Bytes(b"").tag(sync=True)
    scene = traitlets.Bytes(b"").tag(sync=True)
    frame = traitlets.Int(0).tag(sync=True)
    alt = traitlets.Unicode("").tag(sync=True)
    turnable = traitlets.Bool(False).tag(sync=True)

    def show(self, *, scene: bytes, size: tuple[int, int], background: bytes | None = None):
        """Send one frame (and a new background, if given) in one message."""
        with self.hold_sync():
            self.width, self.height = int(size[0]), int(size[1])
            if background is not None:
                self.background = background
            self.scene = scene
            self.frame += 1
