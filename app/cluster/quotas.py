"""Tenant quotas on inputs: how many per second, and how much work per minute.

Every input (REST or WebSocket) is charged to its session's tenant
(:mod:`app.http.tenants`) before it is applied: one input against
``tenant_inputs_per_second``, and its work units (:func:`input_work`) against
``tenant_work_per_minute``. Over either, it is refused with 429 and
``Retry-After`` and nothing is applied. The tenant's live sessions are the
third quota, counted by the store when a session is created
(``tenant_max_sessions``).

The counters are the ``limits`` library's sliding-window counters, kept where
the sessions are: in Redis for the redis store (every instance charges the
same counters, under ``P:quota``), in this process's memory otherwise (one
process serves the store). A Redis that cannot be reached makes the charge
raise :class:`~app.errors.StoreUnavailable` (503): the input could not be
logged either.
"""

from __future__ import annotations

import math
import time
from http import HTTPStatus

import redis
from limits import RateLimitItem, RateLimitItemPerMinute, RateLimitItemPerSecond
from limits.aio.storage import MemoryStorage, RedisStorage, Storage
from limits.aio.strategies import SlidingWindowCounterRateLimiter

from app.cluster import shared_redis
from app.errors import LimitExceeded, StoreUnavailable
from app.stores.base import Store
from app.stores.redis import CONNECT_TIMEOUT_S, SOCKET_TIMEOUT_S

BROKEN = (redis.ConnectionError, ConnectionError)
"""A connection that broke (Redis restarted): tried once more on a fresh one."""
UNREACHABLE = (*BROKEN, redis.TimeoutError, TimeoutError, OSError)


def input_work(items: int, live_tracks: int) -> int:
    """An input's work units: the (reported item, live fused track) pairs its association may
    score, plus one per item (gating, update, initiation): ``items × (live_tracks + 1)``."""
    return items * (live_tracks + 1)


class TenantQuotas:
    """The input quotas of every tenant (see the module's text)."""

    def __init__(self, storage: Storage, inputs_per_second: int, work_per_minute: int) -> None:
        self.limiter = SlidingWindowCounterRateLimiter(storage)
        self.inputs = RateLimitItemPerSecond(inputs_per_second)
        self.work = RateLimitItemPerMinute(work_per_minute)

    async def charge(self, tenant: str, work: int) -> None:
        """Count one input of ``work`` units for ``tenant``, or refuse it (429, nothing counted
        against the quota it breaks). A connection that broke (Redis restarted) is tried once
        more on a fresh one, then the store is unavailable (503)."""
        for attempt in range(2):
            try:
                await self._charge(tenant, work)
                return
            except UNREACHABLE as error:
                if attempt or not isinstance(error, BROKEN):  # a timeout: frozen, not retried
                    reason = f"{type(error).__name__}: {error}"[:200]
                    raise StoreUnavailable("redis", reason) from error

    async def _charge(self, tenant: str, work: int) -> None:
        if not await self.limiter.hit(self.inputs, "inputs", tenant):
            raise await self._refusal(
                self.inputs, "inputs", tenant, "tenant_inputs_per_second", 1, "inputs"
            )
        if not await self.limiter.hit(self.work, "work", tenant, cost=work):
            raise await self._refusal(
                self.work, "work", tenant, "tenant_work_per_minute", work, "work units"
            )

    async def _refusal(
        self, item: RateLimitItem, kind: str, tenant: str, limit: str, cost: int, what: str
    ) -> LimitExceeded:
        reset = (await self.limiter.get_window_stats(item, kind, tenant)).reset_time
        return LimitExceeded(
            limit,
            item.amount,
            cost,
            what=f"{what} of this tenant per {item.GRANULARITY.name} (this input: {cost})",
            status=HTTPStatus.TOO_MANY_REQUESTS,
            retry_after_s=max(1, math.ceil(reset - time.time())),
        )


def open_quotas(store: Store, inputs_per_second: int, work_per_minute: int) -> TenantQuotas:
    """The quotas that go with ``store``: counted in its Redis when shared, else in memory."""
    backing = shared_redis(store)
    storage: Storage
    if backing is not None:
        scheme, _, rest = backing.url.partition("://")
        storage = RedisStorage(
            f"async+{scheme}://{rest}",
            implementation="redispy",
            key_prefix=backing.keys.quotas(),
            wrap_exceptions=False,
            socket_timeout=SOCKET_TIMEOUT_S,
            socket_connect_timeout=CONNECT_TIMEOUT_S,
        )
    else:
        storage = MemoryStorage()
    return TenantQuotas(storage, inputs_per_second, work_per_minute)
