"""``tests/diskcache.py`` never hands back a value computed from other sources."""

from __future__ import annotations

import diskcache
import pytest


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setattr(diskcache, "CACHE", tmp_path / "cache")
    return tmp_path / "cache"


def test_a_value_is_computed_once_per_content_of_its_sources(tmp_path, cache):
    src, calls = tmp_path / "source.py", []

    def compute():
        calls.append(src.read_text())
        return {"from": src.read_text()}

    src.write_text("a = 1\n")
    assert diskcache.cached("v", [src], compute) == {"from": "a = 1\n"}
    assert diskcache.cached("v", [src], compute) == {"from": "a = 1\n"}
    assert calls == ["a = 1\n"]                      # the second came from disk
    src.write_text("a = 2\n")                          # a changed source: computed again
    assert diskcache.cached("v", [src], compute) == {"from": "a = 2\n"}
    assert calls == ["a = 1\n", "a = 2\n"]
    assert len(list(cache.glob("v-*.pickle"))) == 1    # the stale file is gone


def test_a_torn_file_is_computed_again(tmp_path, cache):
    src = tmp_path / "source.py"
    src.write_text("b = 1\n")
    diskcache.cached("w", [src], lambda: [1, 2, 3])
    (stored,) = cache.glob("w-*.pickle")
    stored.write_bytes(stored.read_bytes()[:5])
    assert diskcache.cached("w", [src], lambda: [4]) == [4]
