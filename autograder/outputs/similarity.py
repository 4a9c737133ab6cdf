"""Similarity evidence for the class report: near-copied solution cells and pasted references.

For every graded name (one solution cell per exercise, see EXERCISES.md) this
module finds

- pairs of students whose cells are near copies of each other once names, comments, docstrings
  and layout are ignored, and
- students whose cell is a near copy of the ``course_lib`` reference source of that function (a
  pasted reference: ``inspect.getsource(REGISTRY[name].reference)``),

and renders them as an HTML section with the two cells side by side, the matching lines marked.
Everything here is a pure function of plain data (strings in, dataclasses and an HTML string
out); it imports the standard library and NumPy only, so the report can call it after grading.
:func:`reference_source` gives a reference's source together with the private helpers of its
module that it calls (``course_lib`` references often delegate to one), which is what a student
who pastes the reference has to paste.

Method (MOSS-style winnowing, Schleimer, Wilkerson & Aiken, SIGMOD 2003)
--------------------------------------------------------------------------
1. **Normalise** (:func:`normalise`): the cell is parsed with :mod:`ast` (IPython ``%``/``!``
   lines blanked first); the tree is written out in pre-order as one token per node (its type),
   with every identifier the student chose (variables, parameters, function and helper names)
   replaced by ``V``, every string by ``S``, and docstrings, bare string statements, comments,
   type annotations and layout dropped. Attribute names (``.linalg``, ``.sum``), keyword-argument
   names (``axis=``), Python built-ins (``float``, ``ValueError``) and numbers are kept: they are
   what a copier rarely changes and two honest authors often choose differently. Top-level
   ``def``/``class`` blocks are sorted by their normalised text, so re-ordered helpers give the
   same stream.
2. **Fingerprint** (:func:`fingerprint`): every run of ``k`` = :data:`K_GRAM` consecutive tokens
   is hashed (a 64-bit polynomial hash of the tokens' BLAKE2 digests); winnowing keeps the
   smallest hash of every :data:`WINDOW` consecutive ones. Any run of ``k + WINDOW - 1`` = 17
   tokens (about two lines) shared by two cells is guaranteed to give them a common
   fingerprint, whatever surrounds it.
3. **Compare per graded name** (:func:`find_similar`). Two students' cells score their
   :func:`jaccard` index (fingerprints in both / fingerprints in either). A student's cell
   scores against the reference by :func:`containment`: the share of the reference's
   fingerprints found in the cell, so a pasted reference with helpers or extra checks around it
   still scores 1. The fingerprints two cells share are counted for every pair at once from
   an inverted index (fingerprint -> cells that contain it, :func:`shared_counts`), not by
   ``n (n - 1) / 2`` set intersections; the scores are exactly the all-pairs ones.

Threshold
---------
Reported when the score is at least :data:`THRESHOLD` = 0.75 and both cells (student and
reference alike) have at least :data:`MIN_TOKENS` = 80 normalised tokens. Shorter cells (about six
lines of NumPy: a three-line ``normalize``, a basis matrix typed from the notes) are too short to
tell: everyone who writes them correctly writes nearly the same thing. Measured on this course
with ``k = 12``, ``WINDOW = 6``: the honest solutions written for the tests
(``tests/grading/honest``) score at most 0.53 against the notebooks' model answers (a
``scanline_span`` written the same textbook way), and the ``course_lib`` references are at most
0.62 contained in either; a copy with renamed variables, re-ordered helpers and new comments,
or a pasted reference, scores 1.0. The report is evidence for a person to read, never an
automatic penalty.

Why not a library
-----------------
``copydetect`` 0.5 (the MOSS-like tool on PyPI, Python and NumPy) was read and not used: it
fingerprints files on disk and compares every test file with every reference file in a Python
loop (125 000 pairs per graded name for 500 students, 5 million for 40 names), hashes character
k-grams with Python's salted ``hash()`` (fingerprints change from run to run), keeps docstrings
as string tokens, and brings Jinja2, Pygments and tqdm for a report of its own. The per-name
inverted index, the syntax-tree normalisation and the report section need about 150 lines here.
"""

