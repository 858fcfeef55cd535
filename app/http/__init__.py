"""The HTTP and WebSocket edge: dependencies, problems, request limits, security, middleware."""
