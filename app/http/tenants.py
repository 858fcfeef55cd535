"""The tenants of one service at its edge: who a request's key or address acts for.

:mod:`app.tenants` has the rules (modes, address tenants, key syntax);
:class:`Tenancy` applies them to a request's ``Authorization`` header, with the
keys kept hashed.
"""

from __future__ import annotations

import hmac

from app.errors import Unauthorized
from app.http.security import hash_token
from app.settings import Settings
from app.tenants import ADMIN_TENANT, address_tenant, parse_api_keys


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


def tenancy_of(settings: Settings) -> Tenancy:
    """The service's tenants under ``settings`` (``access``, ``api_keys``, ``admin_token``)."""
    keys = {} if settings.api_keys is None else parse_api_keys(settings.api_keys.get_secret_value())
    admin = settings.admin_token
    return Tenancy(
        settings.open_access(),
        {hash_token(key): tenant for key, tenant in keys.items()},
        None if admin is None else hash_token(admin.get_secret_value()),
    )