from __future__ import annotations

import ast
import builtins
import concurrent.futures
import functools
import hashlib
import html
import inspect
import math
import re
import textwrap
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

#: Tokens per k-gram (a token is one node of the normalised syntax tree).
K_GRAM = 12
#: Winnowing window: one fingerprint is kept per WINDOW consecutive k-grams.
WINDOW = 6
#: Reported at or above this score (:func:`jaccard` for pairs, :func:`containment` of the reference).
THRESHOLD = 0.75
#: Cells with fewer normalised tokens than this are too short to tell and never reported.
MIN_TOKENS = 80
#: Label of the ``course_lib`` reference in a :class:`Match`.
REFERENCE = "course_lib reference"

_BUILTINS = frozenset(dir(builtins))
_MAGIC_LINE = re.compile(r"^[ \t]*[%!].*$", re.M)
_SKIPPED_FIELDS = frozenset({"ctx", "type_comment", "annotation", "returns", "kind",
                             "type_params"})
_DEFINITIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
_FIELDS: dict[type, tuple[str, ...]] = {}     # per node type, the fields that are written out


@dataclass(frozen=True, eq=False)
class Fingerprint:
    """The winnowed fingerprints of one cell (see the module docstring)."""

    tokens: int              #: normalised length (syntax-tree nodes kept)
    hashes: np.ndarray       #: uint64 hash of every k-gram, in order
    token_lines: np.ndarray  #: source line of every normalised token
    prints: np.ndarray       #: winnowed hashes (the minimum of each window), sorted, unique


@dataclass(frozen=True)
class Match:
    """One reported pair: two cells of the same graded name, or a cell and the reference."""

    name: str                #: the graded name (the function the cells define)
    left: str                #: student id
    right: str               #: student id, or :data:`REFERENCE`
    score: float             #: :func:`jaccard` of a pair, :func:`containment` of the reference
    left_source: str
    right_source: str
    left_lines: frozenset[int]    #: 1-based lines of ``left_source`` in shared k-grams
    right_lines: frozenset[int]

    @property
    def is_reference(self) -> bool:
        return self.right == REFERENCE


# ============================================================================================
# normalising


def normalise(source: str) -> list[tuple[str, int]]:
    """The normalised token stream of a cell: ``[(token, source line), ...]``.

    Identifiers become ``V`` and strings ``S``; docstrings, comments, annotations and layout go;
    top-level definitions are sorted by their normalised text. A cell that does not parse
    (even with its IPython ``%``/``!`` lines blanked), or that nests deeper than Python's
    parser allows, gives ``[]``.
    """
    if not isinstance(source, str):
        raise ValueError(f"source must be a string, got {type(source).__name__}")
    tree = _parse(source)
    if tree is None:
        return []
    others, definitions = [], []
    for stmt in tree.body:
        tokens = _emit(stmt)
        (definitions if isinstance(stmt, _DEFINITIONS) else others).append(tokens)
    definitions.sort(key=lambda toks: [t for t, _ in toks])
    return [tok for block in others + definitions for tok in block]


def _parse(source: str) -> ast.Module | None:
    """The cell's syntax tree; failing that, the tree with its IPython ``%``/``!`` lines blanked
    (only then: ``!= b`` may start a continuation line); ``None`` when neither parses."""
    for text in (source, _MAGIC_LINE.sub("", source)):
        try:
            return ast.parse(text)
        except (SyntaxError, ValueError, RecursionError, MemoryError):  # ValueError: NUL byte
            continue
    return None


