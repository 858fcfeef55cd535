"""The one JSON reader of bodies and messages (:func:`app.http.requests.parse_json`) reads
what ``json.loads`` reads (its oracle), refuses what it refuses with the same message, and
refuses duplicate keys; its decoder is kept per thread."""

from __future__ import annotations

import json
import threading

import pytest

from app.http.requests import _decoder, parse_json

DOCUMENTS = [
    '{"type":"detections","sensor":"radar","time":1.5,"detections":[{"z":[1.25,-2e5]}]}',
    '[1, 2.5e-300, -0.0, "é\\u2028", null, true, {"nested": {"a": [[]]}}]',
    '{"x": NaN, "y": -Infinity}',
    '  "text"  ',
]
REFUSED = ["\ufeff{}", "[1,2", '{"a" 1}', "", "[1] 2"]


@pytest.mark.parametrize("text", DOCUMENTS)
def test_a_document_reads_as_json_loads_reads_it(text: str) -> None:
    assert repr(parse_json(text)) == repr(json.loads(text))
    assert repr(parse_json(text.encode())) == repr(json.loads(text))


@pytest.mark.parametrize("text", REFUSED)
def test_a_refusal_says_what_json_loads_says(text: str) -> None:
    with pytest.raises(json.JSONDecodeError) as expected:
        json.loads(text)
    with pytest.raises(json.JSONDecodeError) as refused:
        parse_json(text)
    assert (refused.value.msg, refused.value.pos) == (expected.value.msg, expected.value.pos)


def test_duplicate_keys_are_refused_at_any_depth() -> None:
    for text in ('{"time": 1, "time": 2}', '{"a": [{"b": 1, "b": 1}]}'):
        with pytest.raises(json.JSONDecodeError, match="duplicate key"):
            parse_json(text)


def test_each_thread_reads_with_its_own_decoder() -> None:
    decoders: list[json.JSONDecoder] = []
    results: list[object] = []

    def read(index: int) -> None:
        decoders.append(_decoder())
        results.extend(parse_json(f'{{"n": {index}, "k": [{index}]}}') for _ in range(200))

    threads = [threading.Thread(target=read, args=(index,)) for index in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len({id(decoder) for decoder in decoders}) == 4
    assert sorted(results, key=repr) == sorted(
        ({"n": index, "k": [index]} for index in range(4) for _ in range(200)), key=repr
    )
