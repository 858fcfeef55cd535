"""The wire contract: pydantic v2 models of every request, response and message.

Modules: ``config`` (session configuration), ``reports`` (sensor inputs),
``results`` (fused output), ``sessions``, ``associate``, ``events``, ``ws``
(WebSocket messages), ``problem`` (RFC 9457 errors), ``consistency`` (input
against session config). No algorithms; never imports ``app``.
"""