def _emit(root: ast.AST) -> list[tuple[str, int]]:
    """The pre-order tokens of ``root`` (see :func:`normalise`), with an explicit stack so that
    deeply nested code cannot exhaust Python's recursion limit."""
    out: list[tuple[str, int]] = []
    stack = [(root, getattr(root, "lineno", 1))]
    while stack:
        node, line = stack.pop()
        cls = node.__class__
        if cls is str:                      # a leaf prepared by its parent
            out.append((node, line))
        elif cls is ast.Name:               # the two commonest nodes, inlined
            out += [("Name", node.lineno), (node.id if node.id in _BUILTINS else "V", node.lineno)]
        elif cls is ast.Constant:
            value = node.value
            out += [("Constant", node.lineno),
                    ("S" if isinstance(value, (str, bytes)) else repr(value), node.lineno)]
        elif cls is not ast.Expr or not _is_bare_string(node):
            line = getattr(node, "lineno", line)
            out.append((cls.__name__, line))
            stack += [(child, line) for child in reversed(_children(node))]
    return out


def _children(node: ast.AST) -> list:
    """The sub-trees and leaf tokens of ``node``, in field order, without skipped fields."""
    fields = _FIELDS.get(node.__class__)
    if fields is None:
        fields = _FIELDS[node.__class__] = tuple(f for f in node._fields
                                                 if f not in _SKIPPED_FIELDS)
    children = []
    for field in fields:
        value = getattr(node, field, None)
        if isinstance(value, ast.AST):
            children.append(value)
        elif isinstance(value, list):
            children += [item for item in value if isinstance(item, ast.AST)]
        elif value is not None:
            children.append(_leaf(node, field, value))
    return children


def _is_bare_string(node: ast.AST) -> bool:
    """A docstring or any other string used as a statement (it does nothing)."""
    return (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
            and isinstance(node.value.value, (str, bytes, type(Ellipsis))))


def _leaf(node: ast.AST, field: str, value) -> str:
    """The token of a plain field: names chosen by the student become ``V``."""
    if isinstance(node, (ast.Attribute, ast.keyword, ast.ImportFrom)) \
            or (isinstance(node, ast.alias) and field == "name"):
        return f"{field}={value}"
    if isinstance(node, ast.Name):
        return value if value in _BUILTINS else "V"
    if isinstance(node, ast.Constant):
        return "S" if isinstance(value, (str, bytes)) else repr(value)
    if isinstance(value, str):          # def/class names, parameters, alias.asname, globals
        return "V"
    return repr(value)


def reference_source(function) -> str:
    """The source of ``function`` followed by the private (``_name``) functions of its module
    that it calls, transitively: what pasting the reference into a cell takes.

    Raises
    ------
    ValueError
        If ``function`` is not a Python function whose source is available.
    """
    if not inspect.isfunction(function):
        raise ValueError(f"function must be a Python function, got {type(function).__name__}")
    module = inspect.getmodule(function)
    try:
        parts = [textwrap.dedent(inspect.getsource(function))]
    except (OSError, TypeError) as exc:
        raise ValueError(f"no source for {function.__qualname__}: {exc}") from None
    seen = {function.__name__}
    for part in parts:                  # grows while it is read: helpers of helpers
        for name in sorted(set(re.findall(r"\b(_\w+)\s*\(", part)) - seen):
            helper = getattr(module, name, None)
            if inspect.isfunction(helper) and inspect.getmodule(helper) is module:
                seen.add(name)
                parts.append(textwrap.dedent(inspect.getsource(helper)))
    return "\n\n".join(parts)


# ============================================================================================
# fingerprints


_TOKEN_IDS: dict[str, int] = {}


def _token_id(token: str) -> int:
    """A stable 64-bit number per token (BLAKE2b, so runs and machines agree)."""
    found = _TOKEN_IDS.get(token)
    if found is None:
        found = int.from_bytes(hashlib.blake2b(token.encode(), digest_size=8).digest(), "little")
        _TOKEN_IDS[token] = found
    return found


