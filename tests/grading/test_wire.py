"""The grader's side of the wire is total: whatever the sandbox sends (the student owns every
process in it, the encoder included), decoding gives a value or ``BadValue`` and a case record
gives that case an outcome; nothing else ever escapes to the grader (issue 33, finding 3: an
array of shape ``[0, 2**70]`` or a complex of ``[10**400, 0]`` made a whole notebook
``grader-error``).

Generated records are hostile by construction: every field of every type, huge and negative
ints, NaN, lone surrogates, deep nesting, arrays whose shape, dtype and data disagree.
"""

from __future__ import annotations

import base64
import tracemalloc

import numpy as np
from hypothesis import example, given
from hypothesis import strategies as st

from autograder.isolation import CaseInput, Limits, NameJob, NotebookJob
from autograder.isolation.inside import wire
from autograder.isolation.runner import Collector
from autograder.model import CaseOutcome, OutcomeKind

BUDGET = 4096                    #: bytes a decoded value may take in these tests
INTS = st.one_of(st.integers(-3, 70), st.sampled_from([2**31, 2**62, 2**63, 2**64, 2**70,
                                                       10**400, -(2**63)]),
                 st.integers(min_value=-(2**80), max_value=2**80))
SCALARS = st.one_of(st.none(), st.booleans(), INTS, st.floats(allow_nan=True),
                    st.text(alphabet=st.characters(codec=None), max_size=40))
DTYPES = st.one_of(st.sampled_from(sorted(wire.ARRAY_DTYPES)),
                   st.sampled_from(["|O", "<U4", "V8", "<M8[s]", ">f8", "", "f8"]), SCALARS,
                   st.lists(SCALARS, max_size=2))


@st.composite
def arrays(draw):
    """An array record whose dtype, shape and data may or may not agree."""
    shape = draw(st.one_of(st.lists(INTS, max_size=5), SCALARS))
    size = draw(st.integers(0, 200))
    data = draw(st.one_of(st.just(base64.b64encode(bytes(size)).decode()), SCALARS))
    return {"t": "array", "dtype": draw(DTYPES), "shape": shape, "v": data}


def _tagged(children):
    tags = st.one_of(st.sampled_from(["tuple", "list", "dict", "complex", "array", "pickle"]),
                     SCALARS)
    items = st.one_of(st.lists(children, max_size=4),
                      st.lists(st.lists(st.one_of(st.text(max_size=5), children), max_size=3),
                               max_size=3), children)
    return st.one_of(st.builds(lambda t, v: {"t": t, "v": v}, tags, items), arrays(),
                     st.dictionaries(st.text(max_size=6), children, max_size=3),
                     st.lists(children, max_size=4))


VALUES = st.recursive(SCALARS, _tagged, max_leaves=30)


def _nested(depth: int):
    value = 1.0
    for _ in range(depth):
        value = {"t": "list", "v": [value]}
    return value


@given(VALUES)
@example({"t": "array", "dtype": "<f8", "shape": [0, 2**70], "v": ""})
@example({"t": "array", "dtype": "<f8", "shape": [0, 2**40, 2**40, 2**40], "v": ""})
@example({"t": "complex", "v": [10**400, 0]})
@example({"t": "complex", "v": [0.5, -(10**309)]})
@example({"t": "array", "dtype": ["<f8"], "shape": [1], "v": "AAAAAAAAAAA="})
@example({"t": ["list"], "v": []})
@example({"t": "dict", "v": [["\ud800", "\udfff"]]})
@example(10**2000)
@example(_nested(60))
def test_decoding_gives_a_value_or_bad_value_and_stays_small(obj):
    tracemalloc.start()
    try:
        value = wire.decode_value(obj, wire.Budget(BUDGET))
    except wire.BadValue as exc:
        assert str(exc)
        value = None
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < 1_000_000, f"decoding took {peak} bytes"
    _assert_writable(value)


