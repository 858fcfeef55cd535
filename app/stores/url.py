"""``--store`` / ``CREDAL_STORE`` URLs: ``memory``, ``sqlite[:PATH]`` or ``redis://HOST:PORT/DB``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from app.stores.base import Store
from app.stores.memory import MemoryStore
from app.stores.redis import RedisStore
from app.stores.redis_keys import DEFAULT_PREFIX
from app.stores.sqlite import SqliteStore, Synchronous

DEFAULT_SQLITE_PATH = Path("data") / "credal-fusion.db"
DEFAULT_REDIS_URL = "redis://127.0.0.1:6379/0"
REDIS_SCHEMES = ("redis", "rediss")
EXPECTED = "expected memory, sqlite[:PATH] or redis[s]://HOST[:PORT][/DB]"


@dataclass(frozen=True)
class StoreSpec:
    """A parsed store URL: ``path`` for sqlite, ``url`` for redis."""

    kind: Literal["memory", "sqlite", "redis"]
    path: Path | None = None
    url: str | None = None


def _redis_spec(url: str, text: str) -> StoreSpec:
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError as error:
        raise ValueError(f"store {url!r}: {error}") from None
    if not parts.hostname:
        raise ValueError(f"store {url!r}: no redis host")
    if port == 0:
        raise ValueError(f"store {url!r}: port 0")
    database = parts.path.removeprefix("/")
    if database and not database.isdigit():
        raise ValueError(f"store {url!r}: the database must be a number, not {database!r}")
    if parts.fragment:
        raise ValueError(f"store {url!r}: unexpected fragment")
    return StoreSpec("redis", url=text)


def parse_store_url(url: str) -> StoreSpec:
    """Parse ``memory``, ``sqlite``, ``sqlite:PATH``, ``sqlite:///ABSOLUTE/PATH``, ``redis``,
    ``redis://[[USER]:PASSWORD@]HOST[:PORT][/DB]`` or ``rediss://…`` (TLS)."""
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
    if text == "redis":
        return StoreSpec("redis", url=DEFAULT_REDIS_URL)
    if any(text.startswith(f"{scheme}://") for scheme in REDIS_SCHEMES):
        return _redis_spec(url, text)
    raise ValueError(f"store {url!r}: {EXPECTED}")


def open_store(
    url: str, redis_prefix: str = DEFAULT_PREFIX, sqlite_synchronous: Synchronous = "FULL"
) -> Store:
    """Open the store named by ``url`` (``redis_prefix``: ``CREDAL_REDIS_PREFIX``;
    ``sqlite_synchronous``: ``CREDAL_SQLITE_SYNCHRONOUS``)."""
    spec = parse_store_url(url)
    if spec.kind == "memory":
        return MemoryStore()
    if spec.kind == "redis":
        assert spec.url is not None
        return RedisStore(spec.url, prefix=redis_prefix)
    assert spec.path is not None
    return SqliteStore(spec.path, sqlite_synchronous)