def fingerprint(source: str, k: int = K_GRAM, window: int = WINDOW) -> Fingerprint | None:
    """Winnowed k-gram fingerprints of one cell, or ``None`` when it has fewer than ``k +
    window - 1`` normalised tokens (nothing to winnow) or does not parse."""
    _check_positive_int(k=k, window=window)
    tokens = normalise(source)
    if len(tokens) < k + window - 1:
        return None
    ids = np.array([_TOKEN_IDS.get(t) or _token_id(t) for t, _ in tokens], dtype=np.uint64)
    n_grams = ids.size - k + 1
    hashes = np.zeros(n_grams, dtype=np.uint64)
    with np.errstate(over="ignore"):   # the polynomial hash is modulo 2**64 on purpose
        for j in range(k):
            hashes = hashes * np.uint64(1_000_003) + ids[j:j + n_grams]
    smallest = hashes[:n_grams - window + 1].copy()
    for j in range(1, window):         # the minimum of every window of k-gram hashes
        np.minimum(smallest, hashes[j:j + smallest.size], out=smallest)
    return Fingerprint(tokens=len(tokens), hashes=hashes,
                       token_lines=np.array([line for _, line in tokens], dtype=np.int64),
                       prints=np.unique(smallest))


def jaccard(a: Fingerprint, b: Fingerprint) -> float:
    """Fingerprints the two cells share over the fingerprints either has, in ``[0, 1]``: the
    score of a pair of students."""
    shared = np.intersect1d(a.prints, b.prints, assume_unique=True).size
    return shared / (a.prints.size + b.prints.size - shared)


def containment(part: Fingerprint, whole: Fingerprint) -> float:
    """Share of ``part``'s fingerprints also in ``whole``, in ``[0, 1]``: the score of a cell
    against the reference (``part``), so a pasted reference scores 1 whatever is around it."""
    return np.intersect1d(part.prints, whole.prints, assume_unique=True).size / part.prints.size


def shared_lines(a: Fingerprint, b: Fingerprint) -> tuple[frozenset[int], frozenset[int]]:
    """Source lines of ``a`` and of ``b`` covered by a k-gram the other cell also has."""
    return _covered(a, np.isin(a.hashes, b.hashes)), _covered(b, np.isin(b.hashes, a.hashes))


def _covered(fp: Fingerprint, matched: np.ndarray) -> frozenset[int]:
    """Lines of the tokens that belong to at least one matched k-gram."""
    k = fp.token_lines.size - fp.hashes.size + 1
    starts = np.r_[0, np.cumsum(matched)]          # matched k-grams starting before each index
    token = np.arange(fp.token_lines.size)
    inside = starts[np.minimum(token + 1, matched.size)] - starts[np.maximum(token - k + 1, 0)] > 0
    return frozenset(np.unique(fp.token_lines[inside]).tolist())


def common_limit(n_cells: int) -> int:
    """Cells of one name above which a fingerprint counts as common code in
    :func:`shared_counts` (counted by a matrix product instead of pair by pair): 10 % of the
    cells, at least 10."""
    return max(10, math.ceil(0.1 * n_cells))


def _check_positive_int(**values) -> None:
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")


# ============================================================================================
# comparing


def shared_counts(prints: list[np.ndarray], limit: int) -> np.ndarray:
    """``counts[i, j]``, ``i < j``: fingerprints that sets ``i`` and ``j`` share (0 elsewhere).

    An inverted index (fingerprint -> sets holding it), never ``n (n - 1) / 2`` set
    intersections: a fingerprint held by at most ``limit`` sets adds one to each of its pairs
    (enumerated with NumPy, grouped by how many sets hold it); the few held by more, code most
    of the class writes alike, become columns of a 0/1 matrix ``D`` whose product ``D @ D.T``
    counts them for every pair at once.
    """
    n = len(prints)
    counts = np.zeros((n, n), dtype=np.int32)    # 1 MB for 500 cells of one name
    sizes = np.fromiter((p.size for p in prints), dtype=np.int64, count=n)
    if n < 2 or not sizes.any():
        return counts
    owner = np.repeat(np.arange(n), sizes)
    every = np.concatenate(prints)
    order = np.argsort(every, kind="stable")     # owners stay ascending within a fingerprint
    every, owner = every[order], owner[order]
    starts = np.flatnonzero(np.r_[True, every[1:] != every[:-1]])
    held = np.diff(np.r_[starts, every.size])
    for size in np.unique(held[(held > 1) & (held <= limit)]):
        groups = owner[starts[held == size][:, None] + np.arange(size)]   # (fingerprints, size)
        i, j = np.triu_indices(size, 1)
        np.add.at(counts, (groups[:, i].ravel(), groups[:, j].ravel()), 1)
    common = held > limit
    if common.any():
        column = np.repeat(np.cumsum(common) - 1, held)
        in_common = np.repeat(common, held)
        dense = np.zeros((n, int(common.sum())), dtype=np.float32)
        dense[owner[in_common], column[in_common]] = 1.0
        counts += np.triu(np.rint(dense @ dense.T).astype(np.int32), 1)
    return counts


