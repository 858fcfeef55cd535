"""Session stores: the protocol and its ``memory``, ``sqlite`` and ``redis`` implementations."""

from app.stores.base import (
    LogEntry,
    SequenceConflict,
    SessionExists,
    SessionLoad,
    SessionRecord,
    Snapshot,
    Store,
    to_plain,
)
from app.stores.memory import MemoryStore
from app.stores.redis import RedisStore
from app.stores.sqlite import SqliteStore
from app.stores.url import StoreSpec, open_store, parse_store_url

__all__ = [
    "LogEntry",
    "MemoryStore",
    "RedisStore",
    "SequenceConflict",
    "SessionExists",
    "SessionLoad",
    "SessionRecord",
    "Snapshot",
    "SqliteStore",
    "Store",
    "StoreSpec",
    "open_store",
    "parse_store_url",
    "to_plain",
]
