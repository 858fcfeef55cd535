"""Tenants: who a request acts for, and so whose quotas it spends.

Two modes (``CREDAL_ACCESS``):

- ``open`` — anyone may create sessions, no key needed: each client address is
  its own tenant (an IPv6 address by its /64 network, which one host holds
  whole). Meant for ``make run`` on loopback.
- ``keys`` — creating a session (and ``POST /v1/associate``) needs an API key,
  ``Authorization: Bearer <key>``: each key is a tenant (``CREDAL_API_KEYS``,
  ``name:key`` pairs separated by commas). Without a valid key: 401.

``auto`` (the default) is ``open`` when the service listens on a loopback
address and ``keys`` otherwise, so a service reachable from a network never
opens itself by accident. The admin token acts as the tenant ``admin``.

A session belongs to the tenant that created it (``SessionRecord.tenant``):
its token opens that session only, and every request and input sent with it
counts against its tenant's rate limit and quotas (:mod:`app.cluster.quotas`),
so minting more sessions never buys more requests. The tenant's live sessions
are capped too (``tenant_max_sessions``, counted by the store at creation).
"""

from __future__ import annotations

import ipaddress
from typing import Literal

Access = Literal["auto", "open", "keys"]
ADMIN_TENANT = "admin"
LOOPBACK_NAMES = frozenset({"localhost", "ip6-localhost"})


def is_loopback(host: str) -> bool:
    """Whether the service's listening ``host`` is a loopback address (or name)."""
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


ADDRESS_TENANT_PREFIX = "address:"


def address_tenant(client: str | None) -> str:
    """The tenant of a client without a key: its address (an IPv6 address by its /64)."""
    if client is None:
        return f"{ADDRESS_TENANT_PREFIX}unknown"
    try:
        address = ipaddress.ip_address(client)
    except ValueError:
        return f"{ADDRESS_TENANT_PREFIX}{client}"
    if isinstance(address, ipaddress.IPv6Address):
        if address.ipv4_mapped is not None:
            return f"{ADDRESS_TENANT_PREFIX}{address.ipv4_mapped}"
        return f"{ADDRESS_TENANT_PREFIX}{ipaddress.ip_network(f'{address}/64', strict=False)}"
    return f"{ADDRESS_TENANT_PREFIX}{address}"


KEY_TENANT_PREFIX = "key:"
"""The tenant of an API key is ``key:<name>``."""


def is_keyed(tenant: str) -> bool:
    """Whether ``tenant`` is an API key's (not a client address's, nor the admin's): keyed
    tenants are served first (:mod:`app.http.front`, :mod:`app.sessions.turns`)."""
    return tenant.startswith(KEY_TENANT_PREFIX)


def is_anonymous(tenant: str) -> bool:
    """Whether ``tenant`` is a client address's (open access, no key): its large bodies wait
    while keyed tenants are served (:mod:`app.http.front`)."""
    return tenant.startswith(ADDRESS_TENANT_PREFIX)


def parse_api_keys(text: str) -> dict[str, str]:
    """``name:key,name:key`` → key → tenant name (``key:<name>``); ``ValueError`` naming what
    is wrong."""
    keys: dict[str, str] = {}
    for part in (piece.strip() for piece in text.split(",")):
        if not part:
            continue
        name, colon, key = part.partition(":")
        if not colon or not name:
            raise ValueError("each API key is 'name:key' (a tenant name, a colon, the key)")
        check_secret(f"the API key of tenant {name!r}", key)
        if key in keys:
            raise ValueError(f"the API key of tenant {name!r} is another tenant's too")
        keys[key] = f"{KEY_TENANT_PREFIX}{name}"
    return keys


MIN_SECRET_LENGTH = 32
"""An admin token or API key opens much: at least 32 characters (``secrets.token_urlsafe(24)``)."""


def check_secret(what: str, value: str) -> None:
    """Refuse a secret that is short or not visible ASCII (``ValueError`` naming ``what``).

    HTTP headers are bytes that servers read as latin-1: a secret with a
    non-ASCII character would never match what a client sends in UTF-8, and a
    space-only secret is no secret."""
    if len(value) < MIN_SECRET_LENGTH:
        raise ValueError(
            f"{what} must have at least {MIN_SECRET_LENGTH} characters (got {len(value)}); "
            "e.g. python -c 'import secrets; print(secrets.token_urlsafe(32))'"
        )
    if not all("!" <= char <= "~" for char in value):
        raise ValueError(
            f"{what} must be visible ASCII characters only (no spaces, no accents): "
            "e.g. python -c 'import secrets; print(secrets.token_urlsafe(32))'"
        )
