"""Liveness and readiness answers."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field


class Health(BaseModel):
    """``GET /healthz``: the service is up."""

    status: Literal["ok"] = "ok"
    version: str


class ComponentState(BaseModel):
    """One thing the service needs to take inputs, and whether it answers now."""

    name: Literal["store", "fanout"]
    ready: bool
    detail: str | None = None


class Readiness(BaseModel):
    """``GET /readyz``: whether the service can take inputs now (the store answers).

    ``leases_held`` counts the sessions whose lease this instance holds (redis
    store: it applies their inputs); 0 for the single-process stores. A damaged
    store is not ready (its component says why); quarantined sessions alone do
    not make the service unready.
    """

    ready: bool
    store: str
    components: list[ComponentState]
    leases_held: int
    quarantined: list[str] = Field(
        default_factory=list,
        description="sessions the store holds but cannot read (corrupt data): set aside, "
        "answered 500 session-unreadable; every other session is served",
    )
