"""``--store`` / ``CREDAL_STORE`` URLs: ``memory``, ``sqlite`` or ``sqlite:PATH``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from app.stores.base import Store
from app.stores.memory import MemoryStore
from app.stores.sqlite import SqliteStore

DEFAULT_SQLITE_PATH = Path("data") / "credal-fusion.db"


@dataclass(frozen=True)
class StoreSpec:
    """A parsed store URL."""

    kind: Literal["memory", "sqlite"]
    path: Path | None = None


def parse_store_url(url: str) -> StoreSpec:
    """Parse ``memory``, ``sqlite``, ``sqlite:PATH`` or ``sqlite:///ABSOLUTE/PATH``."""
    text = url.strip()
    if text == "memory":
        return StoreSpec("memory")
    if text == "sqlite":
        return StoreSpec("sqlite", DEFAULT_SQLITE_PATH)
    if text.startswith("sqlite:"):
        location = text.removeprefix("sqlite:")
        if location.startswith("//"):
            location = location.removeprefix("//")
        if not location:
            raise ValueError(f"store {url!r}: empty sqlite path")
        return StoreSpec("sqlite", Path(location))
    if text.startswith("redis"):
        raise ValueError(
            f"store {url!r}: the redis store is not available yet (use memory or sqlite[:PATH])"
        )
    raise ValueError(f"store {url!r}: expected memory, sqlite or sqlite:PATH")


def open_store(url: str) -> Store:
    """Open the store named by ``url``."""
    spec = parse_store_url(url)
    if spec.kind == "memory":
        return MemoryStore()
    assert spec.path is not None
    return SqliteStore(spec.path)
