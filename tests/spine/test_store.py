"""kit.store: results kept on disk for the next process; a damaged entry is named and recomputed,
a store that cannot be written is named and the answer kept."""
import json

import pytest

from mechopt.kit import store

SOURCES = ("mechopt.kit.store",)


def _pair(calls):
    def compute():
        calls.append(1)
        return (True, 0.25)
    return compute


def _stored(compute):
    return store.stored("probe", ("lever", 1.5), compute, list, lambda d: (bool(d[0]), float(d[1])), sources=SOURCES)


def test_an_entry_is_written_whole_and_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv(store.ENV, str(tmp_path))
    calls = []
    assert _stored(_pair(calls)) == (True, 0.25) and _stored(_pair(calls)) == (True, 0.25)
    assert len(calls) == 1
    [entry] = tmp_path.iterdir()
    assert entry.suffix == ".json" and json.loads(entry.read_text()) == [True, 0.25]


@pytest.mark.parametrize("text", ["[]", "{not json", '{"a": 1}', "[1]"])
def test_a_damaged_entry_of_any_shape_is_named_and_recomputed(tmp_path, monkeypatch, text):
    monkeypatch.setenv(store.ENV, str(tmp_path))
    _stored(_pair([]))
    [entry] = tmp_path.iterdir()
    entry.write_text(text, encoding="utf-8")
    calls = []
    with pytest.warns(store.StoreWarning, match=entry.name):
        assert _stored(_pair(calls)) == (True, 0.25)
    assert calls == [1] and json.loads(entry.read_text()) == [True, 0.25]       # written over


def test_a_value_the_store_cannot_write_is_named_and_leaves_no_temporary_file(tmp_path, monkeypatch):
    monkeypatch.setenv(store.ENV, str(tmp_path))
    with pytest.warns(store.StoreWarning, match="not stored"):
        value = store.stored("odd", "key", lambda: {1, 2}, lambda v: v, lambda d: d, sources=SOURCES)
    assert value == {1, 2} and list(tmp_path.iterdir()) == []


def test_off_without_the_variable(tmp_path, monkeypatch):
    monkeypatch.delenv(store.ENV, raising=False)
    calls = []
    _stored(_pair(calls)), _stored(_pair(calls))
    assert len(calls) == 2
