"""simulate/replay progress: a tqdm bar with the figures extra, one stderr line without it."""

from __future__ import annotations

import sys

import pytest
from tqdm import tqdm

from app.commands.progress import shown


def test_quiet_passes_the_items_through_untouched() -> None:
    items = [1, 2, 3]
    assert shown(items, "replay", quiet=True) is items


def test_a_bar_when_tqdm_is_installed(capsys: pytest.CaptureFixture[str]) -> None:
    bar = shown([1, 2, 3], "replay", quiet=False)
    assert isinstance(bar, tqdm)
    assert list(bar) == [1, 2, 3]
    assert "replay" in capsys.readouterr().err


def test_without_tqdm_the_items_and_one_line_saying_why(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "tqdm", None)  # as if the figures extra were missing
    items = [1, 2, 3]
    assert shown(items, "replay", quiet=False) is items
    [line] = capsys.readouterr().err.splitlines()
    assert "no progress bar" in line and "credal-fusion[figures]" in line
