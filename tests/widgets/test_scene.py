"""The scene renderer of the browser-painted explorers (issue 15): what it records is where
matplotlib puts it.

Oracles, all independent of :mod:`course_lib.widgets._scene`: the axes' own data-to-display
transform (``ax.transData``), the unit conversion points -> pixels (``dpi / 72``),
``matplotlib.colors.to_rgba`` for colours, matplotlib's rcParams for dash patterns, the text
extents and the pixels of a full Agg draw of the same figure (``fig.canvas.buffer_rgba()``),
and the byte layout of a packed scene as its docstring specifies it.
"""

from __future__ import annotations

import json
import re
import struct

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.patches import Circle, Polygon, Rectangle  # noqa: E402
from matplotlib.path import Path  # noqa: E402

from course_lib.widgets._scene import SceneRenderer, pack, unpack  # noqa: E402

DPI = 100.0
PX_PER_PT = DPI / 72.0


@pytest.fixture
def fig():
    figure = plt.figure(figsize=(4, 3), dpi=DPI)
    yield figure
    plt.close(figure)


@pytest.fixture
def ax(fig):
    axes = fig.add_axes([0.12, 0.15, 0.8, 0.75])
    axes.set_xlim(-0.5, 3.5)
    axes.set_ylim(-1.5, 1.5)
    return axes


def record(fig, *artists) -> tuple[SceneRenderer, list[dict]]:
    """A full Agg draw of ``fig`` (the metrics), then the items ``artists`` record."""
    fig.canvas.draw()
    scene = SceneRenderer(fig.canvas.get_renderer())
    for artist in artists:
        artist.draw(scene)
    return scene, scene.items


def css_rgba(css: str) -> np.ndarray:
    """``rgba(r,g,b,a)`` as four floats in [0, 1]."""
    m = re.fullmatch(r"rgba\((\d+),(\d+),(\d+),([0-9.eE+-]+)\)", css)
    assert m, f"not a CSS rgba() colour: {css!r}"
    r, g, b, a = (float(v) for v in m.groups())
    return np.array([r / 255, g / 255, b / 255, a])


def assert_colour(css, colour, alpha=None):
    expected = np.array(to_rgba(colour, alpha))
    np.testing.assert_allclose(css_rgba(css), expected, atol=0.5 / 255 + 1e-4)


def extents(item) -> np.ndarray:
    """``[x0, y0, x1, y1]`` of a recorded path (its curves, not the CLOSEPOLY placeholders)."""
    return np.array(Path(item["v"].astype(float), item["c"]).get_extents().extents)


# -- lines and markers ------------------------------------------------------------------------

def test_line_vertices_width_dashes_and_colour(fig, ax):
    x = np.linspace(0.0, 3.0, 25)
    y = np.sin(2 * x)                       # not rectilinear: no pixel snapping
    (line,) = ax.plot(x, y, lw=2.5, ls="--", color="C1", alpha=0.6)
    _, items = record(fig, line)
    assert len(items) == 1
    item = items[0]
    assert item["k"] == "path" and item["v"].dtype == np.float32
    np.testing.assert_allclose(item["v"], ax.transData.transform(np.c_[x, y]), atol=1e-3)
    assert item["c"][0] == Path.MOVETO and np.all(item["c"][1:] == Path.LINETO)
    assert item["lw"] == pytest.approx(2.5 * DPI / 72)
    # dashes: rcParams' dash pattern, scaled by the line width (lines.scale_dashes), in pixels
    on, off = matplotlib.rcParams["lines.dashed_pattern"]
    assert matplotlib.rcParams["lines.scale_dashes"]
    np.testing.assert_allclose(item["dash"], [0.0, on * 2.5 * PX_PER_PT, off * 2.5 * PX_PER_PT],
                               rtol=1e-9, atol=1e-9)
    assert_colour(item["stroke"], "C1", alpha=0.6)
    assert item["fill"] is None


