"""Students' written answers in the marker's Formgrader, shown as text and never run.

nbgrader's Formgrader renders every markdown cell of an autograded notebook with nbconvert's
``markdown2html``, which passes raw HTML through, and shows raw cells verbatim. A written
answer holding ``<script>``, ``<img onerror=...>``, ``<style>`` or a ``javascript:`` link
therefore ran in the marker's browser, with the marker's session: a submission could give itself full
marks on answers nobody had read and zeroed classmates' grades that way.

Two layers, both set up for the course by :func:`autograder.course.config_text`:

* :func:`markdown2html` replaces the Formgrader's filter of that name
  (``c.HTMLExporter.filters``): nbconvert renders the markdown exactly as before, then the HTML
  goes through an allow-list (bleach, nbconvert's own sanitiser): formatting, lists, tables,
  links to ``http(s)``/``mailto``/the page itself, and images only as ``data:`` rasters (a
  pasted sketch; an image at any address would be fetched with the marker's session, and
  ``/logout`` logged the marker out). Anything else is escaped, so the marker reads the attempt
  as text. MathJax text (``$...$``) and code blocks come out as nbconvert rendered them (the
  page's MathJax runs with its ``Safe`` extension). An answer that cannot be rendered at all
  (a missing attachment) is shown as its source instead of taking the page down.
* raw cells are not shown as HTML (``c.HTMLExporter.raw_mimetypes = []``), and the grader
  turns a student's raw cell, or one of a type nbformat does not know, into a markdown cell
  quoting it (:func:`quoted_cell`); grading metadata the student put on a cell the course does
  not know is dropped (``gradebook._merge``).
"""

from __future__ import annotations

import base64
import functools
import html
import io
import re

import bleach
from jinja2 import pass_context

from ..cells import join_source

__all__ = ["ALLOWED_TAGS", "clean_html", "comment_html", "markdown2html", "quoted_cell"]

#: HTML that nbconvert's markdown renderer produces for ordinary markdown, and nothing more
ALLOWED_TAGS = frozenset({
    "a", "abbr", "b", "blockquote", "br", "code", "del", "details", "div", "em", "h1", "h2",
    "h3", "h4", "h5", "h6", "hr", "i", "img", "kbd", "li", "ol", "p", "pre", "s", "span",
    "strong", "sub", "summary", "sup", "table", "tbody", "td", "tfoot", "th", "thead", "tr",
    "u", "ul",
})
#: code highlighting's classes only (pygments' token names, ``highlight``, ``hl-python``): a
#: class of the Formgrader's own style sheet (Bootstrap's ``btn``, ``navbar-fixed-top``) could
#: dress an answer as the marking form or pin it over it
_CLASS_TAGS = frozenset({"code", "div", "pre", "span"})
_HIGHLIGHT_CLASS = re.compile(r"^(highlight|hl-[a-z0-9+#-]{1,30})$")
_ATTRIBUTES = {
    "a": {"href", "title"},
    "img": {"src", "alt", "title"},
    "td": {"align", "colspan", "rowspan"}, "th": {"align", "colspan", "rowspan"},
    "ol": {"start"},
}
#: a picture pasted into an answer (an attachment) arrives as one of these data URLs
_RASTER_DATA_URL = re.compile(r"^data:image/(png|jpeg|gif|webp);base64,[A-Za-z0-9+/=\s]*$")
_PROTOCOLS = frozenset({"http", "https", "mailto", "data"})


def _highlight_classes(value: str) -> bool:
    from pygments.token import STANDARD_TYPES

    names = value.split()
    return bool(names) and all(n in STANDARD_TYPES.values() or _HIGHLIGHT_CLASS.match(n)
                               for n in names)


def _allowed_attribute(tag: str, name: str, value: str) -> bool:
    if name == "class":
        return tag in _CLASS_TAGS and _highlight_classes(value)
    if name == "title":
        return True
    if name not in _ATTRIBUTES.get(tag, ()):
        return False
    if tag == "img" and name == "src":
        # only a picture the answer carries: any other address would be fetched with the
        # marker's session (``/logout`` would log the marker out) or tell a site when
        # the marking happens
        return bool(_RASTER_DATA_URL.match(value.strip()))
    if tag == "a" and name == "href" and value.strip().lower().startswith("data:"):
        return False
    return True


def clean_html(html: str) -> str:
    """``html`` with only :data:`ALLOWED_TAGS`, harmless attributes and safe URLs; every other
    tag is escaped (shown as text), comments are dropped.

    Examples
    --------
    >>> clean_html('<p>ok <img src=x onerror="alert(1)"> <script>alert(2)</script></p>')
    '<p>ok <img> &lt;script&gt;alert(2)&lt;/script&gt;</p>'
    """
    if not isinstance(html, str):
        raise ValueError(f"html must be a str, got {type(html).__name__}")
    return bleach.clean(html, tags=ALLOWED_TAGS, attributes=_allowed_attribute,
                        protocols=_PROTOCOLS, strip=False, strip_comments=True)


#: added to every picture *after* cleaning (the student's own styles are gone by then): a pasted
#: picture 4 x 60,000 px pushed the rubric 60,000 px down the page
_PICTURE_STYLE = "max-width: 100%; max-height: 40em; object-fit: contain"