def find_similar(cells: Mapping[str, Mapping[str, str]], references: Mapping[str, str] | None = None,
                 *, threshold: float = THRESHOLD, min_tokens: int = MIN_TOKENS,
                 k: int = K_GRAM, window: int = WINDOW, jobs: int = 1) -> list[Match]:
    """Near-copied cells between students, and cells that copy the reference.

    Parameters
    ----------
    cells : mapping
        ``{student: {graded name: solution-cell source}}``; names are compared only with the
        same name. Empty or non-string sources (a missing cell) are skipped.
    references : mapping, optional
        ``{graded name: course_lib reference source}``, e.g. from :func:`reference_source`.
    threshold : float
        Report at or above this score (default :data:`THRESHOLD`), in ``(0, 1]``.
    min_tokens : int
        Ignore cells with fewer normalised tokens (default :data:`MIN_TOKENS`).
    k, window : int
        k-gram length and winnowing window.
    jobs : int
        Processes that fingerprint the cells (1: this process only).

    Returns
    -------
    list of Match
        Highest score first; reference matches before pairs at equal score.
    """
    if not isinstance(cells, Mapping):
        raise ValueError(f"cells must map student -> {{name: source}}, got {type(cells).__name__}")
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) \
            or not 0 < threshold <= 1:
        raise ValueError(f"threshold must be a number in (0, 1], got {threshold!r}")
    _check_positive_int(min_tokens=min_tokens, k=k, window=window, jobs=jobs)
    references = {n: r for n, r in (references or {}).items() if isinstance(r, str)}
    sources = {src for per in cells.values() if isinstance(per, Mapping)
               for src in per.values() if isinstance(src, str)}
    prints = fingerprint_all(sources | set(references.values()), k, window, jobs)
    return compare_fingerprinted(cells, prints, references, threshold=threshold,
                                 min_tokens=min_tokens)


def find_pasted_references(code: Mapping[str, Iterable[str]], references: Mapping[str, str], *,
                           threshold: float = THRESHOLD, min_tokens: int = MIN_TOKENS,
                           k: int = K_GRAM, window: int = WINDOW, jobs: int = 1) -> list[Match]:
    """Students whose solution code *anywhere* holds a reference (a hidden copy).

    :func:`find_similar` compares each graded name's own cell with its reference; a reference
    pasted into another cell (behind a helper the graded cell calls) escapes it. Here ``code`` is
    ``{student: that student's graded cells' sources}``; each cell is fingerprinted on its own
    (so memory stays bounded by the largest cell) and every reference is looked for in the union
    of a student's fingerprints, by containment, so the code around the paste does not hide it.
    The evidence shown is the student's cell that shares the most with the reference.
    """
    if not isinstance(code, Mapping) or not isinstance(references, Mapping):
        raise ValueError("code and references must be mappings")
    _check_positive_int(min_tokens=min_tokens, k=k, window=window, jobs=jobs)
    cells = {s: [c for c in srcs if isinstance(c, str) and c.strip()] for s, srcs in code.items()}
    references = {n: r for n, r in references.items() if isinstance(r, str)}
    prints = fingerprint_all({c for cs in cells.values() for c in cs} | set(references.values()),
                             k, window, jobs)
    found: list[Match] = []
    for student, sources in sorted(cells.items()):
        mine = [(src, prints[src]) for src in sources if prints[src] is not None]
        if not mine:
            continue
        union = np.unique(np.concatenate([fp.prints for _, fp in mine]))
        for name, ref_source in sorted(references.items()):
            ref = prints.get(ref_source)
            if ref is None or ref.tokens < min_tokens:
                continue
            score = np.intersect1d(ref.prints, union, assume_unique=True).size / ref.prints.size
            if score >= threshold:
                src, fp = max(mine, key=lambda item: containment(ref, item[1]))
                left, right = shared_lines(fp, ref)
                found.append(Match(name, student, REFERENCE, score, src, ref_source, left, right))
    found.sort(key=lambda m: (-m.score, m.name, m.left))
    return found