def test_solid_line_has_no_dashes(fig, ax):
    (line,) = ax.plot([0.1, 1.3, 2.9], [0.2, -0.7, 1.1], lw=1.0, color="#123456")
    _, (item,) = record(fig, line)
    assert item["dash"] is None
    assert item["lw"] == pytest.approx(PX_PER_PT)
    assert_colour(item["stroke"], "#123456")


def test_markers_at_the_data_and_nan_points_dropped(fig, ax):
    x = np.linspace(0.0, 3.0, 12)
    y = np.cos(x)
    y[[2, 7]] = np.nan
    (dots,) = ax.plot(x, y, "o", ms=9, mfc="tab:red", mec="navy", mew=1.5)
    _, items = record(fig, dots)
    assert [i["k"] for i in items] == ["markers"]
    item = items[0]
    finite = np.isfinite(y)
    np.testing.assert_allclose(item["at"], ax.transData.transform(np.c_[x, y][finite]),
                               atol=1e-3)
    assert len(item["at"]) == 10
    # the marker: a circle of diameter ms points, relative to each offset
    x0, y0, x1, y1 = extents(item)
    radius = 9 / 2 * PX_PER_PT
    np.testing.assert_allclose([x0, y0, x1, y1], [-radius, -radius, radius, radius], atol=0.05)
    assert_colour(item["fill"], "tab:red")
    assert_colour(item["stroke"], "navy")
    assert item["lw"] == pytest.approx(1.5 * PX_PER_PT)


def one_pixel_line(fig, x, y):
    """A black 1 px line (0.72 pt at 100 dpi) through data ``x, y`` of a full-figure axes
    with unit limits, and the figure's Agg buffer (grey levels) once drawn."""
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.set_axis_off()
    (line,) = ax.plot(x, y, lw=72 / DPI, color="k", solid_capstyle="butt")
    _, (item,) = record(fig, line)
    grey = np.asarray(fig.canvas.buffer_rgba())[..., 0].astype(int)
    return item, grey


def test_snapped_vertical_line_is_on_the_column_agg_paints(fig):
    item, grey = one_pixel_line(fig, [0.4371, 0.4371], [0.1, 0.9])
    column = int(np.argmin(grey[150]))          # Agg's darkest column on row 150
    assert grey[150, column] < 60
    # the column's centre, in display pixels, is where the recorded (snapped) stroke runs
    np.testing.assert_allclose(item["v"][:, 0], column + 0.5, atol=0.25)


@pytest.mark.parametrize("y", [0.3137, 0.5, 0.7761])
def test_snapped_horizontal_line_is_on_the_row_agg_paints(fig, y):
    item, grey = one_pixel_line(fig, [0.1, 0.9], [y, y])
    height = grey.shape[0]
    row = int(np.argmin(grey[:, 200]))          # Agg's darkest row on column 200 (from the top)
    assert grey[row, 200] < 60
    np.testing.assert_allclose(item["v"][:, 1], height - row - 0.5, atol=0.25)


# -- patches ----------------------------------------------------------------------------------

def test_filled_polygon_vertices_and_colour(fig, ax):
    corners = np.array([[0.2, -1.0], [2.7, -0.4], [1.9, 1.2], [0.4, 0.6]])
    poly = Polygon(corners, closed=True, fc="tab:purple", ec="none", alpha=0.4)
    ax.add_patch(poly)
    _, (item,) = record(fig, poly)
    corner_codes = item["c"] != Path.CLOSEPOLY
    np.testing.assert_allclose(item["v"][corner_codes][:4], ax.transData.transform(corners),
                               atol=1e-3)
    assert item["c"][-1] == Path.CLOSEPOLY
    assert_colour(item["fill"], "tab:purple", alpha=0.4)
    assert item["stroke"] is None and item["hatch"] is None


