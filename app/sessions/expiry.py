"""Idle sessions end: a session without input for ``session_idle_seconds`` is deleted.

With a shared store a session another instance moved on is not idle here.
"""

from __future__ import annotations

import logging
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING

import anyio

from app.errors import SessionNotFound

if TYPE_CHECKING:
    from app.sessions.registry import SessionRegistry

logger = logging.getLogger("credal_fusion.sessions")


class SessionExpiry:
    """Ends the registry's idle sessions (:meth:`run` until cancelled)."""

    def __init__(self, registry: SessionRegistry) -> None:
        self.registry = registry

    async def expire_idle(self, now: datetime | None = None) -> list[str]:
        """End every session idle for longer than ``session_idle_seconds`` (0: never)."""
        idle = self.registry.settings.session_idle_seconds
        if idle <= 0:
            return []
        moment = now or datetime.now(UTC)
        expired = [
            session.id
            for session in self.registry
            if moment - session.idle_since() > timedelta(seconds=idle) and not session.lock.locked()
        ]
        if self.registry.shared:
            expired = [sid for sid in expired if not await self._active_elsewhere(sid, moment)]
        for session_id in expired:
            logger.info("session %s expired after %.0f s without input", session_id, idle)
            await self.registry.delete(session_id)
        return expired

    async def _active_elsewhere(self, session_id: str, now: datetime) -> bool:
        """Whether another instance moved the session's log on (then it is not idle)."""
        session = self.registry.loaded(session_id)
        try:
            last = await self.registry.io(self.registry.store.last_seq, session_id)
        except SessionNotFound:
            self.registry.discard(session_id)
            return True
        if session is not None and last != session.seq:
            session.last_input_at = now  # it will be rebuilt when this instance next applies
            return True
        return False

    async def run(self) -> None:
        """Check idle sessions periodically until cancelled."""
        idle = self.registry.settings.session_idle_seconds
        if idle <= 0:
            return
        period = min(60.0, max(1.0, idle / 10.0))
        while True:
            await anyio.sleep(period)
            try:
                await self.expire_idle()
            except Exception:
                logger.exception("idle expiry failed")
