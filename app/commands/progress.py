"""Progress bars of the long CLI runs, when the ``figures`` extra (tqdm) is installed.

The service never needs tqdm, so it is not a runtime dependency: without it
``simulate`` and ``replay`` run the same, and say once on stderr why there is
no bar.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TypeVar

Item = TypeVar("Item")

EXTRA_HINT = "pip install 'credal-fusion[figures]'"


def shown(
    items: Iterable[Item], label: str, quiet: bool, total: int | None = None
) -> Iterable[Item]:
    """``items`` behind a tqdm bar on stderr (none if ``quiet`` or tqdm is missing)."""
    if quiet:
        return items
    try:
        from tqdm import tqdm
    except ModuleNotFoundError:
        print(f"{label}: no progress bar without tqdm ({EXTRA_HINT})", file=sys.stderr)
        return items
    return tqdm(items, desc=label, unit="input", file=sys.stderr, total=total)