def _fitted_pictures(html_text: str) -> str:
    """Every picture of cleaned HTML at most 40em tall. Only a real tag can start with "<img"
    there: bleach escapes "<" in text and in attribute values (pinned by a test)."""
    return re.sub(r"<img\b", f'<img style="{_PICTURE_STYLE}"', html_text)


@pass_context
def markdown2html(context, source: str) -> str:
    """The Formgrader's ``markdown2html`` filter, sanitised: nbconvert's rendering of
    ``source`` (the cell's attachments resolved as nbconvert does), then :func:`clean_html`."""
    from nbconvert.filters.markdown_mistune import IPythonRenderer, MarkdownWithMath

    cell = context.get("cell", {}) or {}
    try:
        renderer = IPythonRenderer(escape=False, allow_harmful_protocols=False,
                                   attachments=cell.get("attachments", {}) or {},
                                   anchor_link_text="", exclude_anchor_links=True)
        return _fitted_pictures(clean_html(MarkdownWithMath(renderer=renderer).render(source)))
    except Exception as err:  # noqa: BLE001 - one odd answer must not take the page down
        # (a missing or malformed attachment made the whole submission page a server error,
        # so nothing of it could be marked)
        return (f"<p><em>This answer could not be shown as formatted text "
                f"({html.escape(type(err).__name__)}); its source:</em></p>"
                f"<pre>{html.escape(str(source))}</pre>")


#: ``$$display$$`` or ``$inline$`` math in a marker's comment (a ``\\$`` is a dollar sign)
_MATH = re.compile(r"(?<!\\)\$\$(.+?)(?<!\\)\$\$|(?<!\\)\$(?!\s)([^$\n]+?)(?<![\s\\])\$",
                   re.DOTALL)
#: longer TeX is shown as text (a comment's math is a symbol or a short formula)
_MATH_CHARS = 400


def comment_html(text: str) -> str:
    """A marker's comment as the students' pages show it: Markdown (the Formgrader says
    comments support Markdown and MathJax) through :func:`clean_html`, with each ``$...$`` or
    ``$$...$$`` typeset by matplotlib's mathtext into a picture (the page is read offline,
    without MathJax; TeX mathtext cannot typeset stays as text). Raw HTML is escaped as in
    the Formgrader."""
    from nbconvert.filters.markdown_mistune import IPythonRenderer, MarkdownWithMath

    maths: list[str] = []

    def hold(m: re.Match) -> str:
        display = m.group(1) is not None
        maths.append(_math_html(m.group(1) if display else m.group(2), display))
        return f"MATHSPAN{len(maths) - 1}X"

    source = _MATH.sub(hold, str(text))
    renderer = IPythonRenderer(escape=False, allow_harmful_protocols=False,
                               anchor_link_text="", exclude_anchor_links=True)
    try:
        rendered = clean_html(MarkdownWithMath(renderer=renderer).render(source))
    except Exception:  # noqa: BLE001 - a comment that cannot be rendered is shown as text
        rendered = f"<p>{html.escape(source)}</p>"
    # the pictures are the course's own HTML, put in after cleaning; no newline is left
    # between blocks, so a page may keep the newlines inside them (white-space: pre-wrap)
    rendered = re.sub(r">\n+<", "><", rendered.strip())
    return re.sub(r"MATHSPAN(\d+)X", lambda m: maths[int(m.group(1))]
                  if int(m.group(1)) < len(maths) else m.group(0), rendered)


def _math_html(tex: str, display: bool) -> str:
    """``tex`` typeset as an inline (or display) picture, its TeX as the alt text; the TeX as
    text when mathtext cannot typeset it."""
    delim = "$$" if display else "$"
    shown = html.escape(f"{delim}{tex}{delim}", quote=True)
    png = _typeset(tex.strip()) if len(tex) <= _MATH_CHARS else None
    if png is None:
        return f"<code>{shown}</code>"
    style = ("display:block;margin:.4em auto" if display
             else "vertical-align:middle;max-height:3em")
    return f'<img class="math" style="{style}" alt="{shown}" src="data:image/png;base64,{png}">'


@functools.lru_cache(maxsize=512)
def _typeset(tex: str) -> str | None:
    """``$tex$`` as a base64 PNG by matplotlib's mathtext, or None when it cannot."""
    from matplotlib import mathtext

    buf = io.BytesIO()
    try:
        mathtext.math_to_image(f"${tex}$", buf, dpi=130, format="png")
    except Exception:  # noqa: BLE001 - TeX beyond mathtext's subset: shown as text
        return None
    return base64.b64encode(buf.getvalue()).decode("ascii")


def quoted_cell(cell: dict) -> dict:
    """A student's raw cell (or a cell of a type nbformat does not know) as a markdown cell
    that shows its text in a code block: never rendered as HTML, whatever its
    ``raw_mimetype``."""
    source = cell.get("source", "")
    source = join_source(source) if isinstance(source, list) else str(source)
    kind = re.sub(r"[^a-z]", "", str(cell.get("cell_type", "")).lower())[:20] or "unknown"
    fence = "`" * max(3, 1 + max((len(run) for run in re.findall(r"`+", source)), default=0))
    return {"cell_type": "markdown", "metadata": {},
            "source": f"*(a {kind} cell)*\n\n{fence}text\n{source}\n{fence}\n"}
