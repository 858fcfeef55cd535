"""Service settings, read from the environment with the ``CREDAL_`` prefix.

Each limit is named after its setting; a breach answers a 4xx whose
``limit`` member is that name (``max_body_bytes`` ↔ ``CREDAL_MAX_BODY_BYTES``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

from limits import RateLimitItem, parse_many
from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from api_schemas.base import MAX_CLASSES
from api_schemas.limits import MAX_FOCAL_SETS, MAX_ITEMS, MAX_SENSORS, WireLimits
from app.cluster.lease import DEFAULT_LEASE_TTL_MS
from app.errors import MAX_LISTED_ERRORS
from app.stores.redis_keys import DEFAULT_PREFIX
from app.tenants import MIN_SECRET_LENGTH, Access, check_secret, is_loopback, parse_api_keys

DEFAULT_STORE = "sqlite:data/credal-fusion.db"
UNLIMITED = frozenset({"", "none", "off", "0"})
"""``CREDAL_RATE_LIMIT`` values that turn the rate limit off."""
DEFAULTS = WireLimits()


@dataclass(frozen=True)
class TransportLimits:
    """The limits the HTTP protocol checks before the application (:mod:`app.http.transport`)."""

    max_header_bytes: int = 16 * 1024
    max_header_count: int = 100
    request_head_timeout: float = 10.0
    max_connections: int = 1000
    max_connections_per_client: int = 64


TRANSPORT = TransportLimits()


class Settings(BaseSettings):
    """Everything the service can be told from outside."""

    model_config = SettingsConfigDict(env_prefix="CREDAL_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = 8000
    store: str = Field(
        DEFAULT_STORE, description="memory | sqlite[:PATH] | redis[s]://HOST:PORT/DB"
    )
    workers: int = Field(
        1,
        ge=0,
        description="worker processes of `serve`, sharing the sessions through the store "
        "(sqlite or redis; the memory store is one process's): 0 is one per usable core",
    )
    sqlite_synchronous: Literal["FULL", "NORMAL"] = Field(
        "FULL",
        description="sqlite store: FULL fsyncs each commit (an acknowledged input survives a "
        "power loss); NORMAL does not (it survives the process's death, SIGKILL included, "
        "not the machine's) and costs less CPU per input",
    )
    redis_prefix: str = Field(
        DEFAULT_PREFIX, min_length=1, description="start of every Redis key and channel name"
    )
    admin_token: SecretStr | None = Field(
        None,
        description=f"opens every session and the admin routes; at least "
        f"{MIN_SECRET_LENGTH} visible ASCII characters",
    )
    access: Access = Field(
        "auto",
        description="who may create sessions: 'open' (anyone; each client address is a tenant), "
        "'keys' (an API key of CREDAL_API_KEYS), 'auto': open on a loopback host, keys otherwise",
    )
    api_keys: SecretStr | None = Field(
        None,
        description="the tenants' API keys, 'name:key,name:key' (each key at least "
        f"{MIN_SECRET_LENGTH} visible ASCII characters)",
    )
    tenant_max_sessions: int = Field(
        100, ge=1, description="live sessions of one tenant (429 beyond, with Retry-After)"
    )
    tenant_inputs_per_second: int = Field(
        500, ge=1, description="inputs (REST and WebSocket) of one tenant's sessions per second"
    )
    tenant_body_bytes_per_second: int = Field(
        2 * 1024 * 1024,
        ge=1024,
        description="request body bytes of one tenant per second (a body counts its "
        "Content-Length; parsing 1 MiB costs ~50 ms of CPU)",
    )
    tenant_work_per_minute: int = Field(
        10_000_000,
        ge=1,
        description="work units of one tenant's inputs per minute (an input's units: its items × "
        "(the session's live fused tracks + 1))",
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
    max_header_bytes: int = Field(
        TRANSPORT.max_header_bytes,
        ge=1024,
        description="request line and headers of one request; more: 431 and the connection closed",
    )
    max_header_count: int = Field(
        TRANSPORT.max_header_count, ge=8, description="header lines of one request (431)"
    )
    request_head_timeout: float = Field(
        TRANSPORT.request_head_timeout,
        gt=0.0,
        description="seconds from a connection (or a request's first byte) to the end of its "
        "headers; slower: 408 and the connection closed (slowloris)",
    )
    keep_alive_timeout: float = Field(
        5.0, gt=0.0, description="seconds an idle keep-alive connection stays open"
    )
    max_connections: int = Field(
        TRANSPORT.max_connections,
        ge=1,
        description="open connections in all; at the limit a new one closes the oldest "
        "connection still waiting for a request head, or gets 503 if none is",
    )
    max_connections_per_client: int = Field(
        TRANSPORT.max_connections_per_client,
        ge=1,
        description="open connections (HTTP and WebSocket) of one client address; one more: 429",
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
    max_input_work: int = Field(
        1_000_000,
        ge=1,
        description="work units of one input: its tracks or detections × (the tracks they may be "
        "compared with + 1), i.e. the session's live fused tracks (and, for detections, the "
        "sensor's local tracks); 2 000 tracks on a session of 499: ~1 s of CPU",
    )
    max_explain_cells: int = Field(
        250_000,
        ge=1,
        description="cells of the score matrix ?explain=true adds: (known tracks + reported "
        "tracks) × reported tracks (one cell is ~20 bytes of JSON)",
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
    overload_delay_ms: float = Field(
        200.0,
        ge=0.0,
        description="refuse new inputs (503 overloaded with Retry-After, a stream's error) while "
        "the event loop runs later than this on average (app.runtime.LoopLag.smoothed), so "
        "the inputs accepted are answered in time instead of every session falling behind; "
        "0: never refuse",
    )
    max_queue_ms: float = Field(
        500.0,
        ge=0.0,
        description="refuse an input (503 overloaded with Retry-After, a stream's error) that "
        "has waited longer than this since its last byte was read (for the event loop, its "
        "session's lock, its tenant's turn) when its engine step would start: before it is "
        "applied or logged, rather than answering it late; an input during whose wait no other "
        "input's step started is not refused; 0: never refuse",
    )
    tenant_max_in_flight: int = Field(
        256,
        ge=1,
        description="inputs of one tenant in flight on one instance (admitted, not yet "
        "answered: waiting for their turn or being applied); one more: 429 with Retry-After. "
        "The tenants' steps are taken round-robin (app.sessions.turns)",
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
        DEFAULT_LEASE_TTL_MS,
        ge=100,
        description="redis store or several workers: an instance that stops renewing a session's lease loses it "
        "after this long, and another instance takes the session over (a stream renews it "
        "every third of it)",
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
    def _admin_token_is_a_secret(cls, value: SecretStr | None) -> SecretStr | None:
        if value is not None:
            check_secret("CREDAL_ADMIN_TOKEN", value.get_secret_value())
        return value

    @field_validator("api_keys", mode="before")
    @classmethod
    def _empty_api_keys_is_none(cls, value: object) -> object:
        return None if value == "" else value

    @field_validator("api_keys")
    @classmethod
    def _api_keys_parse(cls, value: SecretStr | None) -> SecretStr | None:
        if value is not None:
            parse_api_keys(value.get_secret_value())
        return value

    def open_access(self) -> bool:
        """Whether anyone may create sessions (``access``; ``auto``: on a loopback host)."""
        return self.access == "open" or (self.access == "auto" and is_loopback(self.host))

    def transport_limits(self) -> TransportLimits:
        """The limits the HTTP protocol checks before the application (:mod:`app.http.transport`)."""
        return TransportLimits(
            max_header_bytes=self.max_header_bytes,
            max_header_count=self.max_header_count,
            request_head_timeout=self.request_head_timeout,
            max_connections=self.max_connections,
            max_connections_per_client=self.max_connections_per_client,
        )

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