def test_hatched_rectangle(fig, ax):
    rect = Rectangle((0.5, -1.0), 2.0, 1.2, fc="lightyellow", ec="k", hatch="//",
                     hatchcolor="tab:blue")
    ax.add_patch(rect)
    _, (item,) = record(fig, rect)
    corners = ax.transData.transform([[0.5, -1.0], [2.5, -1.0], [2.5, 0.2], [0.5, 0.2]])
    drawn = item["v"][item["c"] != Path.CLOSEPOLY]
    # a rectilinear path is snapped to the pixel grid, as Agg snaps it: within a pixel
    np.testing.assert_allclose(drawn[:4], corners, atol=1.0)
    assert_colour(item["fill"], "lightyellow")
    assert_colour(item["stroke"], "k")
    hatch = item["hatch"]
    assert hatch is not None
    assert hatch["size"] == pytest.approx(DPI)            # one hatch tile per inch
    assert_colour(hatch["color"], "tab:blue")
    assert hatch["lw"] == pytest.approx(matplotlib.rcParams["hatch.linewidth"] * PX_PER_PT)
    # "/" hatching: segments of slope +1 (MOVETO, LINETO pairs), two per tile for "//"
    v, c = hatch["v"], hatch["c"]
    assert np.all(c[0::2] == Path.MOVETO) and np.all(c[1::2] == Path.LINETO)
    d = v[1::2] - v[0::2]
    np.testing.assert_allclose(d[:, 0], d[:, 1], atol=1e-3)
    assert np.all(d[:, 0] > 0)
    # the lines cross the tile's diagonal band: some of them pass through its inside
    assert np.any((v[:, 0] > 0) & (v[:, 0] < DPI))


# -- text -------------------------------------------------------------------------------------

@pytest.mark.parametrize("rotation", [0, 90])
def test_text_outline_fills_its_window_extent(fig, rotation):
    """The glyph outlines cover the box matplotlib lays the text out in (Agg's metrics).
    "depth (mm)" has ascenders and descenders, so ink reaches the box's top and bottom."""
    text = fig.text(0.3, 0.4, "depth (mm)", fontsize=10, rotation=rotation, color="darkred")
    _, (item,) = record(fig, text)
    box = text.get_window_extent(fig.canvas.get_renderer()).extents
    np.testing.assert_allclose(extents(item), box, atol=2.0)
    assert_colour(item["fill"], "darkred")
    assert item["stroke"] is None


def agg_ink_extents(fig) -> np.ndarray:
    """``[x0, y0, x1, y1]`` in display pixels of the pixels of the Agg buffer that black ink
    covers by half or more (the antialiased fringe beyond the outline is fainter)."""
    rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    rows, cols = np.nonzero((rgb < 128).all(axis=-1))
    height = rgb.shape[0]
    return np.array([cols.min(), height - 1 - rows.max(), cols.max() + 1, height - rows.min()],
                    dtype=float)


@pytest.mark.parametrize("rotation", [0, 30, 90, -45])
def test_text_outline_covers_the_pixels_agg_paints(fig, rotation):
    """Rotated text too: the outline's bounds are those of the ink of a full Agg draw."""
    text = fig.text(0.35, 0.35, "Slope (mm)", fontsize=10, rotation=rotation, color="k")
    _, (item,) = record(fig, text)
    np.testing.assert_allclose(extents(item), agg_ink_extents(fig), atol=2.0)


def test_long_text_ends_where_agg_ends_it(fig):
    text = fig.text(0.05, 0.5, "m" * 15, fontsize=10)
    _, (item,) = record(fig, text)
    np.testing.assert_allclose(extents(item)[[0, 2]], agg_ink_extents(fig)[[0, 2]], atol=2.0)


# -- images -----------------------------------------------------------------------------------

CELL_COLOURS = np.array([[[230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200]],
                         [[245, 130, 48], [145, 30, 180], [70, 240, 240], [240, 50, 230]],
                         [[210, 245, 60], [250, 190, 212], [0, 128, 128], [170, 110, 40]]],
                        dtype=np.uint8)


