"""Service settings, read from the environment with the ``CREDAL_`` prefix.

Each limit is named after its setting; a breach answers a 4xx whose
``limit`` member is that name (``max_body_bytes`` ↔ ``CREDAL_MAX_BODY_BYTES``).
"""

from __future__ import annotations

from functools import lru_cache

from limits import RateLimitItem, parse_many
from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from api_schemas.base import MAX_CLASSES
from api_schemas.limits import MAX_FOCAL_SETS, MAX_ITEMS, MAX_SENSORS, WireLimits
from app.errors import MAX_LISTED_ERRORS
from app.stores.redis_keys import DEFAULT_PREFIX

DEFAULT_STORE = "sqlite:data/credal-fusion.db"
UNLIMITED = frozenset({"", "none", "off", "0"})
"""``CREDAL_RATE_LIMIT`` values that turn the rate limit off."""
MIN_ADMIN_TOKEN_LENGTH = 32
"""An admin token opens every session: at least 32 characters (``secrets.token_urlsafe(24)``)."""
DEFAULTS = WireLimits()


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
        None,
        description=f"opens every session and the admin routes; at least "
        f"{MIN_ADMIN_TOKEN_LENGTH} characters",
    )
    cors_origins: str = Field(
        "",
        description="browser origins allowed to call the API, comma-separated "
        "('https://a.example,https://b.example', or '*'); empty: CORS off (no CORS headers)",
    )
    body_read_timeout: float = Field(
        10.0,
        gt=0.0,
        description="seconds a client may take to send a request body; slower: 408 "
        "(a client trickling bytes cannot hold a connection and a buffer forever)",
    )
    access_log: bool = Field(
        True,
        description="one log line per request (uvicorn's access log); /metrics counts them too",
    )

    max_body_bytes: int = Field(
        1024 * 1024,
        ge=1024,
        description="a request body or WebSocket message; 1 MiB: parsing one holds the GIL ~10 ms",
    )
    max_tracks_per_input: int = Field(
        DEFAULTS.max_tracks_per_input,
        ge=1,
        le=MAX_ITEMS,
        description="tracks or detections in one input (and per side of /v1/associate)",
    )
    max_sensors: int = Field(DEFAULTS.max_sensors, ge=1, le=MAX_SENSORS)
    max_classes: int = Field(DEFAULTS.max_classes, ge=1, le=MAX_CLASSES)
    max_focal_sets: int = Field(
        DEFAULTS.max_focal_sets,
        ge=1,
        le=MAX_FOCAL_SETS,
        description="focal sets in one class mass of an input",
    )
    max_associate_pairs: int = Field(
        250_000,
        ge=1,
        description="known × incoming pairs of one POST /v1/associate (the score matrix's size)",
    )
    max_associate_class_pairs: int = Field(
        20_000,
        ge=1,
        description="known × incoming pairs of one POST /v1/associate whose tracks carry class "
        "evidence (each pair combines two class masses)",
    )
    max_listed_errors: int = Field(
        MAX_LISTED_ERRORS,
        ge=1,
        description="a 422 lists at most this many errors; 'error_count' says how many there were",
    )
    max_sessions: int = Field(1000, ge=1)
    session_idle_seconds: float = Field(3600.0, ge=0.0, description="0: sessions never expire")
    snapshot_every: int = Field(100, ge=1, description="snapshot the engine every N inputs")
    log_retention: int = Field(
        1000,
        ge=0,
        description="inputs kept in a session's log behind its latest snapshot; older ones are "
        "deleted after each snapshot (GET …/events then starts with that snapshot)",
    )
    ws_messages_per_second: int = Field(
        1000,
        ge=1,
        description="messages one stream connection may send per second; more are answered "
        "with an error (limit-exceeded, status 429) and not applied",
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
        description="requests per verified session token (or client address for any other "
        "request: no token, an unknown token, unauthenticated routes), in the "
        "'limits' notation: '200/second', '50/second;2000/minute'; 'none' turns it off",
    )

    @field_validator("admin_token", mode="before")
    @classmethod
    def _empty_admin_token_is_none(cls, value: object) -> object:
        return None if value == "" else value  # CREDAL_ADMIN_TOKEN= (empty): no admin token

    @field_validator("admin_token")
    @classmethod
    def _admin_token_is_long(cls, value: SecretStr | None) -> SecretStr | None:
        if value is not None and len(value.get_secret_value()) < MIN_ADMIN_TOKEN_LENGTH:
            raise ValueError(
                f"CREDAL_ADMIN_TOKEN must have at least {MIN_ADMIN_TOKEN_LENGTH} characters "
                f"(got {len(value.get_secret_value())}); e.g. "
                "python -c 'import secrets; print(secrets.token_urlsafe(32))'"
            )
        return value

    def wire_limits(self) -> WireLimits:
        """The limits the wire models check before validating a list's items."""
        return WireLimits(
            max_tracks_per_input=self.max_tracks_per_input,
            max_sensors=self.max_sensors,
            max_classes=self.max_classes,
            max_focal_sets=self.max_focal_sets,
        )

    def cors_origin_list(self) -> list[str]:
        """The configured CORS origins (empty: CORS off)."""
        return [origin.strip() for origin in self.cors_origins.split(",") if origin.strip()]

    @field_validator("rate_limit")
    @classmethod
    def _rate_limit_parses(cls, value: str) -> str:
        parse_rates(value)
        return value


def parse_rates(text: str) -> list[RateLimitItem]:
    """The rates of a ``CREDAL_RATE_LIMIT`` value (empty: no limit); ``ValueError`` if malformed."""
    if text.strip().lower() in UNLIMITED:
        return []
    try:
        return list(parse_many(text))
    except ValueError as error:
        raise ValueError(f"rate limit {text!r}: {error}") from None


@lru_cache
def get_settings() -> Settings:
    """The process-wide settings (cached; tests build their own)."""
    return Settings()