def _assert_writable(value) -> None:
    """A decoded value is one the grader can show and log: strings encode as UTF-8, arrays are
    real arrays of at most the budget's bytes."""
    if type(value) is str:
        value.encode("utf-8")
    elif type(value) in (list, tuple):
        for v in value:
            _assert_writable(v)
    elif type(value) is dict:
        for k, v in value.items():
            k.encode("utf-8")
            _assert_writable(v)
    elif isinstance(value, np.ndarray):
        assert value.nbytes <= BUDGET and value.dtype.str in wire.ARRAY_DTYPES


def test_a_valid_value_still_round_trips():
    """The control: the checks refuse nothing the encoder sends."""
    value = (1, -2.5, None, True, "é", 3 + 4j, {"a": [np.arange(6, dtype="<i8").reshape(2, 3),
                                                   np.zeros((0, 3))]}, 2**100)
    back = wire.decode_value(wire.encode_value(value, wire.Budget(BUDGET)), wire.Budget(BUDGET))
    assert back[:6] == value[:6] and back[7] == 2**100
    assert back[6]["a"][0].tolist() == [[0, 1, 2], [3, 4, 5]]
    assert back[6]["a"][1].shape == (0, 3)


RECORD_FIELDS = {"i": st.one_of(st.integers(-1, 3), SCALARS),
                 "kind": st.one_of(st.sampled_from([k.value for k in OutcomeKind]), SCALARS),
                 "value": VALUES, "seconds": st.one_of(SCALARS, st.floats()),
                 "printed": SCALARS, "message": SCALARS, "etype": SCALARS,
                 "mro": st.one_of(st.lists(SCALARS, max_size=30), SCALARS)}


def _collector() -> Collector:
    cases = [CaseInput((k,), {}, 1024) for k in range(3)]
    return Collector(NotebookJob("fuzz", "", [NameJob("f", "function", [("c", "")], cases)]),
                     Limits())


@given(st.lists(st.fixed_dictionaries({}, optional=RECORD_FIELDS), min_size=1, max_size=4),
       st.integers(0, 2 * wire.record_cap(1024, Limits().output_bytes)))
@example([{"i": 0, "kind": "returned",
           "value": {"t": "array", "dtype": "<f8", "shape": [0, 2**70], "v": ""}}], 100)
@example([{"i": 1, "kind": "returned", "value": {"t": "complex", "v": [10**400, 0]}}], 100)
@example([{"i": 2, "kind": "raised", "etype": "\ud800", "mro": [10**400, "\udcff"],
           "message": "\ud83d"}], 100)
def test_every_case_record_gives_its_case_an_outcome(records, size):
    """The grader's collector never raises for a record's content: each case the records name
    gets an outcome of the student's (the rest: the sandbox's ending), all of them writable."""
    collector = _collector()
    for rec in records:
        rec = dict(rec, t="case", name="f")
        assert collector.take(rec, b" " * size) is False
    run = collector.results("done")["f"]
    assert [o.index for o in run.outcomes] == [0, 1, 2]
    named = {r["i"] for r in records if type(r.get("i")) is int and 0 <= r["i"] < 3}
    for o in run.outcomes:
        assert isinstance(o, CaseOutcome)
        if o.index not in named:
            assert o.kind is OutcomeKind.NOT_RUN
        for text in (o.message, o.printed, o.error_type, *o.error_mro):
            text.encode("utf-8")
        _assert_writable(o.value)


ANY_RECORD = st.fixed_dictionaries(
    {"t": st.one_of(st.sampled_from(["done", "note", "name", "loaded", "case", "end"]), SCALARS),
     "name": st.one_of(st.just("f"), SCALARS)},
    optional={**RECORD_FIELDS, "text": SCALARS, "defined": SCALARS, "launches": INTS,
              "by": SCALARS})


@given(st.lists(ANY_RECORD, max_size=8))
def test_the_collector_takes_any_stream_of_records(records):
    """Whatever records arrive, in whatever order, the results are one outcome per case."""
    collector = _collector()
    for rec in records:
        collector.take(rec, b"{}")
    run = collector.results("eof")["f"]
    assert [o.index for o in run.outcomes] == [0, 1, 2]
    assert 1 <= run.launches <= Limits().max_launches
    for text in [run.printed, *run.load_notes]:
        text.encode("utf-8")