@pytest.mark.parametrize("origin, extent", [
    ("upper", (0.0, 8.0, 0.0, 3.0)),
    ("lower", (0.0, 8.0, 0.0, 3.0)),
    ("upper", (1.0, 3.0, 5.0, -2.0)),       # y extent top to bottom, like the clipping explorer
    ("lower", (-4.0, 2.0, 10.0, 0.0)),
])
def test_axes_image_matrix_maps_pixels_onto_the_cells_agg_paints(fig, origin, extent):
    ax = fig.add_axes([0.1, 0.1, 0.8, 0.8])
    image = ax.imshow(CELL_COLOURS, origin=origin, extent=extent, aspect="auto",
                      interpolation="nearest")
    fig.canvas.draw()
    agg = np.asarray(fig.canvas.buffer_rgba())[..., :3]
    height = agg.shape[0]
    scene = SceneRenderer(fig.canvas.get_renderer())
    scene.draw_axes_image(image)
    (item,) = scene.items
    assert item["k"] == "image" and item["smooth"] is False
    rgba = item["rgba"]
    h, w = rgba.shape[:2]
    assert (h, w) == CELL_COLOURS.shape[:2]
    a, b, c, d, e, f = item["m"]
    for v in range(h):            # v: image row, top row first (as the browser reads it)
        for u in range(w):
            colour = rgba[v, u, :3]
            x, y = a * (u + 0.5) + c * (v + 0.5) + e, b * (u + 0.5) + d * (v + 0.5) + f
            rows, cols = np.nonzero((agg == colour).all(axis=-1))
            assert rows.size, f"colour {colour} of image pixel ({u}, {v}) is not in Agg's draw"
            # the block Agg paints for this cell, in display pixels (origin bottom-left)
            x0, x1 = cols.min(), cols.max() + 1
            y0, y1 = height - 1 - rows.max(), height - rows.min()
            assert x0 <= x <= x1 and y0 <= y <= y1, (
                f"image pixel ({u}, {v}) maps to ({x:.1f}, {y:.1f}), outside Agg's block "
                f"x {x0}..{x1}, y {y0}..{y1} of its colour {colour}")
            # and near its middle (the cells are 40 x 80 px or more)
            assert abs(x - (x0 + x1) / 2) <= 1.5 and abs(y - (y0 + y1) / 2) <= 1.5
    # the image's corners are the extent's corners
    corners = np.array([[a * u + c * v + e, b * u + d * v + f] for u, v in [(0, 0), (w, h)]])
    left, right, bottom, top = extent
    if origin == "lower":
        bottom, top = top, bottom  # the first data row is at the `bottom` edge: shown last
    expected = ax.transData.transform([[left, top], [right, bottom]])
    np.testing.assert_allclose(corners, expected, atol=1e-6)


def test_axes_image_keeps_the_data_resolution_and_smooths_when_asked(fig):
    ax = fig.add_axes([0.1, 0.1, 0.8, 0.8])
    data = np.linspace(0.0, 1.0, 7 * 5).reshape(5, 7)
    image = ax.imshow(data, cmap="gray", interpolation="bilinear", aspect="auto")
    fig.canvas.draw()
    scene = SceneRenderer(fig.canvas.get_renderer())
    scene.draw_axes_image(image)
    (item,) = scene.items
    # an opaque grey image goes as one byte per pixel
    assert item["rgba"].shape == (5, 7) and item["smooth"] is True
    # the colour of each pixel is the colormap's at the data value (origin upper: row 0 on top)
    expected = (np.asarray(plt.get_cmap("gray")(data)) * 255)[..., 0]
    np.testing.assert_allclose(item["rgba"], expected, atol=1.0)
    coloured = ax.imshow(data, cmap="viridis", interpolation="nearest", aspect="auto")
    scene.items = []
    scene.draw_axes_image(coloured)
    (item,) = scene.items
    assert item["rgba"].shape == (5, 7, 4) and item["smooth"] is False
    expected = (np.asarray(plt.get_cmap("viridis")(data)) * 255)[..., :3]
    np.testing.assert_allclose(item["rgba"][..., :3], expected, atol=1.0)