def compare_fingerprinted(cells: Mapping[str, Mapping[str, str]],
                          prints: Mapping[str, Fingerprint | None],
                          references: Mapping[str, str], *, threshold: float = THRESHOLD,
                          min_tokens: int = MIN_TOKENS) -> list[Match]:
    """:func:`find_similar` once every source is fingerprinted (``prints`` from
    :func:`fingerprint_all`): per graded name, every pair and every cell against its reference."""
    found: list[Match] = []
    for name, by_student in _by_name(cells).items():
        kept = {student: prints[src] for student, src in by_student.items()
                if prints[src] is not None and prints[src].tokens >= min_tokens}
        found += _pairs_of(name, kept, by_student, threshold)
        ref = prints.get(references.get(name))
        if ref is not None and ref.tokens >= min_tokens:
            found += _reference_matches(name, kept, by_student, references[name], ref, threshold)
    found.sort(key=lambda m: (-m.score, not m.is_reference, m.name, m.left, m.right))
    return found


def fingerprint_all(sources: Iterable[str], k: int = K_GRAM, window: int = WINDOW,
                    jobs: int = 1) -> dict[str, Fingerprint | None]:
    """``{source: fingerprint(source)}`` for distinct sources, in ``jobs`` processes."""
    _check_positive_int(k=k, window=window, jobs=jobs)
    unique = sorted(set(sources))
    work = functools.partial(fingerprint, k=k, window=window)
    if jobs == 1 or len(unique) < 100:
        return {src: work(src) for src in unique}
    with concurrent.futures.ProcessPoolExecutor(max_workers=jobs) as pool:
        chunk = max(1, len(unique) // (8 * jobs))
        return dict(zip(unique, pool.map(work, unique, chunksize=chunk)))


def _by_name(cells: Mapping[str, Mapping[str, str]]) -> dict[str, dict[str, str]]:
    """``{name: {student: source}}`` from ``{student: {name: source}}``, students sorted."""
    out: dict[str, dict[str, str]] = {}
    for student in sorted(cells):
        per = cells[student]
        if not isinstance(per, Mapping):
            raise ValueError(f"cells[{student!r}] must map graded name -> source")
        for name, source in per.items():
            if isinstance(source, str) and source.strip():
                out.setdefault(name, {})[student] = source
    return out


def _pairs_of(name: str, prints: dict[str, Fingerprint], sources: dict[str, str],
              threshold: float) -> list[Match]:
    students = list(prints)
    sizes = np.array([prints[s].prints.size for s in students], dtype=np.int64)
    counts = shared_counts([prints[s].prints for s in students], common_limit(len(students)))
    rows, cols = np.nonzero(counts)
    shared = counts[rows, cols]
    scores = shared / (sizes[rows] + sizes[cols] - shared)
    found = []
    for i, j, score in zip(rows[scores >= threshold], cols[scores >= threshold],
                           scores[scores >= threshold]):
        a, b = students[i], students[j]
        left, right = shared_lines(prints[a], prints[b])
        found.append(Match(name, a, b, float(score), sources[a], sources[b], left, right))
    return found


def _reference_matches(name: str, prints: dict[str, Fingerprint], sources: dict[str, str],
                       ref_source: str, ref: Fingerprint, threshold: float) -> list[Match]:
    found = []
    for student, fp in prints.items():
        score = containment(ref, fp)
        if score >= threshold:
            left, right = shared_lines(fp, ref)
            found.append(Match(name, student, REFERENCE, score, sources[student], ref_source,
                               left, right))
    return found


# ============================================================================================
# the report's section


_SECTION_STYLE = (".simil pre{margin:0;font-size:.8em;white-space:pre-wrap;word-break:break-word}"
                  ".simil mark{background:#ffe082}.simil td{width:50%}")


def render_section(matches: Iterable[Match], *, threshold: float = THRESHOLD,
                   min_tokens: int = MIN_TOKENS, limit: int = 50) -> str:
    """The report's "Similar solutions" section: an HTML fragment (no scripts, no network).

    Parameters
    ----------
    matches : iterable of Match
        From :func:`find_similar`.
    threshold, min_tokens : float, int
        The values ``matches`` were found with, stated in the section's note.
    limit : int
        Matches shown in full (the two cells side by side, escaped, lines inside shared k-grams
        marked); the rest are listed by name and score.

    Returns
    -------
    str
        ``<section>...</section>``: pasted references first, then pairs of students.
    """
    matches = list(matches)
    _check_positive_int(limit=limit)
    refs = [m for m in matches if m.is_reference]
    pairs = [m for m in matches if not m.is_reference]
    out = [f"<section class='simil'><style>{_SECTION_STYLE}</style>",
           f"<h2>Similar solutions ({len(refs)} like the reference, {len(pairs)} "
           f"pair{'' if len(pairs) == 1 else 's'})</h2>",
           f"<p class='note'>Solution cells compared per graded function after normalising names, "
           f"comments, docstrings and layout (k-gram winnowing). Two students are listed when "
           f"at least {threshold:.0%} of the fingerprints either cell has are in both (Jaccard "
           f"index); a student, when the cell holds at least {threshold:.0%} of the reference's "
           f"fingerprints. Cells under {min_tokens} normalised tokens are too short to tell and "
           f"never listed. This is evidence to read, not a verdict: marked lines are the "
           f"shared code.</p>"]
    if not matches:
        out.append("<p>None above the threshold.</p>")
    budget = limit
    for title, group in (("Like the course_lib reference", refs), ("Pairs of students", pairs)):
        if group:
            out.append(f"<h3>{title}</h3>")
            out += [_match_html(m) for m in group[:budget]]
            out += _overflow_html(group[budget:])
            budget = max(budget - len(group), 0)
    out.append("</section>")
    return "\n".join(out)


def _match_html(m: Match) -> str:
    return (f"<details open><summary><b>{_e(m.name)}</b>: {_e(m.left)} and {_e(m.right)}, "
            f"{m.score:.0%} shared</summary><table><tr><th>{_e(m.left)}</th><th>{_e(m.right)}"
            f"</th></tr><tr><td>{_code_html(m.left_source, m.left_lines)}</td>"
            f"<td>{_code_html(m.right_source, m.right_lines)}</td></tr></table></details>")


def _overflow_html(rest: list[Match], listed: int = 200) -> list[str]:
    """The matches not shown in full, by name and score (the first ``listed`` of them)."""
    if not rest:
        return []
    items = ", ".join(f"{_e(m.name)}: {_e(m.left)}/{_e(m.right)} {m.score:.0%}"
                      for m in rest[:listed])
    more = f" and {len(rest) - listed} more" if len(rest) > listed else ""
    return [f"<p class='note'>Also above the threshold: {items}{more}.</p>"]


def _code_html(source: str, marked: frozenset[int]) -> str:
    rows = [f"<mark>{_e(text)}</mark>" if number in marked else _e(text)
            for number, text in enumerate(source.splitlines(), start=1)]
    return "<pre>\n" + "\n".join(rows) + "</pre>"   # HTML drops a newline right after <pre>


def _e(text) -> str:
    return html.escape(str(text), quote=True)
