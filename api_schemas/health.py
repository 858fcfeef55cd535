"""Liveness answer."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel


class Health(BaseModel):
    """``GET /healthz``: the service is up."""

    status: Literal["ok"] = "ok"
    version: str