# -- clips ------------------------------------------------------------------------------------

def test_clipped_artist_carries_the_axes_box(fig, ax):
    (inside,) = ax.plot([0, 1, 2], [0.1, 0.9, -0.3], color="k")
    (free,) = ax.plot([0, 1, 2], [0.2, 0.8, -0.2], color="k", clip_on=False)
    scene, (clipped, unclipped) = record(fig, inside, free)
    assert unclipped["clip"] is None
    clip = scene.clips[clipped["clip"]]
    np.testing.assert_allclose(clip["rect"], ax.bbox.bounds, atol=1e-3)


def test_clip_path_recorded_in_display_pixels(fig, ax):
    disc = Circle((1.5, 0.0), 1.0, transform=ax.transData)
    (line,) = ax.plot([0, 1, 2, 3], [1, -1, 1, -1], color="k")
    line.set_clip_path(disc)
    scene, (item,) = record(fig, line)
    clip = scene.clips[item["clip"]]
    expected = disc.get_path().transformed(disc.get_transform()).get_extents().extents
    got = Path(clip["v"].astype(float), clip["c"]).get_extents().extents
    np.testing.assert_allclose(got, expected, atol=1e-2)


def test_equal_clips_are_stored_once(fig, ax):
    lines = [ax.plot([0, 3], [k / 10, -k / 10])[0] for k in range(4)]
    scene, items = record(fig, *lines)
    assert len(scene.clips) == 1 and {i["clip"] for i in items} == {0}


# -- one message --------------------------------------------------------------------------------

def a_scene(fig, ax):
    """A scene with a line, markers, a hatched patch, text, an image and two clip regions."""
    (line,) = ax.plot([0, 1, 2, 3], [0.5, -0.5, 1.0, 0.0], "--", color="C0")
    (dots,) = ax.plot([0.5, 1.5, 2.5], [0.3, 0.2, -0.4], "s", color="C3")
    rect = Rectangle((0.2, -1.2), 1.0, 0.5, fc="w", ec="k", hatch="x")
    ax.add_patch(rect)
    label = ax.set_title("Q1(c): B-scan")
    dots.set_clip_path(Circle((1.5, 0.0), 1.0, transform=ax.transData))
    image = ax.imshow(CELL_COLOURS, extent=(0, 1, 0, 1), interpolation="nearest")
    ax.set_xlim(-0.5, 3.5)
    ax.set_ylim(-1.5, 1.5)
    scene, _ = record(fig, line, dots, rect, label)
    scene.draw_axes_image(image)
    return scene


def test_pack_unpack_round_trip(fig, ax):
    scene = a_scene(fig, ax)
    assert {i["k"] for i in scene.items} == {"path", "markers", "image"}
    assert len(scene.clips) == 2
    header = unpack(pack(scene.items, scene.clips, scene.height))
    assert header["height"] == scene.height
    assert len(header["items"]) == len(scene.items)
    for got, sent in zip(header["items"], scene.items):
        lost = {k for k, v in sent.items() if v is not None and not k.startswith("_")} - set(got)
        assert not lost, f"keys lost: {lost}"
        for key, value in sent.items():
            if key.startswith("_"):  # pack's own memo of the item's fixed fields
                continue
            if value is None:      # pack leaves out an absent hatch: the page reads undefined
                assert got.get(key) is None, key
            elif key == "hatch":
                for hk, hv in value.items():
                    np.testing.assert_array_equal(got["hatch"][hk], hv, err_msg=f"hatch {hk}")
            elif isinstance(value, np.ndarray):
                assert got[key].dtype == value.dtype and got[key].shape == value.shape
                np.testing.assert_array_equal(got[key], value, err_msg=key)
            else:
                assert got[key] == value, key
    for got, sent in zip(header["clips"], scene.clips):
        assert got["rect"] == sent["rect"]
        if "v" in sent:
            np.testing.assert_array_equal(got["v"], sent["v"])
            np.testing.assert_array_equal(got["c"], sent["c"])


