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

import hmac
import ipaddress
from typing import Literal

from app.http.errors import Unauthorized
from app.http.security import hash_token

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


def address_tenant(client: str | None) -> str:
    """The tenant of a client without a key: its address (an IPv6 address by its /64)."""
    if client is None:
        return "address:unknown"
    try:
        address = ipaddress.ip_address(client)
    except ValueError:
        return f"address:{client}"
    if isinstance(address, ipaddress.IPv6Address):
        if address.ipv4_mapped is not None:
            return f"address:{address.ipv4_mapped}"
        return f"address:{ipaddress.ip_network(f'{address}/64', strict=False)}"
    return f"address:{address}"


def parse_api_keys(text: str) -> dict[str, str]:
    """``name:key,name:key`` → key hash → tenant name (``ValueError`` naming what is wrong)."""
    keys: dict[str, str] = {}
    for part in (piece.strip() for piece in text.split(",")):
        if not part:
            continue
        name, colon, key = part.partition(":")
        if not colon or not name:
            raise ValueError("each API key is 'name:key' (a tenant name, a colon, the key)")
        check_secret(f"the API key of tenant {name!r}", key)
        hashed = hash_token(key)
        if hashed in keys:
            raise ValueError(f"the API key of tenant {name!r} is another tenant's too")
        keys[hashed] = f"key:{name}"
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


class Tenancy:
    """The tenants of one service: its mode, its API keys, its admin token."""

    def __init__(self, open_access: bool, api_keys: dict[str, str], admin_hash: str | None) -> None:
        self.open = open_access
        self.api_keys = api_keys
        self.admin_hash = admin_hash

    def of_key(self, token: str) -> str | None:
        """The tenant whose API key (or the admin token) ``token`` is, if any."""
        return self.of_hash(hash_token(token))

    def of_hash(self, hashed: str) -> str | None:
        """:meth:`of_key` of a token's hash."""
        if self.admin_hash is not None and hmac.compare_digest(hashed, self.admin_hash):
            return ADMIN_TENANT
        return self.api_keys.get(hashed)

    def creator(self, authorization: str | None, client: str | None) -> str:
        """The tenant a session-creating (or other costly unauthenticated) request acts for:
        its API key's; in open mode without one, its address's (another bearer token, such
        as a session's, is no key and changes nothing); in keys mode, 401 without a key."""
        scheme, _, token = (authorization or "").partition(" ")
        token = token.strip()
        tenant = self.of_key(token) if scheme.lower() == "bearer" and token else None
        if tenant is not None:
            return tenant
        if self.open:
            return address_tenant(client)
        if token:
            raise Unauthorized("this bearer token is not an API key of this service")
        raise Unauthorized(
            "this service needs an API key: send 'Authorization: Bearer <key>' "
            "(ask its operator; keys are set with CREDAL_API_KEYS)"
        )
