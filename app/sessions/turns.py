"""Turns at the engine: the tenants' inputs take the engine steps round-robin.

Every input's engine step (:meth:`~app.sessions.pipeline.InputPipeline.apply`) runs in a turn
(:meth:`Turns.turn`). At most :data:`STEP_SLOTS` steps run at once; inputs that find every slot
taken wait in their tenant's queue (first come, first served within a tenant), and a slot that
frees goes to the next tenant in turn, not to the next input: a tenant with a hundred inputs
waiting and a tenant with one take one step each. A flooding tenant therefore slows itself,
and another tenant's sensor waits for one step of each tenant with work, whatever the flood.

Without contention an input takes its turn at once (nothing queued, a slot free and no other
input in flight). With other inputs in flight it always queues, and the slot is handed out by
a callback scheduled after the tasks already ready on the event loop (``call_soon``): the
inputs whose requests were read in the same turn of the loop reach their queues first, so the
choice is between tenants rather than the loop's first-in-first-out order of requests.

Tenants with an API key come first (:func:`app.tenants.is_keyed`): a free slot goes to the next
keyed tenant in turn while one waits, and to the others (client addresses of open access, the
admin) in turn only when none does. An anonymous crowd, from as many addresses as it likes,
then never has a keyed tenant's input wait for more than the steps already running.

Turns are this process's (each worker of ``serve --workers`` has its own); they order steps,
they refuse nothing (the pipeline's admission does: ``tenant_max_in_flight``, the overload
guard, ``max_queue_ms``).
"""

from __future__ import annotations

import asyncio
from collections import OrderedDict, deque
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from app.tenants import is_keyed

STEP_SLOTS = 2
"""Engine steps at once: a large step in a worker thread and a small one on the event loop
(:mod:`app.sessions.work`); more would only share the GIL between more threads."""


class Turns:
    """Engine steps taken in turns between tenants (module docstring)."""

    def __init__(self, slots: int = STEP_SLOTS) -> None:
        self.free = slots
        self.keyed: OrderedDict[str, deque[asyncio.Future[None]]] = OrderedDict()
        """Keyed tenants with inputs waiting, in the order they are served (the next one
        first): served before :attr:`queues`."""
        self.queues: OrderedDict[str, deque[asyncio.Future[None]]] = OrderedDict()
        """The other tenants with inputs waiting, in the order they are served."""
        self._dispatching = False

    def waiting(self) -> int:
        """Inputs waiting for a turn."""
        return sum(len(queue) for queues in (self.keyed, self.queues) for queue in queues.values())

    def _queues_of(self, tenant: str) -> OrderedDict[str, deque[asyncio.Future[None]]]:
        return self.keyed if is_keyed(tenant) else self.queues

    @asynccontextmanager
    async def turn(self, tenant: str, *, alone: bool = False) -> AsyncIterator[None]:
        """Hold one of the slots for ``tenant``'s step, waiting in its queue if need be;
        ``alone``: no other input is in flight (the slot is taken at once if one is free)."""
        if alone and self.free > 0 and not self.queues and not self.keyed:
            self.free -= 1
        else:
            waiter = asyncio.get_running_loop().create_future()
            self._queues_of(tenant).setdefault(tenant, deque()).append(waiter)
            self._schedule()
            try:
                await waiter
            except BaseException:
                if waiter.done() and not waiter.cancelled():
                    self._release()  # the slot was handed over as it was cancelled
                else:
                    self._forget(tenant, waiter)
                raise
        try:
            yield
        finally:
            self._release()

    def _release(self) -> None:
        self.free += 1
        self._schedule()

    def _schedule(self) -> None:
        """Hand out free slots once the tasks ready now have run (``call_soon``)."""
        if not self._dispatching and self.free > 0 and (self.keyed or self.queues):
            self._dispatching = True
            asyncio.get_running_loop().call_soon(self._dispatch)

    def _dispatch(self) -> None:
        """Give each free slot to the first waiter of the next tenant in turn, keyed first."""
        self._dispatching = False
        while self.free > 0 and (self.keyed or self.queues):
            queues = self.keyed or self.queues
            tenant, queue = next(iter(queues.items()))
            waiter = queue.popleft()
            if queue:
                queues.move_to_end(tenant)  # its next input waits for the other tenants
            else:
                del queues[tenant]
            if not waiter.done():
                self.free -= 1
                waiter.set_result(None)

    def _forget(self, tenant: str, waiter: asyncio.Future[None]) -> None:
        queues = self._queues_of(tenant)
        queue = queues.get(tenant)
        if queue is not None and waiter in queue:
            queue.remove(waiter)
            if not queue:
                del queues[tenant]