def test_pack_layout_is_four_byte_aligned(fig, ax):
    """The layout of the docstring: magic, uint32 header length, header padded to 4 bytes,
    float32 vertices, uint8 codes padded to 4 bytes, then the images' RGBA bytes."""
    scene = a_scene(fig, ax)
    message = pack(scene.items, scene.clips, scene.height)
    assert message[:4] == b"4F9S"
    (n,) = struct.unpack_from("<I", message, 4)
    assert (8 + n) % 4 == 0                            # the vertices start 4-byte aligned
    header = json.loads(message[8:8 + n])
    nv = header["nv"]
    image_bytes = sum(i["rgba"].nbytes for i in scene.items if i["k"] == "image")
    codes_end = 8 + n + 8 * nv + nv
    assert (codes_end + (-nv % 4)) % 4 == 0
    assert len(message) == codes_end + (-nv % 4) + image_bytes
    # the image bytes are the last block, in the items' order
    (image,) = [i for i in scene.items if i["k"] == "image"]
    assert message[-image_bytes:] == image["rgba"].tobytes()


def test_empty_scene_round_trip():
    header = unpack(pack([], [], 480.0))
    assert header["items"] == [] and header["clips"] == [] and header["height"] == 480.0
    assert header["nv"] == 0


@pytest.mark.parametrize("message", [b"", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", b"4F9", b"{}"])
def test_unpack_rejects_bytes_that_are_not_a_scene(message):
    with pytest.raises(ValueError, match="message"):
        unpack(message)


@pytest.mark.parametrize("cut", ["magic only", "bad header", "truncated"])
def test_unpack_rejects_a_damaged_scene(fig, ax, cut):
    scene = a_scene(fig, ax)
    whole = pack(scene.items, scene.clips, scene.height)
    message = {"magic only": b"4F9S",
               "bad header": b"4F9S" + struct.pack("<I", 4) + b"{}  ",
               "truncated": whole[:-100]}[cut]
    with pytest.raises(ValueError, match="message"):
        unpack(message)


def test_a_collections_colours_are_each_rows_css_colour():
    """``_css_list`` formats each distinct colour once; the oracle is ``_css`` row by row
    (repeats, transparent rows and a forced alpha included)."""
    from course_lib.widgets._scene import _css, _css_list

    rng = np.random.default_rng(3)
    rows = rng.random((40, 4))
    rows[::5] = rows[1]                      # repeats
    rows[7, 3] = 0.0                         # invisible: None
    for alpha in (None, 0.5):
        assert _css_list(rows, alpha) == [_css(r, alpha) for r in rows]
    assert _css_list(rows[:2]) == [_css(r) for r in rows[:2]]
    assert _css_list(np.zeros((0, 4))) == []


def test_joined_geometry_is_each_paths_geometry_one_after_the_other():
    """Oracle: ``_geometry`` path by path (a polyline without codes, a closed path, a path
    ending in STOP codes, an empty path)."""
    from matplotlib.path import Path

    from course_lib.widgets._scene import _geometry, _joined_geometry

    paths = [Path([[0, 0], [1, 2], [3, 1]]),
             Path.unit_circle(),
             Path([[0, 0], [1, 0], [1, 1], [0, 0]],
                  [Path.MOVETO, Path.LINETO, Path.LINETO, Path.STOP]),
             Path(np.zeros((0, 2)))]
    v, c, counts = _joined_geometry(paths)
    singles = [_geometry(p) for p in paths]
    assert counts == [len(g[0]) for g in singles]
    np.testing.assert_allclose(v, np.concatenate([g[0] for g in singles]), atol=1e-6)
    np.testing.assert_array_equal(c, np.concatenate([g[1] for g in singles]))
