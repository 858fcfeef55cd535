"""Service settings, read from the environment with the ``CREDAL_`` prefix.

Each limit is named after its setting; a breach answers a 4xx whose
``limit`` member is that name (``max_body_bytes`` ↔ ``CREDAL_MAX_BODY_BYTES``).
"""

from __future__ import annotations

from functools import lru_cache

from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from api_schemas.base import MAX_CLASSES
from app.rate_limit import parse_rates
from app.stores.redis_keys import DEFAULT_PREFIX

DEFAULT_STORE = "sqlite:data/credal-fusion.db"


class Settings(BaseSettings):
    """Everything the service can be told from outside."""

    model_config = SettingsConfigDict(env_prefix="CREDAL_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = 8000
    store: str = Field(
        DEFAULT_STORE, description="memory | sqlite[:PATH] | redis[s]://HOST:PORT/DB"
    )
    redis_prefix: str = Field(
        DEFAULT_PREFIX, min_length=1, description="start of every Redis key and channel name"
    )
    admin_token: SecretStr | None = Field(
        None, description="opens every session and the admin routes"
    )
    access_log: bool = Field(
        True,
        description="one log line per request (uvicorn's access log); /metrics counts them too",
    )

    max_body_bytes: int = Field(4 * 1024 * 1024, ge=1024)
    max_tracks_per_input: int = Field(2000, ge=1, description="tracks or detections in one input")
    max_sensors: int = Field(64, ge=1)
    max_classes: int = Field(MAX_CLASSES, ge=1, le=MAX_CLASSES)
    max_sessions: int = Field(1000, ge=1)
    session_idle_seconds: float = Field(3600.0, ge=0.0, description="0: sessions never expire")
    snapshot_every: int = Field(100, ge=1, description="snapshot the engine every N inputs")
    log_retention: int = Field(
        1000,
        ge=0,
        description="inputs kept in a session's log behind its latest snapshot; older ones are "
        "deleted after each snapshot (GET …/events then starts with that snapshot)",
    )
    ws_ping_interval: float = Field(20.0, gt=0.0, description="seconds between WebSocket pings")
    ws_ping_timeout: float = Field(20.0, gt=0.0, description="a peer silent this long is dropped")
    lease_ttl_ms: int = Field(
        10_000,
        ge=100,
        description="redis store: an instance that stops renewing a session's lease loses it "
        "after this long, and another instance takes the session over",
    )
    rate_limit: str = Field(
        "1000/second",
        description="requests per bearer token (or client address without one), in the "
        "'limits' notation: '200/second', '50/second;2000/minute'; 'none' turns it off",
    )

    @field_validator("rate_limit")
    @classmethod
    def _rate_limit_parses(cls, value: str) -> str:
        parse_rates(value)
        return value


@lru_cache
def get_settings() -> Settings:
    """The process-wide settings (cached; tests build their own)."""
    return Settings()
