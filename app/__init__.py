"""credal-fusion service: FastAPI app, routes, sessions, stores, CLI."""
